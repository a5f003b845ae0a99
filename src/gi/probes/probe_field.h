// The light-field probe grid of the `probes` technique (McGuire et al. 2017 as seed 004 §4 used it;
// ALGORITHMS.md §6; docs/techniques/probes.md): probes on a regular grid over the scene, each with
// an octahedral irradiance map and an octahedral filtered-distance map (mean, mean²), updated by
// tracing rays from the probes through the reference BVH (DDGI style, Majercik et al. 2019) and
// read per camera pixel with trilinear, backface and Chebyshev weights (kernels/gi/probes/).
//
//   ProbeField field(ctx, scene, deviceScene, settings);
//   field.update(deviceScene, 0.97f);   // one update: rays, blend with hysteresis, borders
//   field.shade(gbuffer, indirect);     // ρ/π · E per pixel
//
// Probes inside geometry are moved out or switched off (DDGI relocation and classification).
// Not handled: glossy indirect light (the paper's probe ray marching), moving geometry (the
// BVH is built once; lights may move).
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "cl/runtime.h"
#include "gi/filters/discontinuity_filter.h"
#include "kernels/gi/probes/probe_types.h"
#include "raster/gbuffer.h"
#include "reference/bvh.h"
#include "scene/device_scene.h"
#include "scene/scene.h"

namespace gi {

struct ProbeSettings {
  glm::ivec3 counts{0};          // probes per axis; 0 = automatic (autoProbeCounts)
  int irradianceRes = 8;         // interior texels per side of an irradiance map
  int distanceRes = 16;          // ... of a distance map
  int rays = 64;                 // rays per probe per update
  int updateBudget = 0;          // probes per update, round-robin (probes.update_budget); 0 or ≥ the probe count: all
  int distanceExponentLog2 = 6;  // distance filter weight max(0, cos)^(2^this)
  int chebyshevPower = 3;
  bool smoothBackface = true;    // DDGI's smooth backface weight ((n·ω + 1)/2)² + 0.2; false: seed 004's eq. 7
  float backfaceFloor = 0.05f;    // eq. 7: smallest backface weight
  float crushThreshold = 0.2f;   // DDGI's crush of small backface × visibility weights; 0 = off
  bool perceptualBlend = false;  // blend the probes' irradiance as √E (DDGI)
  bool multiBounce = true;       // ray hits also gather the probes' previous irradiance
  float normalBias = 0.045f;     // fractions of the smallest probe spacing
  float viewBias = 0.18f;
  float maxDistance = 0.0f;      // metres; 0 = the scene's bounding-box diagonal
  bool relocate = true;          // DDGI relocation and classification of probes inside geometry
  float backfaceFraction = 0.25f;  // a probe with more of its rays on back faces is inside geometry
  float minFrontface = 0.1f;     // relocated probes keep this distance to surfaces (fraction of the smallest spacing)
  int downsample = 1;            // shade at 1/downsample resolution, then upsample geometry-aware
  float tauZ = 0.05f, tauNDegrees = 25.0f;  // the upsampler's depth and normal tolerances
};

// The seed's Sponza layout generalised: 8 probes along the two longest axes of the scene bounds,
// 4 along the shortest (8×8×4 = 256 for Sponza).
glm::ivec3 autoProbeCounts(const Bounds& bounds);

// Probes at the centres of a counts.x × counts.y × counts.z cell partition of the bounds (so none
// lies on the bounding walls). Throws gi::Error for counts outside 1 … 64 or bad map sizes.
GiProbeGrid fitProbeGrid(const Bounds& bounds, const ProbeSettings& settings);

// Host mirrors of the kernels' octahedral mapping (seed 004 Algorithms 1 and 2), for tests.
glm::vec2 probeOctEncode(const glm::vec3& unitDirection);
glm::vec3 probeOctDecode(const glm::vec2& octahedral);
glm::vec3 probeTexelDirection(int tx, int ty, int res);

// The unit ray directions of update number `update`: a spherical Fibonacci set of `rays` points,
// rotated by a pseudo-random rotation drawn from the update number (deterministic).
std::vector<glm::vec4> probeRayDirections(int rays, uint32_t update);

// The launch of probes first … first + count − 1 in index order, all with one hysteresis (an
// update without a budget is probeIndexRange(0, N, h)); for kernel tests and relocation batches.
GiProbeUpdate probeIndexRange(int first, int count, float hysteresis = 0.0f);

class ProbeField {
public:
  ProbeField(cl::Context& ctx, const Scene& scene, const DeviceScene& deviceScene, const ProbeSettings& settings);

