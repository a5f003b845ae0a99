// The light propagation volume on the device (see lpv_volume.h; kernels in kernels/gi/lpv/lpv.cl).
#include "gi/lpv/lpv_volume.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "cl/gather_width.h"
#include "kernels/common/sh.h"

namespace gi {

std::vector<LpvCascade> lpvCascadeLayout(const Bounds& bounds, const glm::vec3& camera, int resolution,
                                         int cascades, float extent0) {
  const float n = float(resolution);
  if (cascades == 0) {
    glm::vec3 e = bounds.extent();
    float cell = std::max({e.x, e.y, e.z, 1e-6f}) / n;
    return {LpvCascade{bounds.center() - 0.5f * n * cell, cell}};
  }
  std::vector<LpvCascade> layout;
  for (int k = 0; k < cascades; ++k) {
    float cell = extent0 * std::ldexp(1.0f, k) / n;
    glm::vec3 snapped = glm::floor(camera / cell) * cell;
    layout.push_back({snapped - 0.5f * n * cell, cell});
  }
  return layout;
}

float lpvInjectionFixedScale(const Scene& scene, const std::vector<ReflectiveShadowMap>& rsms) {
  double bound = 0.0;
  for (const ReflectiveShadowMap& r : rsms) {
    const GiLight& l = scene.lights[r.light];
    double peak = std::max({l.intensity[0], l.intensity[1], l.intensity[2], 0.0f});
    if (l.type == GI_LIGHT_DIRECTIONAL) {
      double side = double(r.view.texel_world_size);
      bound += peak * side * r.view.width * side * r.view.height;  // irradiance × the RSM's area
    } else {
      bound += peak * 4.0 * M_PI;  // intensity over the whole sphere
    }
  }
  return float(std::ldexp(1.0, 48) / std::max(bound, 1e-20));
}

LpvImage::LpvImage(cl::Context& ctx, size_t width, size_t height, size_t depth)
    : width_(width), height_(height), depth_(depth) {
  const cl::DeviceInfo& d = ctx.device();
  if (!d.imageSupport) throw Error("lpv.lookup_storage=image: " + d.name + " has no image support");
  size_t limit[3] = {0, 0, 0};
  clGetDeviceInfo(d.id, CL_DEVICE_IMAGE3D_MAX_WIDTH, sizeof(size_t), &limit[0], nullptr);
  clGetDeviceInfo(d.id, CL_DEVICE_IMAGE3D_MAX_HEIGHT, sizeof(size_t), &limit[1], nullptr);
  clGetDeviceInfo(d.id, CL_DEVICE_IMAGE3D_MAX_DEPTH, sizeof(size_t), &limit[2], nullptr);
  if (width > limit[0] || height > limit[1] || depth > limit[2])
    throw Error("lpv.lookup_storage=image: a 3D image of " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                std::to_string(depth) + " exceeds " + d.name + "'s limit of " + std::to_string(limit[0]) + "x" +
                std::to_string(limit[1]) + "x" + std::to_string(limit[2]) + " (fewer cascades or a lower resolution)");
  ctx.requireAllocation(bytes(), "lpv lookup grid (3D image)");
  cl_image_format format{CL_RGBA, CL_FLOAT};
  cl_image_desc desc{};
  desc.image_type = CL_MEM_OBJECT_IMAGE3D;
  desc.image_width = width;
  desc.image_height = height;
  desc.image_depth = depth;
  cl_int err = CL_SUCCESS;
  mem_ = clCreateImage(ctx.get(), CL_MEM_READ_ONLY, &format, &desc, nullptr, &err);
  cl::check(err, "allocating the lpv lookup grid (3D image, " + std::to_string(bytes()) + " bytes)");
}
LpvImage::~LpvImage() {
  if (mem_) clReleaseMemObject(mem_);
}
LpvImage::LpvImage(LpvImage&& o) noexcept
    : mem_(std::exchange(o.mem_, nullptr)), width_(o.width_), height_(o.height_), depth_(o.depth_) {}
LpvImage& LpvImage::operator=(LpvImage&& o) noexcept {
  if (this != &o) {
    if (mem_) clReleaseMemObject(mem_);
    mem_ = std::exchange(o.mem_, nullptr);
    width_ = o.width_;
    height_ = o.height_;
    depth_ = o.depth_;
  }
  return *this;
}
void LpvImage::copy(cl::Context& ctx, const cl::Buffer& src) {
  const size_t origin[3] = {0, 0, 0}, region[3] = {width_, height_, depth_};
  cl::check(clEnqueueCopyBufferToImage(ctx.queue(), src.get(), mem_, 0, origin, region, 0, nullptr, nullptr),
            "copying the lpv lookup grid into its 3D image");
}

// Cells of a row per propagation work-item: the device's native float vector width (16 with
// AVX-512, 8 with AVX2, 1 on GPUs; cl/gather_width.h), reduced to a width the row length is a
// multiple of.
int propagationLanes(int vectorWidth, int n) {
  for (int lanes : {16, 8, 4})
    if (lanes <= vectorWidth && n % lanes == 0) return lanes;
  return 1;
}

LpvVolume::LpvVolume(cl::Context& ctx, int resolution, int cascadeCount, LpvLookupStorage storage, bool bounces)
    : ctx_(ctx),
      storage_(storage),
      n_(resolution),
      cascades_(cascadeCount),
      vw_(cl::gatherVectorWidth(ctx)),
      lanes_(propagationLanes(vw_, resolution)),
      bounces_(bounces) {
  bool images = storage_ == LpvLookupStorage::Image;
  if (images)  // the (cascade, channel) slabs stacked along z
    lookupImage_ = LpvImage(ctx, size_t(n_), size_t(n_), size_t(n_) * 3 * cascades_);
  // A propagation step's working set per cascade: source, destination and accumulated grids (12
  // floats per cell each) and the 30 half-precision face factors. Larger than the last-level cache
  // (64³: 53.5 MB against 32 MiB), the step prefetches all its streams (lpv.cl LPV_PREFETCH_STREAMS).
  uint64_t cacheBytes = ctx.device().globalCacheBytes;
  bool streamPrefetch = cacheBytes > 0 && cellsPerGrid() * (3 * 12 * sizeof(float) + 30 * sizeof(uint16_t)) > cacheBytes;
  // GI_VW: texels or pixels per work-item of the injection, surfel and lookup kernels (a divisor of LPV_RUN).
  program_ = ctx.buildProgram("kernels/gi/lpv/lpv.cl", {{"LPV_N", std::to_string(n_)},
                                                         {"LPV_CASCADES", std::to_string(cascades_)},
                                                         {"LPV_RUN", std::to_string(kRunLength)},
                                                         {"LPV_LANES", std::to_string(lanes_)},
                                                         {"LPV_PAD", std::to_string(kPad)},
                                                         {"LPV_SKEW", std::to_string(kSkew)},
                                                         {"LPV_PREFETCH_STREAMS", streamPrefetch ? "1" : "0"},
                                                         {"GI_VW", std::to_string(vw_)},
                                                         {"LPV_IMAGES", images ? "1" : "0"}});
  inject_ = program_.kernel("lpv_inject");
  geometryRsm_ = program_.kernel("lpv_geometry_rsm");
  geometryCamera_ = program_.kernel("lpv_geometry_camera");
  resolveInjection_ = program_.kernel("lpv_resolve_injection");
  resolveGeometry_ = program_.kernel("lpv_resolve_geometry");
  faceGeometryKernel_ = program_.kernel("lpv_face_geometry");
  faceFactorsKernel_ = program_.kernel("lpv_face_factors");
  propagateBlocked_ = program_.kernel("lpv_propagate_blocked");
  propagateOpen_ = program_.kernel("lpv_propagate_open");
  toLookupGrid_ = program_.kernel("lpv_lookup_grid");
  lookup_ = program_.kernel("lpv_lookup");
  faceAlbedoKernel_ = program_.kernel("lpv_face_albedo");
  reflectBlocked_ = program_.kernel("lpv_reflect_blocked");
  size_t cells = cellsPerGrid() * cascades_, nodes = nodesPerGrid() * cascades_;
  layout_ = cl::Buffer(ctx, size_t(cascades_) * 16, CL_MEM_READ_ONLY, "lpv cascade layout");
  gridAcc_ = cl::Buffer(ctx, cells * 3 * 4 * 8, CL_MEM_READ_WRITE, "lpv injection sums");
  geometryAcc_ = cl::Buffer(ctx, nodes * 2 * 4 * 8, CL_MEM_READ_WRITE, "lpv geometry sums");
  size_t gridBytes = gridFloats() * sizeof(float);
  for (cl::Buffer& g : grids_) {
    g = cl::Buffer(ctx, gridBytes, CL_MEM_READ_WRITE, "lpv grid");
    ctx.fill(g, 0.0f);  // the padding stays 0
  }
  accumulated_ = cl::Buffer(ctx, gridBytes, CL_MEM_READ_WRITE, "lpv accumulated grid");
  ctx.fill(accumulated_, 0.0f);
  geometry_ = cl::Buffer(ctx, nodes * 16, CL_MEM_READ_WRITE, "lpv geometry volume");
  ctx.fill(geometry_, 0.0f);
  faceGeometry_ = cl::Buffer(ctx, gridFloats() * sizeof(uint16_t), CL_MEM_READ_WRITE,  // half precision
                             "lpv face blocking potential");
  ctx.fill(faceGeometry_, 0.0f);  // padding and skew stay 0
  // 30 face factors per cell in half precision, row blocks (lpv.cl LPV_FACTOR_AT): per cascade N
  // slices of 30·N² + kSkew.
  size_t factorHalves = kPad + size_t(cascades_) * n_ * (30 * size_t(n_) * n_ + kSkew);
  faceFactors_ = cl::Buffer(ctx, factorHalves * sizeof(uint16_t), CL_MEM_READ_WRITE, "lpv face factors");
  ctx.fill(faceFactors_, uint16_t(0));  // padding and skew stay 0
  lookupGrid_ = cl::Buffer(ctx, cells * 3 * 16, CL_MEM_READ_WRITE, "lpv lookup grid");
  if (bounces_) {
    albedoAcc_ = cl::Buffer(ctx, nodes * 4 * 8, CL_MEM_READ_WRITE, "lpv surfel albedo sums");
    faceAlbedo_ = cl::Buffer(ctx, gridBytes, CL_MEM_READ_WRITE, "lpv face albedo");  // planes a·4 + ch of a grid
    ctx.fill(faceAlbedo_, 0.0f);
  }
  // One row of cells per work-group: many groups, which PoCL spreads over the cores.
  propagateRange_ = cl::NDRange::d3(size_t(n_ / lanes_), size_t(n_), size_t(n_));  // one cascade
  propagateRange_.local[0] = size_t(n_ / lanes_);
  propagateRange_.local[1] = propagateRange_.local[2] = 1;
}

// The grids hold each SH coefficient times its basis constant (lpv.cl LPV_UNIT0, LPV_UNIT1: Y0 and
// Y1/√5, in the kernel's float arithmetic); the host reads and writes plain coefficients.
static const float kGridUnit[4] = {GI_SH_Y0, GI_SH_Y1 * 0.4472135955f, GI_SH_Y1 * 0.4472135955f,
                                   GI_SH_Y1 * 0.4472135955f};

size_t LpvVolume::gridOffset(int k, int p, size_t cell) const {
  size_t n = size_t(n_), x = cell % n, y = cell / n % n, z = cell / (n * n);
  size_t slice = 12 * n * n + kSkew;
  return kPad + (size_t(k) * n + z) * slice + y * 12 * n + size_t(p) * n + x;
}

uint64_t LpvVolume::bytes() const {
  return layout_.bytes() + gridAcc_.bytes() + geometryAcc_.bytes() + grids_[0].bytes() + grids_[1].bytes() +
         accumulated_.bytes() + geometry_.bytes() + faceGeometry_.bytes() + faceFactors_.bytes() + lookupGrid_.bytes() +
         (bounces_ ? albedoAcc_.bytes() + faceAlbedo_.bytes() : 0) +
         (lookupImage_.get() ? lookupImage_.bytes() : 0);
}

void LpvVolume::begin(const std::vector<LpvCascade>& layout, float injectionFixedScale) {
  if (int(layout.size()) != cascades_) throw Error("lpv: layout has the wrong number of cascades");
  std::vector<glm::vec4> packed;
  for (const LpvCascade& c : layout) packed.emplace_back(c.origin, c.cell);
  ctx_.write(layout_, packed.data(), packed.size() * sizeof(glm::vec4));
  injectionScale_ = injectionFixedScale;
  ctx_.fill(gridAcc_, int64_t(0));
  ctx_.fill(geometryAcc_, int64_t(0));
  if (bounces_) ctx_.fill(albedoAcc_, int64_t(0));
  current_ = 0;
  lookupGridCurrent_ = false;
}

void LpvVolume::inject(const cl::Buffer& position, const cl::Buffer& normal, const cl::Buffer& flux, int res,
                       int block, float bias) {
  int merged = res / block;
  inject_.args(position, normal, flux, res, block, bias, layout_, injectionScale_, gridAcc_);
  size_t runs = size_t(merged + kRunLength - 1) / kRunLength;
  ctx_.launch(inject_, cl::NDRange::d2(runs, size_t(merged)), "lpv: inject");
}

void LpvVolume::addGeometryRsm(const GiView& view, const cl::Buffer& position, const cl::Buffer& normal, int res) {
  geometryRsm_.args(view, position, normal, res, layout_, kGeometryFixedScale, geometryAcc_);
  size_t runs = size_t(res + kRunLength - 1) / kRunLength;
  ctx_.launch(geometryRsm_, cl::NDRange::d2(runs, size_t(res)), "lpv: geometry (rsm)");
}

void LpvVolume::addGeometryCamera(const GBuffer& g) {
  cl::Buffer none;  // without bounces the kernel gets null albedo pointers and skips them
  geometryCamera_.args(g.view, g.position, g.geoNormal, g.width, g.height, layout_, kGeometryFixedScale,
                       geometryAcc_, bounces_ ? g.albedo : none, bounces_ ? albedoAcc_ : none);
  size_t runs = size_t(g.width + kRunLength - 1) / kRunLength;
  ctx_.launch(geometryCamera_, cl::NDRange::d2(runs, size_t(g.height)), "lpv: geometry (camera)");
}

void LpvVolume::resolve(bool geometry) {
  resolveInjection_.args(gridAcc_, 1.0f / injectionScale_, grids_[0], accumulated_);
  ctx_.launch(resolveInjection_, cl::NDRange::d3(size_t(n_ / lanes_), size_t(n_), size_t(n_) * 3 * cascades_),
              "lpv: resolve");
  current_ = 0;
  lookupGridCurrent_ = false;
  if (!geometry) return;
  resolveGeometry_.args(geometryAcc_, 1.0f / kGeometryFixedScale, geometry_);
  size_t nodeGroups = (nodesPerGrid() + lanes_ - 1) / lanes_;  // LPV_LANES nodes per work-item
  ctx_.launch(resolveGeometry_, cl::NDRange::d2(cl::roundUp(nodeGroups, 16), size_t(cascades_), 16, 1),
              "lpv: resolve");
}

void LpvVolume::setInjected(const std::vector<glm::vec4>& coefficients) {
  size_t cells = cellsPerGrid();
  if (coefficients.size() != cells * 3 * cascades_) throw Error("lpv: injected grid of the wrong size");
  std::vector<float> planes(gridFloats(), 0.0f);
  for (size_t i = 0; i < coefficients.size(); ++i) {  // i = (k·3 + ch)·cells + cell
    size_t kch = i / cells, cell = i % cells;
    for (int c = 0; c < 4; ++c)
      planes[gridOffset(int(kch / 3), int(kch % 3) * 4 + c, cell)] = coefficients[i][c] * kGridUnit[c];
  }
  ctx_.write(grids_[0], planes.data(), planes.size() * sizeof(float));
  ctx_.write(accumulated_, planes.data(), planes.size() * sizeof(float));
  current_ = 0;
  lookupGridCurrent_ = false;
}

std::vector<glm::vec4> LpvVolume::readGrid(const cl::Buffer& b) {
  std::vector<float> planes = ctx_.download<float>(b);
  size_t cells = cellsPerGrid();
  std::vector<glm::vec4> out(cells * 3 * cascades_);
  for (size_t i = 0; i < out.size(); ++i) {
    size_t kch = i / cells, cell = i % cells;
    for (int c = 0; c < 4; ++c) out[i][c] = planes[gridOffset(int(kch / 3), int(kch % 3) * 4 + c, cell)] / kGridUnit[c];
  }
  return out;
}

std::vector<glm::vec4> LpvVolume::readGeometry() {
  std::vector<float> planes = ctx_.download<float>(geometry_);
  size_t nodes = nodesPerGrid();
  std::vector<glm::vec4> out(nodes * cascades_);
  for (size_t i = 0; i < out.size(); ++i)
    for (int c = 0; c < 4; ++c) out[i][c] = planes[((i / nodes) * 4 + c) * nodes + i % nodes];
  return out;
}

void LpvVolume::setGeometry(const std::vector<glm::vec4>& nodeValues) {
  size_t nodes = nodesPerGrid();
  if (nodeValues.size() != nodes * cascades_) throw Error("lpv: geometry volume of the wrong size");
  std::vector<float> planes(nodes * 4 * cascades_);
  for (size_t i = 0; i < nodeValues.size(); ++i)
    for (int c = 0; c < 4; ++c) planes[((i / nodes) * 4 + c) * nodes + i % nodes] = nodeValues[i][c];
  ctx_.write(geometry_, planes.data(), planes.size() * sizeof(float));
}

void LpvVolume::setSurfelAlbedo(const std::vector<glm::vec4>& nodeValues) {
  size_t nodes = nodesPerGrid();
  if (!bounces_) throw Error("lpv: surfel albedo set on a volume without bounces");
  if (nodeValues.size() != nodes * cascades_) throw Error("lpv: surfel albedo of the wrong size");
  std::vector<int64_t> sums(nodeValues.size() * 4);
  for (size_t i = 0; i < nodeValues.size(); ++i)
    for (int c = 0; c < 4; ++c) sums[i * 4 + c] = std::llrint(double(nodeValues[i][c]) * kGeometryFixedScale);
  ctx_.write(albedoAcc_, sums.data(), sums.size() * sizeof(int64_t));
}

void LpvVolume::propagate(int iterations, bool blocking) {
  if (blocking && iterations > 1) {
    faceGeometryKernel_.args(geometry_, faceGeometry_);
    ctx_.launch(faceGeometryKernel_, cl::NDRange::d3(size_t(n_ / lanes_), size_t(n_), size_t(n_) * 3 * cascades_),
                "lpv: propagate");
    faceFactorsKernel_.args(faceGeometry_, faceFactors_);
    ctx_.launch(faceFactorsKernel_, cl::NDRange::d3(size_t(n_ / lanes_), size_t(n_), size_t(n_) * cascades_),
                "lpv: propagate");
    if (bounces_) {
      faceAlbedoKernel_.args(albedoAcc_, faceAlbedo_);
      ctx_.launch(faceAlbedoKernel_, cl::NDRange::d3(size_t(n_ / lanes_), size_t(n_), size_t(n_) * 3 * cascades_),
                  "lpv: bounces");
    }
  }
  bool reflect = bounces_ && blocking;
  // Cascade after cascade, all steps of one before the next: a step touches 6 MB per 32³ cascade
  // (two grids, the accumulated grid, the face potentials), which the last-level cache holds for
  // one cascade but not for three (all cascades in one launch per step: 0.92 instead of 0.50–0.58 ms
  // per step and cascade on the idle machine). The cascades do not interact.
  // The accumulated grid already holds the source grid of the first step; each step's result is
  // added to it by the next step together with that step's own, or by the step itself when it is
  // the last, which also writes the lookup grid (lpv.cl LPV_ADD_*, LPV_WRITE_LOOKUP).
  const int addThis = 1, addSource = 2, writeLookup = 4;
  int start = current_;
  for (int k = 0; k < cascades_; ++k) {
    current_ = start;
    for (int i = 0; i < iterations; ++i) {
      bool last = i + 1 == iterations;
      int accumulate = (i % 2 ? addThis | addSource : last ? addThis : 0) | (last ? writeLookup : 0);
      // The first step leaves blocking out: the VPLs sit next to the surfaces they were lit on.
      if (blocking && i > 0) {
        propagateBlocked_.args(grids_[current_], grids_[1 - current_], accumulated_, faceFactors_, k, accumulate,
                               layout_, lookupGrid_);
        ctx_.launch(propagateBlocked_, propagateRange_, "lpv: propagate");
        if (reflect) {  // into the step's result (and the accumulated grid where the step added it)
          reflectBlocked_.args(grids_[current_], grids_[1 - current_], accumulated_, faceFactors_, faceGeometry_,
                               faceAlbedo_, k, accumulate & addThis);
          ctx_.launch(reflectBlocked_, propagateRange_, "lpv: bounces");
        }
      } else {
        propagateOpen_.args(grids_[current_], grids_[1 - current_], accumulated_, k, accumulate, layout_,
                            lookupGrid_);
        ctx_.launch(propagateOpen_, propagateRange_, "lpv: propagate");
      }
      current_ = 1 - current_;
    }
  }
  // With reflection the last step's lookup grid lacks that step's reflected light: lookup()
  // converts the accumulated grid again.
  if (iterations > 0) lookupGridCurrent_ = !(reflect && iterations > 1);
}

void LpvVolume::lookup(const GBuffer& g, bool blendCascades, cl::Buffer& out, bool damping) {
  if (!lookupGridCurrent_) {  // the grid was set or resolved after the last propagation step
    toLookupGrid_.args(accumulated_, layout_, lookupGrid_);
    ctx_.launch(toLookupGrid_, cl::NDRange::d3(size_t(n_ / lanes_), size_t(n_), size_t(n_) * 3 * cascades_),
                "lpv: lookup grid");
    lookupGridCurrent_ = true;
  }
  if (storage_ == LpvLookupStorage::Image) {
    lookupImage_.copy(ctx_, lookupGrid_);
    lookup_.args(g.width, g.height, g.position, g.geoNormal, g.normal, g.albedo, layout_, int(blendCascades),
                 int(damping), lookupImage_.get(), out);
  } else {
    lookup_.args(g.width, g.height, g.position, g.geoNormal, g.normal, g.albedo, layout_, int(blendCascades),
                 int(damping), lookupGrid_, out);
  }
  size_t groups = (size_t(g.width) + vw_ - 1) / vw_;  // GI_VW pixels per work-item
  ctx_.launch(lookup_, cl::NDRange::d2(cl::roundUp(groups, 16), cl::roundUp(g.height, 4), 16, 4), "lpv: lookup");
}

}  // namespace gi
