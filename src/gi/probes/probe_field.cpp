// Host side of the probe grid (kernels/gi/probes/probes.cl documents what each kernel computes).
#include "gi/probes/probe_field.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>

#include <glm/gtc/quaternion.hpp>

#include "cl/gather_width.h"
#include "gi/emitter_flags.h"
#include "util/error.h"

namespace gi {

glm::ivec3 autoProbeCounts(const Bounds& bounds) {
  glm::vec3 e = bounds.valid() ? bounds.extent() : glm::vec3(1.0f);
  int shortest = 0;
  for (int a = 1; a < 3; ++a)
    if (e[a] < e[shortest]) shortest = a;
  glm::ivec3 c(8);
  c[shortest] = 4;
  return c;
}

GiProbeGrid fitProbeGrid(const Bounds& bounds, const ProbeSettings& s) {
  glm::ivec3 counts = s.counts;
  glm::ivec3 automatic = autoProbeCounts(bounds);
  const char* axis[3] = {"probes.grid_x", "probes.grid_y", "probes.grid_z"};
  for (int a = 0; a < 3; ++a) {
    if (counts[a] == 0) counts[a] = automatic[a];
    if (counts[a] < 1 || counts[a] > 64)
      throw Error(std::string(axis[a]) + " = " + std::to_string(counts[a]) + ": probes per axis must be 1 … 64 (0 = automatic)");
  }
  if (s.irradianceRes < 2 || s.distanceRes < 2 || s.rays < 1 || s.chebyshevPower < 0)
    throw Error("probes: map resolutions must be at least 2 texels and rays at least 1");
  glm::vec3 lo = bounds.valid() ? bounds.lo : glm::vec3(-0.5f), e = bounds.valid() ? bounds.extent() : glm::vec3(1.0f);
  GiProbeGrid g{};
  float minSpacing = 1e30f;
  for (int a = 0; a < 3; ++a) {
    float spacing = std::max(e[a], 1e-6f) / float(counts[a]);
    g.spacing[a] = spacing;
    g.origin[a] = lo[a] + 0.5f * spacing;
    g.count[a] = counts[a];
    minSpacing = std::min(minSpacing, spacing);
  }
  g.max_distance = s.maxDistance > 0.0f ? s.maxDistance : std::max(glm::length(e), 1e-3f);
  g.normal_bias = s.normalBias * minSpacing;
  g.view_bias = s.viewBias * minSpacing;
  g.irradiance_res = s.irradianceRes;
  g.distance_res = s.distanceRes;
  g.rays = s.rays;
  g.backface_floor = s.backfaceFloor;
  return g;
}

namespace {
// The integer nearest n · (√5 − 1)/2 that is coprime to n: consecutive positions i · stride mod n
// of the probe order then fall like a golden-ratio sequence, k of them spread over all n indices
// with gaps of about n/k (and so over every layer of the grid), and the order is a permutation.
int spreadingStride(int n) {
  int golden = int(std::lround(double(n) * 0.6180339887498949));
  for (int d = 0;; ++d)
    for (int c : {golden - d, golden + d})
      if (c >= 1 && c <= n && std::gcd(c, n) == 1) return c;
}

float signNotZero(float v) { return v >= 0.0f ? 1.0f : -1.0f; }
}  // namespace

glm::vec2 probeOctEncode(const glm::vec3& v) {
  float l1 = std::fabs(v.x) + std::fabs(v.y) + std::fabs(v.z);
  glm::vec2 p(v.x / l1, v.y / l1);
  if (v.z < 0.0f) p = glm::vec2((1.0f - std::fabs(p.y)) * signNotZero(p.x), (1.0f - std::fabs(p.x)) * signNotZero(p.y));
  return p;
}

glm::vec3 probeOctDecode(const glm::vec2& o) {
  glm::vec3 v(o.x, o.y, 1.0f - std::fabs(o.x) - std::fabs(o.y));
  if (v.z < 0.0f) {
    float x = (1.0f - std::fabs(v.y)) * signNotZero(v.x);
    float y = (1.0f - std::fabs(v.x)) * signNotZero(v.y);
    v.x = x;
    v.y = y;
  }
  return glm::normalize(v);
}

glm::vec3 probeTexelDirection(int tx, int ty, int res) {
  return probeOctDecode(glm::vec2((float(tx) + 0.5f) / float(res) * 2.0f - 1.0f, (float(ty) + 0.5f) / float(res) * 2.0f - 1.0f));
}

std::vector<glm::vec4> probeRayDirections(int rays, uint32_t update) {
  // A uniformly random rotation (Shoemake's unit quaternion) from 4 numbers of an mt19937 seeded
  // with the update number; mt19937's output sequence is fixed by the standard.
  std::mt19937 rng(0x9E3779B9u ^ (update * 2654435761u));
  auto uniform = [&] { return float(rng() >> 8) * (1.0f / 16777216.0f); };
  float u1 = uniform(), u2 = 6.2831853f * uniform(), u3 = 6.2831853f * uniform();
  float a = std::sqrt(1.0f - u1), b = std::sqrt(u1);
  glm::quat q(a * std::cos(u2), a * std::sin(u2), b * std::sin(u3), b * std::cos(u3));  // (w, x, y, z)
  glm::mat3 rot = glm::mat3_cast(glm::normalize(q));
  // Spherical Fibonacci: z uniform in (-1, 1), azimuth advancing by the golden angle.
  std::vector<glm::vec4> dirs(static_cast<size_t>(rays));
  const float golden = 0.61803398875f;
  for (int i = 0; i < rays; ++i) {
    float z = 1.0f - (2.0f * float(i) + 1.0f) / float(rays);
    float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    float f = float(i) * golden;
    float phi = 6.2831853f * (f - std::floor(f));
    glm::vec3 d = rot * glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
    dirs[size_t(i)] = glm::vec4(glm::normalize(d), 0.0f);
  }
  return dirs;
}

GiProbeUpdate probeIndexRange(int first, int count, float hysteresis) {
  GiProbeUpdate u{};
  u.first_position = first;
  u.stride = 1;
  u.probes = count;
  u.later_slot = count;
  u.hysteresis = u.later_hysteresis = hysteresis;
  return u;
}

ProbeField::ProbeField(cl::Context& ctx, const Scene& scene, const DeviceScene& deviceScene, const ProbeSettings& s)
    : ctx_(ctx), grid_(fitProbeGrid(scene.bounds, s)), multiBounce_(s.multiBounce), perceptualBlend_(s.perceptualBlend),
      downsample_(s.downsample),
      relocation_(s.relocate), backfaceFraction_(s.backfaceFraction),
      minFrontface_(s.minFrontface * std::min({grid_.spacing[0], grid_.spacing[1], grid_.spacing[2]})) {
  if (s.updateBudget < 0) throw Error("probes.update_budget = " + std::to_string(s.updateBudget) + ": must be at least 0 (0 = all probes)");
  probesPerUpdate_ = s.updateBudget == 0 ? probeCount() : std::min(s.updateBudget, probeCount());
  probeOrderStride_ = probesPerUpdate_ == probeCount() ? 1 : spreadingStride(probeCount());
  upsampleTest_.tauZ = s.tauZ;
  upsampleTest_.tauNDegrees = s.tauNDegrees;
  if (downsample_ > 1) upsampler_ = std::make_unique<GeometryAwareUpsampler>(ctx, "probes: upsample");
  bvh_ = std::make_unique<DeviceBvh>(ctx, scene, deviceScene);
  // The shading kernel is bound by per-lane loads of map texels: the gather width (8 lanes on
  // AVX2, where 16-lane code spills registers; cl/gather_width.h).
  vectorWidth_ = cl::gatherVectorWidth(ctx);
  char crush[32];
  std::snprintf(crush, sizeof crush, "%.9gf", double(s.crushThreshold));
  defines_ = cl::withGatherWidth(ctx, {{"GI_PROBE_DISTANCE_EXPONENT_LOG2", std::to_string(s.distanceExponentLog2)},
                                       {"GI_PROBE_CHEBYSHEV_POWER", std::to_string(s.chebyshevPower)},
                                       {"GI_PROBE_BACKFACE_SMOOTH", s.smoothBackface ? "1" : "0"},
                                       {"GI_PROBE_CRUSH", s.crushThreshold > 0.0f ? "1" : "0"},
                                       {"GI_PROBE_CRUSH_THRESHOLD", crush},
                                       {"GI_PROBE_PERCEPTUAL_BLEND", s.perceptualBlend ? "1" : "0"}});
  program_ = ctx.buildProgram("kernels/gi/probes/probes.cl", defines_);
  trace_ = program_.kernel("probe_trace");
  relocate_ = program_.kernel("probe_relocate");
  blendIrradiance_ = program_.kernel("probe_blend_irradiance");
  blendDistance_ = program_.kernel("probe_blend_distance");
  borderIrradiance_ = program_.kernel("probe_border_irradiance");
  borderDistance_ = program_.kernel("probe_border_distance");
  shade_ = program_.kernel("probe_shade");
  size_t probes = size_t(probeCount());
  size_t irrTexels = probes * size_t(s.irradianceRes + 2) * size_t(s.irradianceRes + 2);
  size_t distTexels = probes * size_t(s.distanceRes + 2) * size_t(s.distanceRes + 2);
  // The ray results hold one update's probes: the budget's, not the grid's (a dense grid's saving).
  size_t rayResultBytes = size_t(probesPerUpdate_) * size_t(s.rays) * 16;
  ctx.requireAllocation(irrTexels * 16 * (s.perceptualBlend ? 2 : 1) + distTexels * 8 + rayResultBytes + probes * 16,
                        "probes: maps and rays (probes.grid_*, probes.*_res, probes.rays, probes.update_budget)");
  irradiance_ = cl::Buffer(ctx, irrTexels * 16, CL_MEM_READ_WRITE, "probe irradiance maps");
  distance_ = cl::Buffer(ctx, distTexels * 8, CL_MEM_READ_WRITE, "probe distance maps");
  rayResults_ = cl::Buffer(ctx, rayResultBytes, CL_MEM_READ_WRITE, "probe ray results");
  rayDirs_ = cl::Buffer(ctx, size_t(s.rays) * 16, CL_MEM_READ_ONLY, "probe ray directions");
  states_ = cl::Buffer(ctx, probes * 16, CL_MEM_READ_WRITE, "probe states");
  ctx.fill(states_, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));  // at the grid points, active
  // Before the first update: no light, and every direction open up to the ray length (the first
  // update replaces both wherever a ray landed).
  ctx.fill(irradiance_, glm::vec4(0.0f));
  if (perceptualBlend_) {
    encodeSqrt_ = program_.kernel("probe_encode_sqrt");
    irradianceSqrt_ = cl::Buffer(ctx, irrTexels * 16, CL_MEM_READ_WRITE, "probe irradiance maps, square roots");
    ctx.fill(irradianceSqrt_, glm::vec4(0.0f));
  }
  ctx.fill(distance_, glm::vec2(grid_.max_distance, grid_.max_distance * grid_.max_distance));
  instanceEmits_ = ctx.upload(instanceEmissionFlags(scene), "probe instance emission flags");
}

