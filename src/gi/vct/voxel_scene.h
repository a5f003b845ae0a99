// The voxel representation of voxel cone tracing (ALGORITHMS.md §5): a cubic grid over the scene
// bounds, its voxelization (kernels/gi/vct/voxelize.cl), light injection from the frame's shadow
// maps and the isotropic or anisotropic mip chain (kernels/gi/vct/voxel_light.cl).
//
//   VoxelScene vs(ctx, scene, 128);
//   vs.voxelize(deviceScene);                     // once for static geometry, or every frame
//   vs.inject(deviceScene, shadowMaps);           // every frame: level 0 radiance
//   vs.buildMips(anisotropic);                    // levels 1 … log2 N (directional voxels: and level 0's 6 volumes)
//   vs.buildShVoxels(anisotropic, ShLobe::Hemisphere);  // optional SH voxels (after buildMips)
#pragma once
#include <cstdint>
#include <string>

#include "cl/runtime.h"
#include "kernels/gi/vct/voxel_types.h"
#include "raster/gbuffer.h"
#include "scene/device_scene.h"
#include "scene/scene.h"

namespace gi {

// Cubic grid of resolution N (power of two, 32…256) around `bounds`, with one empty voxel of margin
// on every side so that geometry on the bounds lies inside.
GiVoxelGrid fitVoxelGrid(const Bounds& bounds, int resolution);

// The directional lobe of SH voxels (voxel_types.h): the surface's radiance on its front
// hemisphere, or ten Brug's clamped cosine.
enum class ShLobe { Hemisphere, Cosine };

class VoxelScene {
public:
  // Directional voxels (vct.voxels=directional / directional_slab; kernels/gi/vct/voxel_grid.h,
  // vox_directional_coverage): level 0 also has 6 directional volumes, from the voxels' normals,
  // each voxel seen as a thin plane or as a slab open only to cones leaving through its front;
  // anisotropic mips only.
  enum class Directional { Off, Plane, Slab };
  VoxelScene(cl::Context& ctx, const Scene& scene, int resolution, Directional directional = Directional::Off);

  const GiVoxelGrid& grid() const { return grid_; }
  int resolution() const { return grid_.resolution; }
  uint64_t voxelCount() const { return uint64_t(grid_.resolution) * grid_.resolution * grid_.resolution; }
  bool directional() const { return directional_ != Directional::Off; }
  Directional directionalKind() const { return directional_; }

  // Clears the accumulators and voxelizes every triangle. Clearing zeroes only the voxels of the
  // previous voxelization's occupied list (accumulators and level 0 of iso): level 0 outside that
  // list must be zero, as voxelize/inject leave it (a caller writing iso itself must not voxelize
  // into the same VoxelScene afterwards).
  // Lanes: the triangles' voxel columns spread over SIMD lanes (vct_voxelize); Trianglewise: one
  // work-item per triangle (vct_voxelize_trianglewise, the tests' reference). Same accumulators.
  enum class VoxelizeKernel { Lanes, Trianglewise };
  void voxelize(const DeviceScene& scene, VoxelizeKernel kernel = VoxelizeKernel::Lanes);
  // Level 0 of the occupied voxels: L = ρ/π·E_direct + L_e (premultiplied by opacity) from the
  // lights and shadow maps; the other voxels stay zero. On CPU devices `cpuItems` work-items share
  // the occupied list in contiguous runs (vct_inject; fewer items = longer runs, for tests).
  static constexpr int kInjectItemsCpu = 64 * 64;  // 64 groups: both cores busy whatever the count
  void inject(const DeviceScene& scene, const ShadowMapSet& shadows, int cpuItems = kInjectItemsCpu);
  // Levels 1 … log2 N from level 0: isotropic (`iso`) or 6 directional volumes (`aniso`). With
  // directional voxels, first level 0's 6 volumes in `aniso` from `iso` and the voxels' normals
  // (anisotropic only: isotropic mips are an error).
  // Level 0 must be zero wherever the occupancy bit is clear (as voxelize/inject/clear leave it):
  // the isotropic level 1 skips the children of parents without an occupied child.
  void buildMips(bool anisotropic);
  // SH voxels (vct.voxels=sh): level 0 from the radiance chain's level 0 and the voxels' normals,
  // then the same mips on the coefficients. Needs buildMips(anisotropic) first (opacity).
  void buildShVoxels(bool anisotropic, ShLobe lobe);
  void projectSh(ShLobe lobe);        // level 0 only
  void buildShMips(bool anisotropic);  // levels ≥ 1 only
  // The empty-space map of the specular march (kernels/gi/vct/voxel_light.cl, vct_empty_space):
  // one byte per cell of every level, 0 where the cells i … i + 1 of the level are exactly empty in
  // every chain. From the occupancy bits (buildMips' contract); valid for the mips built from the
  // current level 0 (build it after the last buildMips of a frame, or any time after voxelize: it
  // depends on the bits only).
  void buildEmptySpace();
  const cl::Buffer& emptySpace() const { return emptySpace_; }  // allocated on first use

