// Addressing and filtered lookups of the voxel radiance mips (ALGORITHMS.md §5).
//
// Storage (float4 = alpha-premultiplied radiance rgb · α, opacity α):
//   `iso`  : the isotropic chain, level 0 (N³) then level 1 ((N/2)³) … down to 1³, consecutive;
//   `aniso`: levels 1 … levels−1, each as 6 directional volumes (+x, −x, +y, −y, +z, −z), where
//            volume "+x" is what a cone travelling along +x sees: the children composited front
//            to back in increasing x. Level 0 is shared with `iso` (a voxel is isotropic), except
//            with directional voxels (GI_VCT_DIRECTIONAL = 1, vct.voxels=directional): then
//            `aniso` starts with 6 directional volumes of level 0 (vox_directional_coverage),
//            and every level of the chain a cone reads is directional.
//   SH voxels (vct.voxels=sh): the same two layouts with 3 float4 per voxel (VoxelMips below).
// Voxels outside the grid are empty (zero).
#pragma once
#include "common/math.h"
#include "common/sh.h"
#include "gi/vct/voxel_types.h"

// (x, y, z) of cell v of a cube of n³ cells, n a power of two: shifts and masks instead of 64-bit
// divisions (v < 2^24 for n ≤ 256).
inline int3 vox_cell(size_t v, int n) {
  int s = 31 - clz(n);
  uint u = (uint)v, m = (uint)n - 1u;
  return (int3)((int)(u & m), (int)((u >> s) & m), (int)(u >> (2 * s)));
}

// First voxel of level `level` in `iso`: Σ_{l<level} (N >> l)³ = 8·(N³ − n³)/7, n = N >> level (closed
// form, no loop: a kernel without loops is vectorized across work-items by PoCL).
inline size_t vox_level_offset(int N, int level) {
  size_t n = (size_t)(N >> level), N3 = (size_t)N * N * N;
  return 8 * (N3 - n * n * n) / 7;
}

#ifndef GI_VCT_DIRECTIONAL
#define GI_VCT_DIRECTIONAL 0
#endif
// The first level with directional volumes in `aniso`: 1, or 0 with directional voxels.
#define GI_VCT_FIRST_DIRECTIONAL_LEVEL (GI_VCT_DIRECTIONAL ? 0 : 1)

// First voxel of directional volume `dir` (0..5) of level `level` ≥ GI_VCT_FIRST_DIRECTIONAL_LEVEL
// in `aniso` (vox_level_offset(N, 1) = N³).
inline size_t vox_aniso_offset(int N, int level, int dir) {
  size_t n = (size_t)(N >> level);
  return 6 * (vox_level_offset(N, level) - vox_level_offset(N, GI_VCT_FIRST_DIRECTIONAL_LEVEL)) +
         (size_t)dir * n * n * n;
}

// Directional voxels (vct.voxels=directional / directional_slab): the fraction of a level-0
// voxel's premultiplied radiance and opacity (L·α, α) that a cone travelling along axis direction
// `dir` (0..5 = +x, −x, +y, −y, +z, −z) sees, for a voxel whose surface has unit mean normal n.
// facing = −n·e / max_i |n_i|: 1 where the surface's front faces the cone head-on along its
// dominant axis, 0 edge-on, −1 where the cone leaves straight through the front (it started on or
// behind the surface).
//   plane (slab = 0): the voxel holds a thin plane; it covers |n·e| / max_i |n_i| of the voxel's
//     cross-section seen along e (1 along its dominant axis, 0 edge-on), and only its front is
//     seen: coverage clamp(facing, 0, 1). A cone entering the front is blocked and sees the
//     surface's radiance (which leaves the surface on its front side only); a cone leaving through
//     the front, or along the plane, passes.
//   slab (slab = 1): the voxel is the one-voxel slab of the conservative voxelization, opaque and
//     lit from every side as an isotropic voxel, except that the cone leaving through its front
//     passes: coverage clamp(1 + facing, 0, 1) (0 for a cone leaving along the dominant axis).
// Voxels whose normals cancel (two-sided thin geometry, VoxelSurface.twoSided) are seen whole from
// every direction (coverage 1), as isotropic voxels are.
inline float vox_directional_coverage(float3 n, int twoSided, int slab, int dir) {
  if (twoSided) return 1.0f;
  float axisN = dir < 2 ? n.x : (dir < 4 ? n.y : n.z);
  float dominant = fmax(fabs(n.x), fmax(fabs(n.y), fabs(n.z)));
  float facing = ((dir & 1) ? axisN : -axisN) / dominant;
  return clamp(slab ? 1.0f + facing : facing, 0.0f, 1.0f);
}

