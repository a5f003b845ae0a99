// The light propagation volume on the device: cascaded SH grids, the geometry volume, and the
// passes that fill, propagate and read them (kernels/gi/lpv/lpv.cl). The `lpv` technique
// (lpv_technique.cpp) drives it once per frame; the tests drive the passes one by one.
//
// Units: the grid stores the SH coefficients (kernels/common/sh.h) of each cell's intensity
// I(ω) in W/sr by direction of travel (on the device each times its basis constant, lpv.cl
// LPV_UNIT0/1; the read and set functions below convert); the geometry volume stores blocking potential
// (dimensionless, A/s² × cosine lobe). A grid with `cascades` levels is LPV_N³ cells each; level k
// is the axis-aligned cube with corner origin[k] and cell edge cell[k] (LpvCascade).
#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "cl/runtime.h"
#include "raster/gbuffer.h"
#include "scene/scene.h"

namespace gi {

struct LpvCascade {
  glm::vec3 origin{0.0f};  // corner of cell (0, 0, 0), metres
  float cell = 1.0f;       // cell edge s, metres
};

// cascades == 0: one grid, a cube over the scene bounds' longest edge, centred on the bounds.
// cascades >= 1: that many grids of edge extent0·2^k centred on the camera, each snapped to its own
// whole cells (the grid moves in steps of one cell, so the image does not swim).
std::vector<LpvCascade> lpvCascadeLayout(const Bounds& bounds, const glm::vec3& camera, int resolution,
                                         int cascades, float extent0);

// Fixed-point scale for the injection sums (ALGORITHMS.md §7): 2^48 over an upper bound of the
// flux all RSMs together can reflect (light power, albedo <= 1), so no cell sum can overflow.
float lpvInjectionFixedScale(const Scene& scene, const std::vector<ReflectiveShadowMap>& rsms);

// Where the lookup reads the grid from: a float4 buffer interpolated by the kernel, or a 3D image
// filtered by the sampler (in hardware on GPUs; PoCL filters images in software).
enum class LpvLookupStorage { Buffer, Image };

// The lookup grid as a read-only 3D image of float4 texels (CL_RGBA, CL_FLOAT: every image-capable
// OpenCL 1.2 device supports it), filled from a buffer by copy(). Frees itself; moves, never copies.
class LpvImage {
public:
  LpvImage() = default;
  // Throws gi::Error naming what the device lacks (images at all, or this size).
  LpvImage(cl::Context& ctx, size_t width, size_t height, size_t depth);
  ~LpvImage();
  LpvImage(LpvImage&& o) noexcept;
  LpvImage& operator=(LpvImage&& o) noexcept;
  LpvImage(const LpvImage&) = delete;
  LpvImage& operator=(const LpvImage&) = delete;

  cl_mem get() const { return mem_; }
  size_t bytes() const { return width_ * height_ * depth_ * 16; }
  // The whole image from `src`, which holds its texels row after row, slice after slice.
  void copy(cl::Context& ctx, const cl::Buffer& src);

private:
  cl_mem mem_ = nullptr;
  size_t width_ = 0, height_ = 0, depth_ = 0;
};

class LpvVolume {
public:
  static constexpr int kRunLength = 16;  // texels a work-item merges before its atomic adds
  static constexpr int kPad = 16;        // floats before the grids (lpv.cl)
  static constexpr int kSkew = 32;       // floats after each z slice (lpv.cl LPV_SKEW: slices not 2^k bytes apart)
  static constexpr float kGeometryFixedScale = 1099511627776.0f;  // 2^40

  // Throws gi::Error when `storage` is Image and the device has no 3D images of the size needed.
  // `bounces` (lpv.bounces): blocked light is reflected by the blockers with the albedo of the
  // camera's surfels (Kaplanyan & Dachsbacher 2010, multiple indirect bounces; lpv.cl).
  LpvVolume(cl::Context& ctx, int resolution, int cascadeCount, LpvLookupStorage storage = LpvLookupStorage::Buffer,
            bool bounces = false);

