// `sh-igi`: SH-filtered instant global illumination (Segovia & Wald, seed 001; ALGORITHMS.md §2.5;
// kernels/gi/sh_igi/sh_igi.cl; docs/techniques/sh-igi.md).
#pragma once
#include "cl/runtime.h"
#include "gi/technique.h"
#include "raster/gbuffer.h"

namespace gi {
TechniqueInfo shIgiTechniqueInfo();

// The filter's planes (kernels/gi/sh_igi/sh_igi.cl, SH_PLANES) in camera order, in row blocks:
// camera row y is block y of kPlanes rows of `pitch` floats (plane k in row k, pixel x at column
// x), after `pad` floats. The pitch leaves at least 16 floats after the row's last whole vector of
// 16, so every window offset's vector load stays inside the buffer.
struct ShIgiPlanes {
  static constexpr int kPlanes = 32;  // 27 coefficients [channel][k], view depth, geometric normal, instance id
  int width = 0, height = 0, pitch = 0, pad = 0;
  size_t floats = 0;
  ShIgiPlanes() = default;
  ShIgiPlanes(int width, int height);
  size_t bytes() const { return floats * sizeof(float); }
  // Float index of `plane` at camera pixel (x, y).
  size_t at(int plane, int x, int y) const {
    return size_t(pad) + (size_t(y) * kPlanes + size_t(plane)) * size_t(pitch) + size_t(x);
  }
};

// GI_VW of the sh-igi projection program (and of its VPL lane table), and its launch range over a
// layout (sh_pixels in the kernels: GI_VW consecutive pixels of one camera row per work-item,
// row-major). The filters are built with shIgiFilterVectorWidth: the box filter with 16 lanes
// where the CPU has AVX-512 (8 with AVX2), the separable one with at most 8.
int shIgiVectorWidth(const cl::Context& ctx);
int shIgiFilterVectorWidth(const cl::Context& ctx, bool separable);
cl::NDRange shIgiRange(const cl::Context& ctx, const ShIgiPlanes& layout);

// The filter and shading kernel of a program built with GI_FX = fx, GI_FY = fy and GI_VW =
// shIgiFilterVectorWidth(ctx, separable) — sh_igi_filter_shade (box) or, with `separable`, sh_igi_filter_shade_separable,
// both SH_FILTER_ROWS = kShIgiFilterRows rows per work-item — launched over `planes` whose
// coefficient and key planes are filled, into `out` (float4 radiance per camera pixel).
constexpr int kShIgiFilterRows = 8;
void shIgiFilterShade(cl::Context& ctx, cl::Kernel& filter, bool separable, const ShIgiPlanes& layout,
                      const GBuffer& g, const cl::Buffer& planes, float tauZ, float cosTauN, bool sameInstance,
                      bool glossy, cl::Buffer& out, const std::string& label = "sh-igi");
}  // namespace gi