// The mip chains a cone reads, gathered into one value for the march (built by the kernels).
//   sh, shAniso: SH voxels (GI_VCT_SH = 1, voxel_types.h), 3 float4 (R, G, B coefficients) per
//   voxel, in the layout of iso / aniso (voxel i at [3i, 3i + 2]); opacity stays in iso / aniso.
typedef struct {
  global const float4* iso;
  global const float4* aniso;    // unread unless anisotropic
  global const float4* sh;       // unread unless GI_VCT_SH
  global const float4* shAniso;  // unread unless GI_VCT_SH and anisotropic
  int N, levels, anisotropic;
} VoxelMips;

#ifndef GI_VCT_SH
#define GI_VCT_SH 0
#endif

#ifndef GI_VCT_BORDER_EDGE
#define GI_VCT_BORDER_EDGE 0
#endif

// The 8 voxels and weights of a trilinear lookup in a volume of n³ voxels at p, given in level-0
// voxel units from the grid corner, for a cone travelling along d; `scale` = 1 / 2^level. The
// grid's border (vct.border):
//   zero (GI_VCT_BORDER_EDGE = 0): voxels outside the volume are empty (weight 0, index 0), so a
//     sample whose filter reaches past the grid is diluted by the empty outside;
//   edge (GI_VCT_BORDER_EDGE = 1): along each axis on which the cone travels towards a face of the
//     grid, the position is clamped to the outermost voxel centre before that face (a 3D texture's
//     clamp-to-edge, ahead of the cone only): the part of the filter past the face repeats the edge
//     voxels, which is what the cone's rays meet before they leave the grid. At the coarse levels
//     every sample reaches past the grid (level log2 N is one voxel), and a cone that ends on a
//     wall at the border sees it at full opacity. Behind the cone and across it the outside stays
//     empty: clamping there too repeats the walls a cone runs along, which the filter already
//     holds (measured: docs/techniques/vct.md, Accuracy point 9).
inline void vox_trilinear_taps(int n, float3 p, float3 d, float scale, size_t idx[8], float w[8]) {
  float3 u = p * scale - 0.5f;
#if GI_VCT_BORDER_EDGE
  u = select(u, fmax(u, 0.0f), d < 0.0f);
  u = select(u, fmin(u, (float)(n - 1)), d > 0.0f);
#endif
  float3 fl = floor(u);
  float3 f = u - fl;
  int3 i0 = convert_int3(fl);
  for (int k = 0; k < 8; ++k) {
    int x = i0.x + (k & 1), y = i0.y + ((k >> 1) & 1), z = i0.z + (k >> 2);
    bool inside = x >= 0 && x < n && y >= 0 && y < n && z >= 0 && z < n;
    w[k] = inside ? ((k & 1) ? f.x : 1.0f - f.x) * (((k >> 1) & 1) ? f.y : 1.0f - f.y) * ((k >> 2) ? f.z : 1.0f - f.z)
                  : 0.0f;
    idx[k] = inside ? ((size_t)z * n + y) * n + x : 0;
  }
}

// Trilinear lookup of one volume by a cone travelling along d.
inline float4 vox_trilinear(global const float4* vol, int n, float3 p, float3 d, float scale) {
  size_t idx[8];
  float w[8];
  vox_trilinear_taps(n, p, d, scale, idx, w);
  float4 acc = (float4)(0.0f);
  for (int k = 0; k < 8; ++k) acc += w[k] * vol[idx[k]];
  return acc;
}

// Trilinear lookup of an SH volume evaluated against basis Y, with the opacity of the matching
// radiance volume: (premultiplied radiance rgb, α). Evaluation is linear, so evaluating the taps
// and filtering the results equals filtering the coefficients and evaluating.
inline float4 vox_trilinear_sh(global const float4* alphaVol, global const float4* shVol, int n, float3 p, float3 d, float scale,
                               float4 Y) {
  size_t idx[8];
  float w[8];
  vox_trilinear_taps(n, p, d, scale, idx, w);
  float4 acc = (float4)(0.0f);
  for (int k = 0; k < 8; ++k) {
    global const float4* c = shVol + 3 * idx[k];
    acc += w[k] * (float4)(dot(c[0], Y), dot(c[1], Y), dot(c[2], Y), alphaVol[idx[k]].w);
  }
  return acc;
}

