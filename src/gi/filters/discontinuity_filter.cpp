#include "gi/filters/discontinuity_filter.h"

#include <cmath>

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
  cl::Kernel& k = it->second.second;
  float cosTauN = std::cos(t.tauNDegrees * 3.14159265f / 180.0f);
  k.args(g.width, g.height, irradiance, g.visibility.depth, g.geoNormal, g.instance, g.albedo, t.tauZ, cosTauN,
         int(t.sameInstance), out);
  ctx_.launch(k, cl::NDRange::d2(cl::roundUp(g.width, 16), cl::roundUp(g.height, 16), 16, 16), label_);
}

void GeometryAwareUpsampler::run(const GBuffer& g, const cl::Buffer& lowIrradiance, int factor, const GeometryTest& t,
                                 cl::Buffer& out) {
  auto it = kernels_.find(factor);
  if (it == kernels_.end()) {
    cl::Program p = ctx_.buildProgram("kernels/gi/filters/discontinuity.cl", {{"GI_UP", std::to_string(factor)}});
    cl::Kernel k = p.kernel("geometry_aware_upsample");
    it = kernels_.emplace(factor, std::make_pair(std::move(p), std::move(k))).first;
  }
  cl::Kernel& k = it->second.second;
  int lw = (g.width + factor - 1) / factor, lh = (g.height + factor - 1) / factor;
  float cosTauN = std::cos(t.tauNDegrees * 3.14159265f / 180.0f);
  k.args(g.width, g.height, lw, lh, lowIrradiance, g.visibility.depth, g.geoNormal, g.instance, g.albedo, t.tauZ,
         cosTauN, out);
  ctx_.launch(k, cl::NDRange::d2(cl::roundUp(g.width, 16), cl::roundUp(g.height, 16), 16, 16), label_);
}

}  // namespace gi