  int resolution() const { return n_; }
  int cascadeCount() const { return cascades_; }
  bool bounces() const { return bounces_; }
  size_t cellsPerGrid() const { return size_t(n_) * n_ * n_; }
  size_t nodesPerGrid() const { return size_t(n_ + 1) * (n_ + 1) * (n_ + 1); }
  // The float grids' row-block layout (lpv.cl LPV_AT): floats in all cascades, and the offset of
  // plane p (channel·4 + coefficient) of cell (z·N + y)·N + x of cascade k.
  size_t gridFloats() const { return kPad + (12 * cellsPerGrid() + size_t(kSkew) * n_) * cascades_; }
  size_t gridOffset(int k, int p, size_t cell) const;
  uint64_t bytes() const;

  // Per frame, in this order.
  void begin(const std::vector<LpvCascade>& layout, float injectionFixedScale);  // clears the sums
  // RSM planes (float4 per texel, res×res) merged in block×block groups; VPLs shifted by
  // bias × cell along their normal.
  void inject(const cl::Buffer& position, const cl::Buffer& normal, const cl::Buffer& flux, int res, int block,
              float bias);
  void addGeometryRsm(const GiView& view, const cl::Buffer& position, const cl::Buffer& normal, int res);
  void addGeometryCamera(const GBuffer& g);
  void resolve(bool geometry);  // sums -> float grids (the geometry volume only when asked)
  // `iterations` gather steps; with `blocking`, first the blocking potential per cell face from
  // the geometry volume and from it the 30 face factors per cell (static over the steps), which
  // block every step but the first; with bounces() each blocked step's blocked light is then
  // reflected back into the cells it came from (lpv_reflect_blocked).
  void propagate(int iterations, bool blocking);
  // Converts the accumulated grid into the lookup grid unless the last propagation step already
  // did, then writes L = ρ/π · E per pixel.
  // With `damping` (lpv.damping): Kaplanyan 2009's damping of light flowing away from the surface,
  // E limited to the irradiance one cell further along the geometric normal (lpv.cl lpv_lookup).
  void lookup(const GBuffer& g, bool blendCascades, cl::Buffer& out, bool damping = false);

  // For tests, coefficients as float4 [cascade][rgb][cell] (the device keeps planes, lpv.cl):
  // the grid the last step wrote (the injected grid before any step), the accumulated grid.
  std::vector<glm::vec4> readCurrent() { return readGrid(grids_[current_]); }
  std::vector<glm::vec4> readAccumulated() { return readGrid(accumulated_); }
  // Replaces the injected grid (and the accumulated one).
  void setInjected(const std::vector<glm::vec4>& coefficients);
  // The geometry volume as float4 [cascade][node], read or replaced.
  std::vector<glm::vec4> readGeometry();
  void setGeometry(const std::vector<glm::vec4>& nodes);
  // With bounces(): the camera surfels' albedo sums per node as float4 [cascade][node]
  // (Σ ρ_r·w, Σ ρ_g·w, Σ ρ_b·w, Σ w), replaced (stored in the kernels' fixed point).
  void setSurfelAlbedo(const std::vector<glm::vec4>& nodes);

private:
  std::vector<glm::vec4> readGrid(const cl::Buffer& b);

  cl::Context& ctx_;
  LpvLookupStorage storage_;
  int n_, cascades_, vw_, lanes_;  // vw_: GI_VW (cl/gather_width.h); lanes_: cells per propagation work-item
  bool bounces_;
  float injectionScale_ = 1.0f;
  cl::Program program_;
  cl::Kernel inject_, geometryRsm_, geometryCamera_, resolveInjection_, resolveGeometry_, faceGeometryKernel_, faceFactorsKernel_, propagateBlocked_, propagateOpen_,
      toLookupGrid_, lookup_, faceAlbedoKernel_, reflectBlocked_;
  cl::Buffer layout_, gridAcc_, geometryAcc_, grids_[2], accumulated_, geometry_, faceGeometry_, faceFactors_, lookupGrid_;
  cl::Buffer albedoAcc_, faceAlbedo_;  // with bounces_: surfel albedo sums per node, albedo per cell face
  LpvImage lookupImage_;  // with LpvLookupStorage::Image: lookupGrid_'s copy the lookup samples
  cl::NDRange propagateRange_;
  int current_ = 0;
  bool lookupGridCurrent_ = false;  // lookupGrid_ holds the accumulated grid (the last step writes it)
};

}  // namespace gi