void ProbeField::trace(const DeviceScene& scene, bool shadeHits, const GiProbeUpdate& slots) {
  unsigned a = 0;
  trace_.setArg(a++, grid_);
  a = bvh_->setArgs(trace_, a);
  trace_.setArg(a++, scene.positions);
  trace_.setArg(a++, scene.normals);
  trace_.setArg(a++, scene.tangents);
  trace_.setArg(a++, scene.triangleInstance);
  trace_.setArg(a++, instanceEmits_);
  trace_.setArg(a++, scene.lights);
  trace_.setArg(a++, shadeHits ? int(scene.lightCount) : 0);  // no lights: no shadow rays
  trace_.setArg(a++, rayDirs_);
  trace_.setArg(a++, irradianceLookup());
  trace_.setArg(a++, distance_);
  trace_.setArg(a++, states_);
  trace_.setArg(a++, int(shadeHits && multiBounce_ && updates_ > 0));
  trace_.setArg(a++, slots);
  trace_.setArg(a++, rayResults_);
  size_t rays = size_t(slots.probes) * size_t(grid_.rays);
  ctx_.launch(trace_, cl::NDRange::d1(cl::roundUp(rays, 64), 64), "probes: trace rays");
}

void ProbeField::relocateFromRays(bool moveProbes, const GiProbeUpdate& slots) {
  relocate_.args(grid_, rayDirs_, rayResults_, backfaceFraction_, minFrontface_, int(moveProbes), slots, states_);
  ctx_.launch(relocate_, cl::NDRange::d1(cl::roundUp(size_t(slots.probes), 64), 64), "probes: relocate");
}

