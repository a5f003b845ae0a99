// `sh-igi`: SH-filtered instant global illumination (Segovia & Wald, seed 001; ALGORITHMS.md §2.5;
// kernels/gi/sh_igi/sh_igi.cl; docs/techniques/sh-igi.md).
#pragma once
#include "cl/runtime.h"
#include "gi/technique.h"
#include "raster/gbuffer.h"

namespace gi {
TechniqueInfo shIgiTechniqueInfo();

// The filter's planes (kernels/gi/sh_igi/sh_igi.cl, SH_PLANES) in row blocks: the slots of row sy
// of sub-image c (InterleavedGather's packed layout: c·stride + sy·subWidth + sx) form block
// c·subHeight + sy of kPlanes rows of `pitch` floats; a margin of `pad` floats before the first and
// after the last block holds every slot a window offset can reach from a slot of the image.
struct ShIgiPlanes {
  static constexpr int kPlanes = 32;  // 27 coefficients [channel][k], view depth, geometric normal, instance id
  int width = 0, height = 0, n = 1, m = 1, subWidth = 0, subHeight = 0, stride = 0, pitch = 0, pad = 0;
  size_t floats = 0;
  ShIgiPlanes() = default;
  ShIgiPlanes(int width, int height, int n, int m, int stride, int fx, int fy);
  size_t bytes() const { return floats * sizeof(float); }
  // Float index of `plane` at packed slot `slot` (c·stride + sy·subWidth + sx).
  size_t at(int plane, size_t slot) const {
    size_t c = slot / size_t(stride), rest = slot % size_t(stride);
    size_t sy = rest / size_t(subWidth), sx = rest % size_t(subWidth);
    return size_t(pad) + ((c * size_t(subHeight) + sy) * kPlanes + size_t(plane)) * size_t(pitch) + sx;
  }
};

// GI_VW of the sh-igi programs, and their launch range over a layout (sh_row in the kernels:
// GI_VW slots of one sub-image row per work-item, sub-image fastest).
int shIgiVectorWidth(const cl::Context& ctx);
cl::NDRange shIgiRange(const cl::Context& ctx, const ShIgiPlanes& layout);

// The kernels of the filter and shading (sh_igi_keys, sh_igi_filter_shade of a program built with
// GI_FX = fx, GI_FY = fy and GI_VW = shIgiVectorWidth), launched over `planes` whose coefficient planes are filled: keys from the
// G-buffer, then filter + shade into `out` (float4 radiance per camera pixel).
void shIgiFilterShade(cl::Context& ctx, cl::Kernel& keys, cl::Kernel& filter, const ShIgiPlanes& layout,
                      const GBuffer& g, const cl::Buffer& planes, float tauZ, float cosTauN, bool sameInstance,
                      bool glossy, cl::Buffer& out, const std::string& label = "sh-igi");
}  // namespace gi
