// Reusable geometry-aware passes (ALGORITHMS.md §3; kernels/gi/filters/discontinuity.cl):
//   DiscontinuityFilter  box filter of irradiance over an fx×fy window (≥ the interleave
//                        pattern), accepting neighbours by depth, geometric normal and optionally
//                        instance id; writes L = ρ/π · E;
//   GeometryAwareUpsampler  reduced-resolution irradiance -> full resolution, same test.
#pragma once
#include <map>
#include <string>
#include <utility>

#include "cl/runtime.h"
#include "raster/gbuffer.h"

namespace gi {

struct GeometryTest {
  float tauZ = 0.05f;        // relative view-depth tolerance
  float tauNDegrees = 25.0f; // geometric-normal angle tolerance
  bool sameInstance = false; // also require the same instance id (filter only)
};

class DiscontinuityFilter {
public:
  DiscontinuityFilter(cl::Context& ctx, std::string label) : ctx_(ctx), label_(std::move(label)) {}
  // irradiance: float4 E per camera pixel; out: float4 L = ρ/π · filtered E.
  void run(const GBuffer& g, const cl::Buffer& irradiance, int fx, int fy, const GeometryTest& t, cl::Buffer& out);

private:
  cl::Context& ctx_;
  std::string label_;
  std::map<std::pair<int, int>, std::pair<cl::Program, cl::Kernel>> kernels_;  // per window size
  cl::Kernel prepare_;
  cl::Buffer planes_;  // padded SoA copy (kernels/gi/filters/discontinuity.cl, GI_FILTER_PAD)
  static constexpr size_t kPad = 64;
};

class GeometryAwareUpsampler {
public:
  GeometryAwareUpsampler(cl::Context& ctx, std::string label) : ctx_(ctx), label_(std::move(label)) {}
  // lowIrradiance: float4 E per pixel of the (⌈W/factor⌉ × ⌈H/factor⌉) image whose pixel (u, v)
  // was evaluated at full-resolution pixel (u·factor, v·factor).
  void run(const GBuffer& g, const cl::Buffer& lowIrradiance, int factor, const GeometryTest& t, cl::Buffer& out);

private:
  cl::Context& ctx_;
  std::string label_;
  std::map<int, std::pair<cl::Program, cl::Kernel>> kernels_;
};

}  // namespace gi