void ProbeField::relocate(const DeviceScene& scene, int passes) {
  if (!relocation_) return;
  int probes = probeCount();
  for (int i = 0; i < passes; ++i) {
    // Directions of update numbers no update uses (the high half), a new rotation per pass.
    std::vector<glm::vec4> dirs = probeRayDirections(grid_.rays, 0x80000000u + relocationPasses_++);
    ctx_.write(rayDirs_, dirs.data(), dirs.size() * sizeof(glm::vec4));
    // Every probe, in batches of what the ray results hold (no hit is shaded: the batches are
    // independent).
    for (int first = 0; first < probes; first += probesPerUpdate_) {
      GiProbeUpdate batch = probeIndexRange(first, std::min(probesPerUpdate_, probes - first));
      trace(scene, false, batch);
      relocateFromRays(true, batch);
    }
  }
}

GiProbeUpdate ProbeField::nextUpdateSlots(float maxHysteresis) const {
  // Probe update number q (counted from the last restartMean()) is update floor(q / N) of the
  // probe at position q mod N of the order: round-robin, every probe comes once in any N
  // consecutive numbers.
  uint64_t probes = uint64_t(probeCount()), sinceMean = probeUpdates_ - meanStartProbeUpdates_;
  uint64_t rounds = sinceMean / probes, intoRound = sinceMean % probes;
  auto hysteresis = [&](uint64_t k) {
    float kf = float(k);
    return std::min(maxHysteresis, kf / (kf + 1.0f));
  };
  GiProbeUpdate slots{};
  slots.first_position = int(probeUpdates_ % probes);
  slots.stride = probeOrderStride_;
  slots.probes = probesPerUpdate_;
  slots.later_slot = int(probes - intoRound);  // from this slot on: the probe's update rounds + 1
  slots.hysteresis = hysteresis(rounds);
  slots.later_hysteresis = hysteresis(rounds + 1);
  return slots;
}

