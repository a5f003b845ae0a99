#include "gi/filters/discontinuity_filter.h"

#include <cmath>

#include "cl/gather_width.h"

namespace gi {

void DiscontinuityFilter::run(const GBuffer& g, const cl::Buffer& irradiance, int fx, int fy, const GeometryTest& t,
                              cl::Buffer& out) {
  auto key = std::make_pair(fx, fy);
  auto it = kernels_.find(key);
  if (it == kernels_.end()) {
    cl::Program p = ctx_.buildProgram("kernels/gi/filters/discontinuity.cl",
                                      {{"GI_FX", std::to_string(fx)}, {"GI_FY", std::to_string(fy)}});
    cl::Kernel k = p.kernel("discontinuity_filter");
    it = kernels_.emplace(key, std::make_pair(std::move(p), std::move(k))).first;
  }
  cl::Program& prog = it->second.first;
  cl::Kernel& k = it->second.second;
  if (!prepare_.get()) prepare_ = prog.kernel("discontinuity_prepare");
  size_t L = size_t(g.width) * g.height + 2 * kPad;
  if (!planes_ || planes_.bytes() != L * 8 * 4) {
    planes_ = cl::Buffer(ctx_, L * 8 * 4, CL_MEM_READ_WRITE, label_ + " planes");
    ctx_.fill(planes_, 0.0f);  // margins: zero depth/normal, instance 0 — always masked by the x/y tests
  }
  prepare_.args(g.width, g.height, irradiance, g.visibility.depth, g.geoNormal, g.instance, planes_);
  size_t groups = (size_t(g.width) * g.height + 15) / 16;
  ctx_.launch(prepare_, cl::NDRange::d1(cl::roundUp(groups, 8), 8), label_ + " (prepare)");
  float cosTauN = std::cos(t.tauNDegrees * 3.14159265f / 180.0f);
  k.args(g.width, g.height, planes_, g.albedo, t.tauZ, cosTauN, int(t.sameInstance), out);
  int vw = ctx_.vectorWidth();
  size_t gx = (size_t(g.width) + vw - 1) / vw;
  if (vw == 1) ctx_.launch(k, cl::NDRange::d2(cl::roundUp(gx, 16), cl::roundUp(g.height, 16), 16, 16), label_);
  else ctx_.launch(k, cl::NDRange::d2(gx, cl::roundUp(g.height, 8), 1, 8), label_);
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