// One volume of level `level` (dir = anisotropic direction, ignored for the isotropic chain) seen
// along unit d: (premultiplied radiance rgb, α).
inline float4 vox_volume_sample(VoxelMips m, int level, int dir, float3 p, float3 d) {
  int n = m.N >> level;
  float scale = 1.0f / (float)(1 << level);
  bool iso = !m.anisotropic || level < GI_VCT_FIRST_DIRECTIONAL_LEVEL;
  size_t off = iso ? vox_level_offset(m.N, level) : vox_aniso_offset(m.N, level, dir);
#if GI_VCT_SH
  // The light arriving at the cone's apex travels along −d.
  return vox_trilinear_sh((iso ? m.iso : m.aniso) + off, (iso ? m.sh : m.shAniso) + 3 * off, n, p, d, scale, sh_basis(-d));
#else
  return vox_trilinear((iso ? m.iso : m.aniso) + off, n, p, d, scale);
#endif
}

// One level of the chain seen along unit direction d: the isotropic volume, or (anisotropic,
// level ≥ 1) the three directional volumes facing d weighted by d² per axis.
inline float4 vox_level_sample(VoxelMips m, int level, float3 p, float3 d) {
  if (!m.anisotropic || level < GI_VCT_FIRST_DIRECTIONAL_LEVEL) return vox_volume_sample(m, level, 0, p, d);
  float3 w = d * d;
  return w.x * vox_volume_sample(m, level, d.x >= 0.0f ? 0 : 1, p, d) +
         w.y * vox_volume_sample(m, level, d.y >= 0.0f ? 2 : 3, p, d) +
         w.z * vox_volume_sample(m, level, d.z >= 0.0f ? 4 : 5, p, d);
}

// Quadrilinear lookup at fractional level (clamped to the chain). SH voxels: the l <= 1
// reconstruction can dip below 0 behind a surface; radiance is clamped at 0.
inline float4 vox_sample(VoxelMips m, float3 p, float3 d, float level) {
  level = clamp(level, 0.0f, (float)(m.levels - 1));
  int l0 = (int)floor(level);
  float f = level - (float)l0;
  float4 c = vox_level_sample(m, l0, p, d);
  if (f > 0.0f && l0 + 1 < m.levels) c = mix(c, vox_level_sample(m, l0 + 1, p, d), f);
#if GI_VCT_SH
  c.xyz = fmax(c.xyz, 0.0f);
#endif
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

// The signed sum of a biased field (voxel_types.h) of record a.
inline int vox_signed_sum(global const uint* a, int field) {
  return (int)(a[field] - (a[GI_VOX_OPACITY] >> 16) * GI_VOX_SIGNED_BIAS);  // GI_VOX_UNIT = 2^16
}

inline VoxelSurface vox_resolve(GiVoxelGrid grid, global const uint* acc, size_t v) {
  int N = grid.resolution;
  global const uint* a = acc + v * GI_VOX_RECORD;
  VoxelSurface r;
  float weight = (float)a[GI_VOX_OPACITY] * (1.0f / GI_VOX_UNIT);  // Σ opacity
  r.alpha = weight / (float)a[GI_VOX_COUNT];
  float invW = 1.0f / weight;
  r.albedo = (float3)(a[GI_VOX_ALBEDO], a[GI_VOX_ALBEDO + 1], a[GI_VOX_ALBEDO + 2]) * (invW / GI_VOX_UNIT);
  r.emission = (float3)(a[GI_VOX_EMISSION], a[GI_VOX_EMISSION + 1], a[GI_VOX_EMISSION + 2]) * (invW / GI_VOX_EMISSION_UNIT);
  float3 meanN = (float3)(vox_signed_sum(a, GI_VOX_NORMAL), vox_signed_sum(a, GI_VOX_NORMAL + 1),
                          vox_signed_sum(a, GI_VOX_NORMAL + 2)) * (invW * 4.0f / GI_VOX_UNIT);
  float3 offset = (float3)(vox_signed_sum(a, GI_VOX_OFFSET), vox_signed_sum(a, GI_VOX_OFFSET + 1),
                           vox_signed_sum(a, GI_VOX_OFFSET + 2)) * (invW * 4.0f / GI_VOX_UNIT);
  r.position = vload3(0, grid.origin) + (convert_float3(vox_cell(v, N)) + 0.5f + offset) * grid.voxel_size;
  r.twoSided = length(meanN) < 0.5f;
  r.normal = safe_normalize(meanN, (float3)(0.0f, 1.0f, 0.0f));
  return r;
}
