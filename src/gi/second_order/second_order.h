// `second-order`: Cochran & Steele's second-order illumination (seed 002; ALGORITHMS.md §2.6;
// docs/techniques/second-order.md; kernels/gi/second_order/second_order.cl): Halton-placed
// indirect lights looked up in each light's RSM, negative lights from the back-side illumination
// of visible surfaces, L = ρ/π·max(0, E_s − E_n), multi-resolution shading with full-resolution
// re-shading of the pixels whose normal or depth differ from their half-resolution parent.
//
// This header also holds the host mirrors of the light placement that the tests compare with.
#pragma once
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "gi/filters/discontinuity_filter.h"
#include "gi/technique.h"
#include "gi/vpl/vpl_lights.h"
#include "gi/vpl/vpl_visibility.h"

namespace gi {

TechniqueInfo secondOrderTechniqueInfo();

class SecondOrderTechnique : public Technique {
public:
  std::string name() const override { return "second-order"; }
  bool needsRsm() const override { return true; }
  void setup(const FrameResources& frame) override;
  void render(const FrameResources& frame, cl::Buffer& indirect) override;
  std::vector<TechniqueStatistic> statistics(cl::Context& ctx) const override;

  // What the last frame computed, for the tests: the lights (N per light, then M negative ones,
  // kernels/gi/vpl layout), counters (re-shaded pixels, surface pixels, negative lights found),
  // the picked negative-light pixels and the per-pixel flags (bit 0 re-shade, bit 1 surface).
  const VplSet& lights() const { return lights_; }
  const cl::Buffer& counters() const { return counters_; }
  const cl::Buffer& negativePixels() const { return picked_; }
  const cl::Buffer& flags() const { return flags_; }

private:
  struct Samples {
    cl::Buffer buffer;
    int count = 0;  // -1: regenerate next frame
    bool orthographic = false;
    float cosAccept = 2.0f;
  };
  cl::Program program_;
  cl::Kernel place_, flag_, rowCounts_, scanRows_, pickNegative_, negative_, shadeLow_, compact_, refine_;
  cl::Program visibleProgram_;  // so_shade_low and so_refine with visibility rays, built when first asked for
  cl::Kernel visibleShadeLow_, visibleRefine_;
  void buildVisibilityKernels(cl::Context& ctx);
  VplVisibility visibility_;
  std::unique_ptr<GeometryAwareUpsampler> upsampler_;
  std::unique_ptr<VplGenerator> fluxGenerator_;
  VplSet lights_, fluxLights_;
  std::vector<Samples> samples_;
  cl::Buffer counters_, flags_, rowCountsBuf_, rowOffsets_, list_, planes_, candidates_, picked_, lowIrradiance_;
  int width_ = 0, height_ = 0, lowW_ = 0, lowH_ = 0, candidatesFor_ = -1, candidateCount_ = 0;
  int frame_ = 0;  // seeds the random placement
  int negativeAsked_ = 0;  // M of the last frame (counters[2] is only written when M > 0)
};

// Halton points on the unit sphere (the paper's §3.1: φ = 2π·Φ₂(i), sin δ = 2·Φ₃(i) − 1,
// s = (sin φ cos δ, cos φ cos δ, sin δ), i = 1, 2, …) in the light's frame (z = axis): the first
// `count` with z ≥ cosAccept, as float4 (x, y, z, 0). Throws gi::Error when the cone is so narrow
// that 2^22 candidates do not hold `count` of them.
std::vector<glm::vec4> haltonConeDirections(float cosAccept, int count);

// Directional lights: Halton (2, 3) points (u, v) in [0, 1)² over the orthographic RSM, i = 1 … count.
std::vector<glm::vec4> haltonSquarePoints(int count);

// The cone the indirect lights are placed in: the spot's outer cone, capped by the RSM's field of
// view (inscribed cone); point lights: the RSM's field of view. Directional lights: not a cone.
float acceptedConeCos(const GiLight& light, const GiView& rsmView);

// Solid angle of the cone z ≥ cosAccept: 2π(1 − cosAccept).
inline float coneSolidAngle(float cosAccept) { return 6.28318530718f * (1.0f - cosAccept); }

// Host mirror of so_place_indirect for one light: the RSM texel each sample lands in, the flux
// scaled to the share of the light's power the sample stands for (weight: Ω_accept/N for a
// perspective RSM, res²/N for an orthographic one), d_min as the VPL generator.
std::vector<HostVpl> hostPlaceIndirectLights(const GiView& rsmView, const std::vector<glm::vec4>& samples, float weight,
                                             const std::vector<glm::vec4>& position, const std::vector<glm::vec4>& normal,
                                             const std::vector<glm::vec4>& flux, float dminOverride);

// Host mirror of so_negative_lights for one picked pixel: position x, geometric normal n, view
// depth z, camera view; `surfacePixels` / `found` is the sample weight.
HostVpl hostNegativeLight(const std::vector<HostVpl>& positive, glm::vec3 x, glm::vec3 n, float z, const GiView& camera,
                          int surfacePixels, int found, float dminOverride);

// Screen pixels along the 2D Halton sequence (bases 2, 3; i = 1 … count), row-major indices.
std::vector<int> haltonScreenPixels(int width, int height, int count);

}  // namespace gi
