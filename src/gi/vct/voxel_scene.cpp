#include "gi/vct/voxel_scene.h"

#include <algorithm>

#include "cl/gather_width.h"
#include "gi/emitter_flags.h"
#include "util/error.h"

namespace gi {

namespace {

int log2Exact(int n) {
  int l = 0;
  while ((1 << l) < n) ++l;
  return l;
}

}  // namespace

GiVoxelGrid fitVoxelGrid(const Bounds& bounds, int resolution) {
  if (resolution < 32 || resolution > 256 || (resolution & (resolution - 1)) != 0)
    throw Error("vct.resolution = " + std::to_string(resolution) + ": the voxel grid resolution must be a power of two (32, 64, 128 or 256)");
  glm::vec3 e = bounds.valid() ? bounds.extent() : glm::vec3(1.0f);
  float extent = std::max({e.x, e.y, e.z, 1e-6f});
  float voxel = extent / float(resolution - 2);  // one empty voxel of margin on each side
  glm::vec3 origin = (bounds.valid() ? bounds.center() : glm::vec3(0.0f)) - 0.5f * voxel * float(resolution);
  GiVoxelGrid g{};
  g.origin[0] = origin.x;
  g.origin[1] = origin.y;
  g.origin[2] = origin.z;
  g.voxel_size = voxel;
  g.resolution = resolution;
  g.levels = log2Exact(resolution) + 1;
  return g;
}

uint64_t VoxelScene::bytesFor(int resolution, bool anisotropic, bool sh, bool directional) {
  // Accumulator records, the occupied voxel list (4 B per voxel), the occupancy bits and the
  // compaction's span counts.
  uint64_t n = uint64_t(resolution) * resolution * resolution;
  uint64_t bytes = n * (GI_VOX_RECORD + 1) * 4 + n / 8 + n / kOccupancySpanVoxels * 4;
  // Per voxel of a chain: 16 B of radiance and opacity, plus 48 B of SH coefficients.
  uint64_t perVoxel = sh ? 64 : 16;
  for (int l = 0; (resolution >> l) > 0; ++l)
    bytes += (n >> (3 * l)) * perVoxel * (anisotropic && (l > 0 || directional) ? 7 : 1);
  return bytes;
}

// One byte per cell of every level (the map), and one per cell of levels >= 1 (occupied levels).
static uint64_t emptySpaceMapCells(int resolution) {
  uint64_t n = uint64_t(resolution) * resolution * resolution, cells = 0;
  for (int l = 0; (resolution >> l) > 0; ++l) cells += n >> (3 * l);
  return cells;
}

uint64_t VoxelScene::emptySpaceBytesFor(int resolution) {
  uint64_t n = uint64_t(resolution) * resolution * resolution;
  return 2 * emptySpaceMapCells(resolution) - n;
}

uint64_t VoxelScene::anisoBytes() const {
  uint64_t bytes = 0;
  for (int l = directional() ? 0 : 1; l < grid_.levels; ++l) bytes += 6 * (voxelCount() >> (3 * l)) * 16;
  return bytes + kChainEndRecords * 16;
}

VoxelScene::VoxelScene(cl::Context& ctx, const Scene& scene, int resolution, Directional directional)
    : ctx_(ctx), grid_(fitVoxelGrid(scene.bounds, resolution)), directional_(directional) {
  voxelizeProgram_ = ctx.buildProgram("kernels/gi/vct/voxelize.cl", cl::withGatherWidth(ctx));
  clear_ = voxelizeProgram_.kernel("vct_clear_occupied");
  occupancyCount_ = voxelizeProgram_.kernel("vct_occupancy_count");
  scan_ = voxelizeProgram_.kernel("vct_exclusive_scan");
  occupancyList_ = voxelizeProgram_.kernel("vct_occupancy_list");
  triangleColumns_ = voxelizeProgram_.kernel("vct_triangle_columns");
  voxelize_ = voxelizeProgram_.kernel("vct_voxelize");
  voxelizeTrianglewise_ = voxelizeProgram_.kernel("vct_voxelize_trianglewise");
  lightProgram_ = ctx.buildProgram("kernels/gi/vct/voxel_light.cl",
                                   cl::withGatherWidth(ctx, {{"GI_VCT_DIRECTIONAL", directional != Directional::Off ? "1" : "0"}}));
  injectLanes_ = cl::gatherVectorWidth(ctx);
  inject_ = lightProgram_.kernel("vct_inject");
  mipIso_ = lightProgram_.kernel("vct_mip_isotropic");
  mipIsoFirst_ = lightProgram_.kernel("vct_mip_isotropic_first");
  mipAnisoFirst_ = lightProgram_.kernel("vct_mip_anisotropic_first");
  mipAniso_ = lightProgram_.kernel("vct_mip_anisotropic");
  if (directional != Directional::Off) directionalLevel0_ = lightProgram_.kernel("vct_directional_level0");
  shProject_ = lightProgram_.kernel("vct_sh_project");
  shMipIso_ = lightProgram_.kernel("vct_mip_sh_isotropic");
  shMipAniso_ = lightProgram_.kernel("vct_mip_sh_anisotropic");
  occupiedFirst_ = lightProgram_.kernel("vct_occupied_first");
  occupiedLevel_ = lightProgram_.kernel("vct_occupied_level");
  emptySpaceFirst_ = lightProgram_.kernel("vct_empty_space_first");
  emptySpaceLevel_ = lightProgram_.kernel("vct_empty_space");
  instanceEmits_ = ctx.upload(instanceEmissionFlags(scene), "vct instance emission flags");
  uint64_t n = voxelCount();
  uint64_t chain = 0;
  for (int l = 0; l < grid_.levels; ++l) chain += (n >> (3 * l));
  chain += kChainEndRecords;
  ctx.requireAllocation(n * GI_VOX_RECORD * 4, "vct voxelization accumulators (vct.resolution)");
  ctx.requireAllocation(chain * 16, "vct radiance mips (vct.resolution)");
  acc_ = cl::Buffer(ctx, n * GI_VOX_RECORD * 4, CL_MEM_READ_WRITE, "vct voxelization accumulators");
  iso_ = cl::Buffer(ctx, chain * 16, CL_MEM_READ_WRITE, "vct radiance mips");
  occupied_ = cl::Buffer(ctx, n * 4, CL_MEM_READ_WRITE, "vct occupied voxel list");
  occupiedCount_ = cl::Buffer(ctx, 4, CL_MEM_READ_WRITE, "vct occupied voxel count");
  occupancy_ = cl::Buffer(ctx, n / 8, CL_MEM_READ_WRITE, "vct occupancy bits");
  spanCounts_ = cl::Buffer(ctx, occupancySpans() * 4, CL_MEM_READ_WRITE, "vct occupancy span counts");
  // Zero once: from then on each voxelization clears only the voxels it listed (vct_clear_occupied).
  ctx.fill(acc_, uint32_t(0));
  ctx.fill(iso_, 0.0f);
  ctx.fill(occupiedCount_, uint32_t(0));
  ctx.fill(occupancy_, uint32_t(0));
  columnTotal_ = cl::Buffer(ctx, 4, CL_MEM_READ_WRITE, "vct voxel column count");
}

uint32_t VoxelScene::occupancySpans() const { return uint32_t(voxelCount() / kOccupancySpanVoxels); }

void VoxelScene::voxelize(const DeviceScene& scene, VoxelizeKernel kernel) {
  uint32_t n = uint32_t(voxelCount()), spans = occupancySpans();
  clear_.args(occupied_, occupiedCount_, acc_, iso_, occupancy_);
  ctx_.launch(clear_, cl::NDRange::d1(cl::roundUp(n / kClearEntriesPerItem, 64), 64), "vct: clear");
  uint32_t triangles = scene.triangleCount;
  if (triangles > 0 && kernel == VoxelizeKernel::Trianglewise) {
    voxelizeTrianglewise_.args(grid_, scene.positions, scene.normals, scene.uvs, scene.triangles,
                               scene.triangleInstance, scene.materials, scene.textures, scene.texels, instanceEmits_,
                               triangles, acc_, occupancy_);
    ctx_.launch(voxelizeTrianglewise_, cl::NDRange::d1(cl::roundUp(triangles, 64), 64), "vct: voxelize (trianglewise)");
  } else if (triangles > 0) {
    if (triangleSetup_.bytes() < uint64_t(triangles) * 16) {
      triangleSetup_ = cl::Buffer(ctx_, uint64_t(triangles) * 16, CL_MEM_READ_WRITE, "vct triangle voxel setup");
      columnStart_ = cl::Buffer(ctx_, uint64_t(triangles) * 4, CL_MEM_READ_WRITE, "vct triangle first voxel columns");
    }
    triangleColumns_.args(grid_, scene.positions, scene.uvs, scene.triangles, scene.materials, scene.textures, triangles,
                          triangleSetup_, columnStart_);
    ctx_.launch(triangleColumns_, cl::NDRange::d1(cl::roundUp(triangles, 64), 64), "vct: voxelize");
    scan_.args(columnStart_, triangles, columnTotal_);
    ctx_.launch(scan_, cl::NDRange::d1(1, 1), "vct: voxelize");
    // The column count stays on the device: a fixed number of work-items loops over it.
    voxelize_.args(grid_, scene.positions, scene.normals, scene.uvs, scene.triangles, scene.triangleInstance,
                   scene.materials, scene.textures, scene.texels, instanceEmits_, triangles, triangleSetup_, columnStart_,
                   columnTotal_, acc_, occupancy_);
    ctx_.launch(voxelize_, cl::NDRange::d1(kVoxelizeWorkItems, 64), "vct: voxelize");
  }
  occupancyCount_.args(occupancy_, spans, spanCounts_);
  ctx_.launch(occupancyCount_, cl::NDRange::d1(cl::roundUp(spans, 16), 16), "vct: occupied list");
  scan_.args(spanCounts_, spans, occupiedCount_);
  ctx_.launch(scan_, cl::NDRange::d1(1, 1), "vct: occupied list");
  occupancyList_.args(occupancy_, spanCounts_, spans, occupied_);
  ctx_.launch(occupancyList_, cl::NDRange::d1(cl::roundUp(spans, 16), 16), "vct: occupied list");
}

void VoxelScene::inject(const DeviceScene& scene, const ShadowMapSet& shadows, int cpuItems) {
  uint32_t n = uint32_t(voxelCount());
  inject_.args(grid_, acc_, occupied_, occupiedCount_, scene.lights, int(scene.lightCount), shadows.viewTable, shadows.offsetTable,
               shadows.depths, iso_);
  // CPU (GI_VW > 1): a fixed number of work-items, each a run of the list (vct_inject); GPU: one
  // block of the list per item, enough items for any count.
  if (cpuItems < 1) throw Error("VoxelScene::inject: cpuItems = " + std::to_string(cpuItems) + ", expected >= 1");
  size_t items = injectLanes_ > 1 ? size_t(cpuItems) : (n + injectLanes_ - 1) / injectLanes_;
  size_t group = std::min<size_t>(items, 64);
  ctx_.launch(inject_, cl::NDRange::d1(cl::roundUp(items, group), group), "vct: inject");
}

void VoxelScene::buildMips(bool anisotropic) {
  int N = grid_.resolution;
  if (directional() && !anisotropic)
    throw Error("vct.voxels=directional(_slab) needs vct.mips=anisotropic (the directional volumes are anisotropic mips)");
  if (anisotropic && !aniso_) {
    ctx_.requireAllocation(anisoBytes(), "vct anisotropic mips (vct.resolution)");
    aniso_ = cl::Buffer(ctx_, anisoBytes(), CL_MEM_READ_WRITE, "vct anisotropic mips");
    ctx_.fill(aniso_, 0.0f);  // the end record stays 0
  }
  if (directional()) {
    directionalLevel0_.args(grid_, occupancy_, acc_, iso_, int(directional_ == Directional::Slab), aniso_);
    ctx_.launch(directionalLevel0_, cl::NDRange::d1(cl::roundUp(voxelCount(), 64), 64), "vct: directional level 0");
  }
  for (int l = 1; l < grid_.levels; ++l) {
    size_t cells = voxelCount() >> (3 * l);
    if (anisotropic && l == 1 && !directional()) {
      mipAnisoFirst_.args(N, iso_, aniso_);
      ctx_.launch(mipAnisoFirst_, cl::NDRange::d1(cl::roundUp(cells, 64), 64), "vct: mips (anisotropic)");
    } else if (anisotropic) {
      mipAniso_.args(N, l, aniso_);
      ctx_.launch(mipAniso_, cl::NDRange::d1(cl::roundUp(cells, 64), 64), "vct: mips (anisotropic)");
    } else if (l == 1 && injectLanes_ > 1 && N >= 32) {
      // CPU: parents without an occupied child written as 0 without reading level 0 (which is 0
      // wherever the occupancy bit is clear: buildMips' contract, voxel_scene.h).
      mipIsoFirst_.args(N, occupancy_, iso_);
      ctx_.launch(mipIsoFirst_, cl::NDRange::d1(cl::roundUp(cells / 16, 16), 16), "vct: mips (isotropic)");
    } else {
      mipIso_.args(N, l, iso_);
      ctx_.launch(mipIso_, cl::NDRange::d1(cl::roundUp(cells, 64), 64), "vct: mips (isotropic)");
    }
  }
}

void VoxelScene::buildEmptySpace() {
  int N = grid_.resolution;
  uint64_t n = voxelCount(), cells = emptySpaceMapCells(N);
  if (!emptySpace_) {
    ctx_.requireAllocation(emptySpaceBytesFor(N), "vct empty-space map (vct.resolution)");
    emptySpace_ = cl::Buffer(ctx_, cells, CL_MEM_READ_WRITE, "vct empty-space map");
    occupiedLevels_ = cl::Buffer(ctx_, std::max<uint64_t>(cells - n, 1), CL_MEM_READ_WRITE, "vct occupied levels");
  }
  uint64_t words = n / 32;  // N ≥ 32: whole words per row
  emptySpaceFirst_.args(N, occupancy_, emptySpace_);
  ctx_.launch(emptySpaceFirst_, cl::NDRange::d1(cl::roundUp(words, 64), 64), "vct: empty space");
  for (int l = 1; l < grid_.levels; ++l) {
    uint64_t levelCells = n >> (3 * l);
    if (l == 1) {
      occupiedFirst_.args(N, occupancy_, occupiedLevels_);
      ctx_.launch(occupiedFirst_, cl::NDRange::d1(cl::roundUp(levelCells, 64), 64), "vct: empty space");
    } else {
      occupiedLevel_.args(N, l, occupiedLevels_);
      ctx_.launch(occupiedLevel_, cl::NDRange::d1(cl::roundUp(levelCells, 64), 64), "vct: empty space");
    }
    emptySpaceLevel_.args(N, l, occupiedLevels_, emptySpace_);
    ctx_.launch(emptySpaceLevel_, cl::NDRange::d1(cl::roundUp(levelCells, 64), 64), "vct: empty space");
  }
}

void VoxelScene::buildShVoxels(bool anisotropic, ShLobe lobe) {
  projectSh(lobe);
  buildShMips(anisotropic);
}

void VoxelScene::projectSh(ShLobe lobe) {
  if (!sh_) {
    uint64_t bytes = 3 * iso_.bytes();
    ctx_.requireAllocation(bytes, "vct SH voxels (vct.voxels=sh, vct.resolution)");
    sh_ = cl::Buffer(ctx_, bytes, CL_MEM_READ_WRITE, "vct SH voxels");
    ctx_.fill(sh_, 0.0f);  // the end records stay 0
  }
  cl_float2 k = lobe == ShLobe::Hemisphere ? cl_float2{{GI_VCT_SH_HEMISPHERE0, GI_VCT_SH_HEMISPHERE1}}
                                           : cl_float2{{GI_VCT_SH_COSINE0, GI_VCT_SH_COSINE1}};
  uint32_t n = uint32_t(voxelCount());
  shProject_.args(grid_, acc_, iso_, k, sh_);
  ctx_.launch(shProject_, cl::NDRange::d1(cl::roundUp(n, 256), 256), "vct: SH project");
}

void VoxelScene::buildShMips(bool anisotropic) {
  int N = grid_.resolution;
  if (anisotropic && !shAniso_) {
    ctx_.requireAllocation(3 * anisoBytes(), "vct anisotropic SH voxels (vct.voxels=sh, vct.resolution)");
    shAniso_ = cl::Buffer(ctx_, 3 * anisoBytes(), CL_MEM_READ_WRITE, "vct anisotropic SH voxels");
    ctx_.fill(shAniso_, 0.0f);  // the end records stay 0
  }
  for (int l = 1; l < grid_.levels; ++l) {
    size_t cells = voxelCount() >> (3 * l);
    if (anisotropic) {
      shMipAniso_.args(N, l, iso_, aniso_, sh_, shAniso_);
      ctx_.launch(shMipAniso_, cl::NDRange::d1(cl::roundUp(6 * cells, 64), 64), "vct: SH mips (anisotropic)");
    } else {
      shMipIso_.args(N, l, sh_);
      ctx_.launch(shMipIso_, cl::NDRange::d1(cl::roundUp(cells, 64), 64), "vct: SH mips (isotropic)");
    }
  }
}

}  // namespace gi