void ProbeField::update(const DeviceScene& scene, float maxHysteresis, bool moveProbes) {
  GiProbeUpdate slots = nextUpdateSlots(maxHysteresis);
  std::vector<glm::vec4> dirs = probeRayDirections(grid_.rays, updates_);
  ctx_.write(rayDirs_, dirs.data(), dirs.size() * sizeof(glm::vec4));
  size_t probes = size_t(slots.probes);
  trace(scene, true, slots);
  if (relocation_) relocateFromRays(moveProbes, slots);

  // The blend kernels take the vector width's worth of texels of one probe per work-item.
  size_t vw = size_t(vectorWidth_);
  auto items = [&](int res) { return probes * ((size_t(res) * size_t(res) + vw - 1) / vw); };
  blendIrradiance_.args(grid_, rayDirs_, rayResults_, slots, irradiance_);
  ctx_.launch(blendIrradiance_, cl::NDRange::d1(cl::roundUp(items(grid_.irradiance_res), 16), 16),
              "probes: blend irradiance");
  blendDistance_.args(grid_, rayDirs_, rayResults_, slots, distance_);
  ctx_.launch(blendDistance_, cl::NDRange::d1(cl::roundUp(items(grid_.distance_res), 16), 16), "probes: blend distance");

  size_t irrSide = size_t(grid_.irradiance_res + 2), distSide = size_t(grid_.distance_res + 2);
  borderIrradiance_.args(irradiance_, grid_.irradiance_res, probeCount(), slots);
  ctx_.launch(borderIrradiance_, cl::NDRange::d1(cl::roundUp(probes * irrSide * irrSide, 64), 64), "probes: irradiance borders");
  borderDistance_.args(distance_, grid_.distance_res, probeCount(), slots);
  ctx_.launch(borderDistance_, cl::NDRange::d1(cl::roundUp(probes * distSide * distSide, 64), 64), "probes: distance borders");
  if (perceptualBlend_) {
    int mapTexels = int(irrSide * irrSide);
    encodeSqrt_.args(irradiance_, mapTexels, probeCount(), slots, irradianceSqrt_);
    ctx_.launch(encodeSqrt_, cl::NDRange::d1(cl::roundUp(probes * size_t(mapTexels), 64), 64),
                "probes: irradiance square roots");
  }
  probeUpdates_ += uint64_t(slots.probes);
  ++updates_;
}

void ProbeField::shade(const GBuffer& g, cl::Buffer& indirect) {
  int d = downsample_, lw = (g.width + d - 1) / d, lh = (g.height + d - 1) / d;
  cl::Buffer* target = &indirect;
  if (d > 1) {
    if (!low_ || low_.bytes() != size_t(lw) * lh * 16)
      low_ = cl::Buffer(ctx_, size_t(lw) * lh * 16, CL_MEM_READ_WRITE, "probes low-res irradiance");
    target = &low_;
  }
  shade_.args(grid_, irradianceLookup(), distance_, states_, g.view, g.position, g.geoNormal, g.normal, g.albedo, d, *target);
  // One work-item shades a tile of 2^shift × vector width / 2^shift pixels (PROBE_TILE_SHIFT in
  // kernels/gi/probes/probes.cl: 16 lanes 8 × 2 at full resolution and 4 × 4 below it, 8 lanes
  // 4 × 2, one pixel at 1).
  int shift = vectorWidth_ == 16 ? (d == 1 ? 3 : 2) : vectorWidth_ == 8 ? 2 : 0;
  int tileW = 1 << shift, tileH = vectorWidth_ >> shift;
  int groupsX = (lw + tileW - 1) / tileW, groupsY = (lh + tileH - 1) / tileH;
  ctx_.launch(shade_, cl::NDRange::d2(cl::roundUp(groupsX, 8), cl::roundUp(groupsY, 8), 8, 8), "probes: shade");
  if (d > 1) upsampler_->run(g, low_, d, upsampleTest_, indirect);
}

}  // namespace gi
