// Addressing and filtered lookups of the voxel radiance mips (ALGORITHMS.md §5).
//
// Storage (float4 = alpha-premultiplied radiance rgb · α, opacity α):
//   `iso`  : the isotropic chain, level 0 (N³) then level 1 ((N/2)³) … down to 1³, consecutive;
//   `aniso`: levels 1 … levels−1, each as 6 directional volumes (+x, −x, +y, −y, +z, −z), where
//            volume "+x" is what a cone travelling along +x sees: the children composited front
//            to back in increasing x. Level 0 is shared with `iso` (a voxel is isotropic).
// Voxels outside the grid are empty (zero).
#pragma once
#include "common/math.h"
#include "gi/vct/voxel_types.h"

inline size_t vox_level_offset(int N, int level) {
  size_t off = 0;
  for (int l = 0; l < level; ++l) {
    size_t n = (size_t)(N >> l);
    off += n * n * n;
  }
  return off;
}

// First voxel of directional volume `dir` (0..5) of level `level` ≥ 1 in `aniso`.
inline size_t vox_aniso_offset(int N, int level, int dir) {
  size_t n = (size_t)(N >> level);
  return 6 * (vox_level_offset(N, level) - (size_t)N * N * N) + (size_t)dir * n * n * n;
}

// Trilinear lookup of one volume of n³ voxels at p, given in level-0 voxel units from the grid
// corner; `scale` = 1 / 2^level.
inline float4 vox_trilinear(global const float4* vol, int n, float3 p, float scale) {
  float3 u = p * scale - 0.5f;
  float3 fl = floor(u);
  float3 f = u - fl;
  int3 i0 = convert_int3(fl);
  float4 acc = (float4)(0.0f);
  for (int dz = 0; dz < 2; ++dz) {
    int z = i0.z + dz;
    if (z < 0 || z >= n) continue;
    float wz = dz ? f.z : 1.0f - f.z;
    for (int dy = 0; dy < 2; ++dy) {
      int y = i0.y + dy;
      if (y < 0 || y >= n) continue;
      float wy = wz * (dy ? f.y : 1.0f - f.y);
      for (int dx = 0; dx < 2; ++dx) {
        int x = i0.x + dx;
        if (x < 0 || x >= n) continue;
        float w = wy * (dx ? f.x : 1.0f - f.x);
        acc += w * vol[((size_t)z * n + y) * n + x];
      }
    }
  }
  return acc;
}

// One level of the chain seen along unit direction d: the isotropic volume, or (anisotropic,
// level ≥ 1) the three directional volumes facing d weighted by d² per axis.
inline float4 vox_level_sample(global const float4* iso, global const float4* aniso, int N, int level, float3 p,
                               float3 d, int anisotropic) {
  int n = N >> level;
  float scale = 1.0f / (float)(1 << level);
  if (!anisotropic || level == 0) return vox_trilinear(iso + vox_level_offset(N, level), n, p, scale);
  float3 w = d * d;
  float4 cx = vox_trilinear(aniso + vox_aniso_offset(N, level, d.x >= 0.0f ? 0 : 1), n, p, scale);
  float4 cy = vox_trilinear(aniso + vox_aniso_offset(N, level, d.y >= 0.0f ? 2 : 3), n, p, scale);
  float4 cz = vox_trilinear(aniso + vox_aniso_offset(N, level, d.z >= 0.0f ? 4 : 5), n, p, scale);
  return w.x * cx + w.y * cy + w.z * cz;
}

// Quadrilinear lookup at fractional level (clamped to the chain).
inline float4 vox_sample(global const float4* iso, global const float4* aniso, int N, int levels, float3 p, float3 d,
                         float level, int anisotropic) {
  level = clamp(level, 0.0f, (float)(levels - 1));
  int l0 = (int)floor(level);
  float f = level - (float)l0;
  float4 c = vox_level_sample(iso, aniso, N, l0, p, d, anisotropic);
  if (f > 0.0f && l0 + 1 < levels)
    c = mix(c, vox_level_sample(iso, aniso, N, l0 + 1, p, d, anisotropic), f);
  return c;
}

// A voxel's surface from the voxelization accumulators (voxel_types.h): opacity α = mean coverage
// of the triangles touching it; albedo, emission, normal = their opacity-weighted means; position =
// the mean of their points nearest the voxel centre. Only for voxels with opacity > 0.
typedef struct {
  float3 albedo, emission, normal, position;
  float alpha;
  int twoSided;  // |mean normal| < 0.5: normals cancel (both sides of thin geometry)
} VoxelSurface;

inline VoxelSurface vox_resolve(GiVoxelGrid grid, global const uint* acc, size_t v) {
  int N = grid.resolution;
  size_t plane = (size_t)N * N * N;
  global const int* iacc = (global const int*)acc;
  VoxelSurface r;
  float weight = (float)acc[GI_VOX_OPACITY * plane + v] * (1.0f / GI_VOX_UNIT);  // Σ opacity
  r.alpha = weight / (float)acc[GI_VOX_COUNT * plane + v];
  float invW = 1.0f / weight;
  r.albedo = (float3)(acc[GI_VOX_ALBEDO * plane + v], acc[(GI_VOX_ALBEDO + 1) * plane + v],
                      acc[(GI_VOX_ALBEDO + 2) * plane + v]) * (invW / GI_VOX_UNIT);
  r.emission = (float3)(acc[GI_VOX_EMISSION * plane + v], acc[(GI_VOX_EMISSION + 1) * plane + v],
                        acc[(GI_VOX_EMISSION + 2) * plane + v]) * (invW / GI_VOX_EMISSION_UNIT);
  float3 meanN = (float3)(iacc[GI_VOX_NORMAL * plane + v], iacc[(GI_VOX_NORMAL + 1) * plane + v],
                          iacc[(GI_VOX_NORMAL + 2) * plane + v]) * (invW * 4.0f / GI_VOX_UNIT);
  float3 offset = (float3)(iacc[GI_VOX_OFFSET * plane + v], iacc[(GI_VOX_OFFSET + 1) * plane + v],
                           iacc[(GI_VOX_OFFSET + 2) * plane + v]) * (invW * 4.0f / GI_VOX_UNIT);
  int x = (int)(v % (size_t)N), y = (int)((v / (size_t)N) % (size_t)N), z = (int)(v / ((size_t)N * N));
  r.position = vload3(0, grid.origin) + ((float3)((float)x, (float)y, (float)z) + 0.5f + offset) * grid.voxel_size;
  r.twoSided = length(meanN) < 0.5f;
  r.normal = safe_normalize(meanN, (float3)(0.0f, 1.0f, 0.0f));
  return r;
}