  const cl::Buffer& accumulators() const { return acc_; }  // GI_VOX_RECORD words per voxel (voxel_types.h)
  cl::Buffer& iso() { return iso_; }      // float4 per voxel, all isotropic levels (voxel_grid.h)
  cl::Buffer& occupancy() { return occupancy_; }  // bit v & 31 of word v >> 5: voxel v voxelized
  cl::Buffer& aniso() { return aniso_; }  // float4, 6 volumes per level ≥ 1 (directional: ≥ 0; allocated on first use)
  cl::Buffer& sh() { return sh_; }            // 3 float4 per voxel of iso (allocated on first use)
  cl::Buffer& shAniso() { return shAniso_; }  // 3 float4 per voxel of aniso (allocated on first use)
  uint64_t bytes() const { return acc_.bytes() + occupied_.bytes() + occupancy_.bytes() + spanCounts_.bytes() + iso_.bytes() + aniso_.bytes() + sh_.bytes() + shAniso_.bytes() + emptySpace_.bytes() + occupiedLevels_.bytes() + triangleSetup_.bytes() + columnStart_.bytes(); }
  // Device memory of a configuration: accumulators + isotropic chain (+ directional volumes)
  // (+ SH coefficients of the chains used).
  // Not counted there: the triangle setup of the voxelization (scene-dependent) and the empty-space
  // map, built only for the continuous specular march with anisotropic mips (emptySpaceBytesFor).
  static uint64_t bytesFor(int resolution, bool anisotropic, bool sh = false, bool directional = false);
  static uint64_t emptySpaceBytesFor(int resolution);  // the map and its occupied-levels scratch

  // Every chain (iso_, aniso_ and their SH copies) ends with this many zero records: the cone march
  // reads the tap pair along x as two adjacent records, which for the last (1-voxel) volume reaches
  // one record past the chain (kernels/gi/vct/cone_lanes.h, vox_trilinear_lanes; weight 0).
  static constexpr uint64_t kChainEndRecords = 1;

private:
  cl::Context& ctx_;
  GiVoxelGrid grid_{};
  cl::Program voxelizeProgram_, lightProgram_;
  int injectLanes_ = 1;  // GI_VW of lightProgram_ (occupied voxels per vct_inject block)
  Directional directional_ = Directional::Off;
  cl::Kernel clear_, occupancyCount_, scan_, occupancyList_, triangleColumns_, voxelize_, voxelizeTrianglewise_, inject_, mipIso_, mipIsoFirst_, mipAnisoFirst_, mipAniso_, directionalLevel0_, shProject_, shMipIso_, shMipAniso_,
      occupiedFirst_, occupiedLevel_, emptySpaceFirst_, emptySpaceLevel_;
  // occupied_: the voxels the last voxelization touched (count in occupiedCount_), in increasing
  // order, built from their bits in occupancy_ (1 bit per voxel) through per-span counts.
  static constexpr uint64_t kOccupancySpanVoxels = 64 * 32;  // GI_VOX_SPAN_WORDS words (voxelize.cl)
  uint32_t occupancySpans() const;
  // Per triangle (allocated on the first voxelization): its voxel setup (uint4) and the first of
  // its voxel columns in the list of all columns (columnTotal_: their count).
  cl::Buffer triangleSetup_, columnStart_, columnTotal_;
  // Work-items of vct_voxelize (each loops over every kVoxelizeWorkItems-th group of columns):
  // enough work-groups of 64 for every core.
  static constexpr uint32_t kVoxelizeWorkItems = 8192;
  static constexpr uint32_t kClearEntriesPerItem = 32;  // GI_VOX_CLEAR_ENTRIES (voxelize.cl)
  cl::Buffer instanceEmits_, acc_, occupied_, occupiedCount_, occupancy_, spanCounts_, iso_, aniso_, sh_, shAniso_;
  // The empty-space map (bytes, levels 0 …) and its scratch: per cell of levels ≥ 1, any voxel occupied.
  cl::Buffer emptySpace_, occupiedLevels_;

  // The 6 directional volumes of levels ≥ 1 (directional voxels: ≥ 0), float4 each, and the
  // chain's zero end record.
  uint64_t anisoBytes() const;
};

}  // namespace gi
