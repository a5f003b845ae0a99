// Reusable geometry-aware passes (ALGORITHMS.md §3; kernels/gi/filters/discontinuity.cl):
//   DiscontinuityFilter  box filter of irradiance over an fx×fy window (≥ the interleave
//                        pattern), accepting neighbours by depth, geometric normal and optionally
//                        instance id; writes L = ρ/π · E. Box: the 2D window in one pass;
//                        separable: an fx×1 pass then a 1×fy pass (fx + fy taps, not fx·fy);
//   GeometryAwareUpsampler  reduced-resolution irradiance -> full resolution, same test.
#pragma once
#include <map>
#include <tuple>
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

enum class FilterShape { Box, Separable };

// "box" | "separable" -> FilterShape (the techniques' *.filter parameter).
FilterShape filterShapeFromName(const std::string& name);

class DiscontinuityFilter {
public:
  DiscontinuityFilter(cl::Context& ctx, std::string label) : ctx_(ctx), label_(std::move(label)) {}
  // irradiance: float4 E per camera pixel; out: float4 L = ρ/π · filtered E.
  void run(const GBuffer& g, const cl::Buffer& irradiance, int fx, int fy, const GeometryTest& t, cl::Buffer& out,
           FilterShape shape = FilterShape::Box);

private:
  enum class Pass {
    Box,               // fx×fy window, writes L
    RowsToIrradiance,  // fx×1 window, writes the filtered E (separable on GI_VW = 1, first launch)
    FusedSeparable,    // row pass then column pass in one launch, writes L (vector devices)
  };
  void pass(const GBuffer& g, const cl::Buffer& irradiance, int fx, int fy, const GeometryTest& t, Pass kind,
            cl::Buffer& out);
  cl::Context& ctx_;
  std::string label_;
  // per window size, instance test and pass kind
  std::map<std::tuple<int, int, bool, Pass>, std::pair<cl::Program, cl::Kernel>> kernels_;
  cl::Buffer rowFiltered_;  // separable on GI_VW = 1: E after the fx×1 launch
  static constexpr int kMaxWindow = 16;   // the kernel's largest GI_FILTER_APRON = kMaxWindow / 2
  static constexpr int kRowsPerItem = 16;  // GI_FILTER_ROWS: output rows per work-item (vector path)
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