  // One update of probesPerUpdate() probes: trace grid.rays rays per probe, blend into the maps
  // with weight min(maxHysteresis, k/(k+1)) for the old value at the probe's update k (k = 0
  // first, or at the last restartMean(): the running mean over the probe's updates since, then an
  // exponential average), copy the borders. With a budget (settings.updateBudget < the probe
  // count) update u takes the next budget probes of a fixed round-robin order that spreads them
  // over the grid (probeOrderStride(); docs/techniques/probes.md says why this order); the other
  // probes keep their maps and states.
  // With relocation on, the update's rays also classify its probes and, when moveProbes, move
  // them (kernels/gi/probes/probes.cl, probe_relocate).
  void update(const DeviceScene& deviceScene, float maxHysteresis, bool moveProbes = true);
  // Relocation alone: `passes` times, trace distances only and move every probe (before the first
  // update, so that the maps are built at the final positions; in batches of the budget, which
  // gives the same result since a probe's relocation reads only its own rays). Nothing when
  // relocation is off.
  void relocate(const DeviceScene& deviceScene, int passes);
  // Each probe's next update replaces its maps and starts a new running mean (its rays already see
  // the field so far: with multi-bounce, more bounces than the updates before).
  void restartMean() { meanStartProbeUpdates_ = probeUpdates_; }
  void shade(const GBuffer& gbuffer, cl::Buffer& indirect);

  const GiProbeGrid& grid() const { return grid_; }
  int probeCount() const { return grid_.count[0] * grid_.count[1] * grid_.count[2]; }
  uint32_t updates() const { return updates_; }  // update() calls so far
  // Probes one update() takes: the budget, or every probe (budget 0 or at least the probe count).
  int probesPerUpdate() const { return probesPerUpdate_; }
  // The order the updates go through the probes: position i is probe (i · stride) mod N; update u
  // takes positions u · probesPerUpdate() … (u + 1) · probesPerUpdate() − 1 mod N. 1 without a
  // budget; with one, the stride spreads each update's probes over the grid.
  int probeOrderStride() const { return probeOrderStride_; }
  const cl::Buffer& irradiance() const { return irradiance_; }  // float4 per texel, layout probe_types.h
  // The maps the shading and the probe rays read: irradiance(), or its square roots (√E per texel)
  // with perceptual blending.
  const cl::Buffer& irradianceLookup() const { return perceptualBlend_ ? irradianceSqrt_ : irradiance_; }
  // The probe program's build defines (kernels/gi/probes/probe_field.h's switches): a test program
  // that calls probe_field_irradiance() builds with the same.
  const cl::Defines& programDefines() const { return defines_; }
  const cl::Buffer& distance() const { return distance_; }      // float2 per texel
  const cl::Buffer& states() const { return states_; }          // float4 per probe: offset, active
  uint64_t mapBytes() const { return irradiance_.bytes() + irradianceSqrt_.bytes() + distance_.bytes(); }
  uint64_t rayBytes() const { return rayResults_.bytes() + rayDirs_.bytes(); }
  uint64_t bvhBytes() const { return bvh_->bytes(); }

private:
  cl::Context& ctx_;
  GiProbeGrid grid_;
  bool multiBounce_, perceptualBlend_;
  cl::Defines defines_;
  int downsample_;
  int vectorWidth_;  // GI_VW of the probe program: pixels or texels per work-item
  GeometryTest upsampleTest_;
  std::unique_ptr<DeviceBvh> bvh_;
  std::unique_ptr<GeometryAwareUpsampler> upsampler_;
  cl::Program program_;
  cl::Kernel trace_, relocate_, blendIrradiance_, blendDistance_, borderIrradiance_, borderDistance_, encodeSqrt_,
      shade_;
  // irradianceSqrt_: √E of irradiance_, what the shading and the probe rays read with
  // perceptual blending (else unused: they read irradiance_).
  cl::Buffer irradiance_, irradianceSqrt_, distance_, states_, rayDirs_, rayResults_, instanceEmits_, low_;
  bool relocation_;
  float backfaceFraction_, minFrontface_;  // minFrontface_ in metres
  int probesPerUpdate_;
  int probeOrderStride_;  // the round-robin order: position i is probe (i · stride) mod N (GiProbeUpdate)
  void trace(const DeviceScene& deviceScene, bool shadeHits, const GiProbeUpdate& slots);
  void relocateFromRays(bool moveProbes, const GiProbeUpdate& slots);
  GiProbeUpdate nextUpdateSlots(float maxHysteresis) const;
  uint32_t updates_ = 0, relocationPasses_ = 0;
  // Probe updates so far (update() adds probesPerUpdate()), and their number at the last
  // restartMean(): probe p's updates are those at positions p, p + N, p + 2N, … of this count.
  uint64_t probeUpdates_ = 0, meanStartProbeUpdates_ = 0;
};

}  // namespace gi
