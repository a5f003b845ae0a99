#include "gi/filters/discontinuity_filter.h"

#include <cmath>
#include <tuple>

#include "cl/gather_width.h"
#include "util/error.h"

namespace gi {

FilterShape filterShapeFromName(const std::string& name) {
  if (name == "box") return FilterShape::Box;
  if (name == "separable") return FilterShape::Separable;
  throw Error("discontinuity filter shape '" + name + "' is not box or separable");
}

void DiscontinuityFilter::run(const GBuffer& g, const cl::Buffer& irradiance, int fx, int fy, const GeometryTest& t,
                              cl::Buffer& out, FilterShape shape) {
  if (fx < 1 || fy < 1 || fx > kMaxWindow || fy > kMaxWindow)
    throw Error("discontinuity filter window " + std::to_string(fx) + "x" + std::to_string(fy) + " outside 1x1 .. " +
                std::to_string(kMaxWindow) + "x" + std::to_string(kMaxWindow));
  if (shape == FilterShape::Box) {
    pass(g, irradiance, fx, fy, t, Pass::Box, out);
    return;
  }
  if (ctx_.vectorWidth() > 1) {  // both passes in one launch (the kernel's GI_FILTER_SEPARABLE)
    pass(g, irradiance, fx, fy, t, Pass::FusedSeparable, out);
    return;
  }
  size_t bytes = size_t(g.width) * g.height * 16;
  if (!rowFiltered_ || rowFiltered_.bytes() != bytes)
    rowFiltered_ = cl::Buffer(ctx_, bytes, CL_MEM_READ_WRITE, label_ + " rows");
  pass(g, irradiance, fx, 1, t, Pass::RowsToIrradiance, rowFiltered_);
  pass(g, rowFiltered_, 1, fy, t, Pass::Box, out);
}

void DiscontinuityFilter::pass(const GBuffer& g, const cl::Buffer& irradiance, int fx, int fy, const GeometryTest& t,
                               Pass kind, cl::Buffer& out) {
  auto key = std::make_tuple(fx, fy, t.sameInstance, kind);
  auto it = kernels_.find(key);
  if (it == kernels_.end()) {
    cl::Program p = ctx_.buildProgram("kernels/gi/filters/discontinuity.cl",
                                      {{"GI_FX", std::to_string(fx)}, {"GI_FY", std::to_string(fy)},
                                       {"GI_SAME_INSTANCE", t.sameInstance ? "1" : "0"},
                                       {"GI_FILTER_APPLY_ALBEDO", kind == Pass::RowsToIrradiance ? "0" : "1"},
                                       {"GI_FILTER_SEPARABLE", kind == Pass::FusedSeparable ? "1" : "0"},
                                       {"GI_FILTER_ROWS", std::to_string(kRowsPerItem)}});
    cl::Kernel k = p.kernel("discontinuity_filter");
    it = kernels_.emplace(key, std::make_pair(std::move(p), std::move(k))).first;
  }
  cl::Kernel& k = it->second.second;
  float cosTauN = std::cos(t.tauNDegrees * 3.14159265f / 180.0f);
  k.args(g.width, g.height, irradiance, g.visibility.depth, g.geoNormal, g.instance, g.albedo, t.tauZ, cosTauN, out);
  int vw = ctx_.vectorWidth();
  if (vw == 1) {
    ctx_.launch(k, cl::NDRange::d2(cl::roundUp(g.width, 16), cl::roundUp(g.height, 16), 16, 16), label_);
  } else {
    size_t gx = (size_t(g.width) + vw - 1) / vw, gy = (size_t(g.height) + kRowsPerItem - 1) / kRowsPerItem;
    ctx_.launch(k, cl::NDRange::d2(cl::roundUp(gx, 2), gy, 2, 1), label_);
  }
}

void GeometryAwareUpsampler::run(const GBuffer& g, const cl::Buffer& lowIrradiance, int factor, const GeometryTest& t,
                                 cl::Buffer& out) {
  auto it = kernels_.find(factor);
  if (it == kernels_.end()) {
    cl::Program p = ctx_.buildProgram("kernels/gi/filters/discontinuity.cl",
                                      cl::withGatherWidth(ctx_, {{"GI_UP", std::to_string(factor)}}));
    cl::Kernel k = p.kernel("geometry_aware_upsample");
    it = kernels_.emplace(factor, std::make_pair(std::move(p), std::move(k))).first;
  }
  cl::Kernel& k = it->second.second;
  int lw = (g.width + factor - 1) / factor, lh = (g.height + factor - 1) / factor;
  float cosTauN = std::cos(t.tauNDegrees * 3.14159265f / 180.0f);
  k.args(g.width, g.height, lw, lh, lowIrradiance, g.visibility.depth, g.geoNormal, g.instance, g.albedo, t.tauZ,
         cosTauN, out);
  int vw = cl::gatherVectorWidth(ctx_);
  size_t gx = (size_t(g.width) + vw - 1) / vw;
  if (vw == 1) ctx_.launch(k, cl::NDRange::d2(cl::roundUp(gx, 16), cl::roundUp(g.height, 16), 16, 16), label_);
  // Work-groups along a row: PoCL runs a group's work-items one after another, and 16 blocks of
  // one row stream through memory where a column of blocks from 8 rows did not (1 x 8 groups
  // took 1.3-2x the CPU time; docs/PERFORMANCE.md, issue 5).
  else ctx_.launch(k, cl::NDRange::d2(cl::roundUp(gx, 16), g.height, 16, 1), label_);
}

}  // namespace gi
