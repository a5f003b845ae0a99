// Light injection and mipmapping of the voxel grid (ALGORITHMS.md §5).
//
// vct_inject: per voxel of the occupied list (every other voxel of level 0 is zero: voxelize.cl's
//   vct_clear_occupied), from the voxelization accumulators (voxel_types.h): opacity α = mean
//   coverage of the triangles touching it; albedo, emission and normal = their opacity-weighted
//   means; radiance L = ρ/π · E_direct + L_e, with E_direct the irradiance of every punctual light
//   on the voxel's mean normal (evaluated at the mean of the triangles' points nearest the voxel
//   centre: a spot light's cone and distance), times the fraction of the voxel's footprint in the
//   light's shadow map where the light reaches the voxel's box (common/shadow.h,
//   shadow_voxel_visibility: 3×3 taps over the footprint, no surface point, so neither the
//   voxel's own surfaces nor the map's texel size change it; a point sample at the surface point
//   with a texel-sized normal offset, used before, lost 44 % of Sponza's injected light between
//   1024² and 4096² maps). Voxels whose normals cancel (|mean n| < 0.5: both sides of thin
//   geometry) are lit from both sides (|n·ω|). Output: level 0, (L·α, α).
// vct_directional_level0 (directional voxels, vct.voxels=directional / directional_slab): the 6
//   directional volumes of level 0 in `aniso`, per voxel the isotropic (L·α, α) times
//   vox_directional_coverage of its mean normal (slab: 1 for directional_slab); vct_mip_anisotropic then builds level 1 from them as it builds the levels above.
// vct_mip_isotropic: parent = mean of its 8 children (premultiplied, so this conserves Σ L·α).
// vct_mip_anisotropic_first (level 1) / vct_mip_anisotropic (levels ≥ 2): per parent and direction,
//   the 2 children along the axis composited front to back (c = c_f + (1 − α_f)·c_b,
//   α = α_f + (1 − α_f)·α_b), the 4 columns averaged; one work-item per parent for all 6 directions.
// vct_occupied_first / vct_occupied_level / vct_empty_space_first / vct_empty_space: the
//   empty-space map of the specular march (cone_lanes.h, vct_cone_lanes), one byte per cell of
//   every level: 0 where the 2×2×2 block of cells i … i + 1 of the level (the part inside the
//   volume) is exactly empty, α = 0 and radiance 0 (below).
// SH voxels (vct.voxels=sh, voxel_types.h), after the radiance mips:
// vct_sh_project: level 0, per voxel and channel the SH coefficients L·α·lobe(n) of its radiance
//   (level 0 of the radiance chain), n its mean normal (both lobes when the normals cancel).
// vct_mip_sh_isotropic / vct_mip_sh_anisotropic: the same two filters on the coefficients (linear
//   in them, so the parent's coefficients are those of the filtered directional radiance), the
//   anisotropic compositing weighted by the opacity of the front child from the radiance mips.
#include "common/lights_lanes.h"
#include "gi/vct/voxel_grid.h"

// The injection one voxel at a time over the whole grid (vox_resolve, light_incident,
// shadow_voxel_visibility): the tests' reference for vct_inject's lanes.
kernel void vct_inject_voxelwise(GiVoxelGrid grid, global const uint* acc, global const GiLight* lights,
                                 int lightCount, global const GiView* shadowViews, global const uint* shadowOffsets,
                                 global const float* shadowDepths, global float4* level0) {
  int N = grid.resolution;
  size_t v = get_global_id(0);
  if (v >= (size_t)N * N * N) return;
  if (acc[v * GI_VOX_RECORD + GI_VOX_OPACITY] == 0u) {
    level0[v] = (float4)(0.0f);
    return;
  }
  VoxelSurface vs = vox_resolve(grid, acc, v);
  float3 p = vs.position, n = vs.normal;
  bool twoSided = vs.twoSided;
  float3 E = (float3)(0.0f);
  for (int li = 0; li < lightCount; ++li) {
    global const GiLight* l = &lights[li];
    float3 wi;
    float dist;
    float3 Ein = light_incident(l, p, &wi, &dist);
    float c = dot(n, wi);
    if (twoSided) c = fabs(c);
    if (c <= 0.0f || Ein.x + Ein.y + Ein.z <= 0.0f) continue;
    float3 centre = vload3(0, grid.origin) + (convert_float3(vox_cell(v, N)) + 0.5f) * grid.voxel_size;
    E += Ein * c * shadow_voxel_visibility(l, shadowViews, shadowOffsets, shadowDepths, centre, 0.5f * grid.voxel_size);
  }
  float3 L = vs.albedo * GI_INV_PI * E + vs.emission;
  level0[v] = (float4)(L * vs.alpha, vs.alpha);
}

// vct_inject's reads of the voxel records and writes of level 0 miss the cache (the list is in
// voxel order but sparse: mostly one 64-byte record line per voxel): each work-item prefetches
// the record and level-0 entry of the work-item GI_INJECT_PREFETCH_AHEAD list entries after it
// (the items of a work-group run in order on a CPU core). clang's __builtin_prefetch, as PoCL's
// prefetch() is a no-op; CPU devices only (GI_VW > 1). Measured in docs/PERFORMANCE.md ("Voxel
// light injection, prefetch"): −10 % CPU time in vct_inject; prefetching the shadow map rows as
// well was slower.
#define GI_INJECT_PREFETCH_AHEAD 64
inline void vox_inject_prefetch(global const uint* acc, global const uint* occupied, int count, int first,
                                global const float4* level0) {
#if GI_VW > 1
  int ahead = first + GI_INJECT_PREFETCH_AHEAD;
  if (ahead >= count) return;
  for (int l = 0; l < GI_VW; ++l) {
    uint v = occupied[min(ahead + l, count - 1)];
    __builtin_prefetch(acc + (size_t)v * GI_VOX_RECORD, 0, 3);
    __builtin_prefetch(level0 + v, 1, 3);
  }
#endif
}

// GI_VW consecutive entries of the occupied list from `first` (the list is in voxel order, so
// the lanes' records are near each other): vox_resolve, light_incident and shadow_visibility
// lane-wise (common/lights_lanes.h), the lights uniform across lanes.
inline void vox_inject_block(GiVoxelGrid grid, global const uint* acc, global const uint* occupied, int count,
                             int first, global const GiLight* lights, int lightCount,
                             global const GiView* shadowViews, global const uint* shadowOffsets,
                             global const float* shadowDepths, global float4* level0) {
  int valid = min(GI_VW, count - first);
  vox_inject_prefetch(acc, occupied, count, first, level0);
  // Lanes past the end repeat the last entry (computed, not stored).
  intV entry = min(first + GI_LANES, count - 1);
  intV v = GI_GATHER(intV, (global const int*)occupied, entry);  // < 2^24
  // The records (voxel_types.h), 4 words at a time, as int (the unsigned fields reinterpreted).
  intV albR, albG, albB, emR, emG, emB, nX, nY, nZ, oX, oY, oZ, opacity, triangles, pad0, pad1;
  global const int* words = (global const int*)acc;
  intV word = v * GI_VOX_RECORD;
  GI_GATHER_SPAN4(int, words, word, albR, albG, albB, emR)
  GI_GATHER_SPAN4(int, words, word + 4, emG, emB, nX, nY)
  GI_GATHER_SPAN4(int, words, word + 8, nZ, oX, oY, oZ)
  GI_GATHER_SPAN4(int, words, word + 12, opacity, triangles, pad0, pad1)
  // vox_resolve lane-wise (vox_signed_sum: the biased signed fields less their bias).
  intV bias = convert_intV(as_uintV(opacity) >> 16) * (int)GI_VOX_SIGNED_BIAS;
  nX -= bias;
  nY -= bias;
  nZ -= bias;
  oX -= bias;
  oY -= bias;
  oZ -= bias;
  intV covered = opacity != 0;
  floatV weight = convert_floatV(as_uintV(opacity)) * (1.0f / GI_VOX_UNIT);
  floatV alpha = weight / convert_floatV(max(as_uintV(triangles), 1u));
  floatV invW = 1.0f / GI_SEL((floatV)(1.0f), weight, covered);
  floatV kAlbedo = invW / GI_VOX_UNIT, kEmission = invW / GI_VOX_EMISSION_UNIT, kSigned = invW * 4.0f / GI_VOX_UNIT;
  float3V albedo = f3v(convert_floatV(as_uintV(albR)) * kAlbedo, convert_floatV(as_uintV(albG)) * kAlbedo,
                       convert_floatV(as_uintV(albB)) * kAlbedo);
  float3V emission = f3v(convert_floatV(as_uintV(emR)) * kEmission, convert_floatV(as_uintV(emG)) * kEmission,
                         convert_floatV(as_uintV(emB)) * kEmission);
  float3V meanN = f3v(convert_floatV(nX) * kSigned, convert_floatV(nY) * kSigned, convert_floatV(nZ) * kSigned);
  float3V offset = f3v(convert_floatV(oX) * kSigned, convert_floatV(oY) * kSigned, convert_floatV(oZ) * kSigned);
  int N = grid.resolution, shift = 31 - clz(N);
  intV mask = (intV)(N - 1);
  float s = grid.voxel_size;
  float3V cell = f3v(convert_floatV(v & mask), convert_floatV((v >> shift) & mask), convert_floatV(v >> (2 * shift)));
  float3V p = f3v(grid.origin[0] + (cell.x + 0.5f + offset.x) * s, grid.origin[1] + (cell.y + 0.5f + offset.y) * s,
                  grid.origin[2] + (cell.z + 0.5f + offset.z) * s);
  float3V centre = f3v(grid.origin[0] + (cell.x + 0.5f) * s, grid.origin[1] + (cell.y + 0.5f) * s,
                       grid.origin[2] + (cell.z + 0.5f) * s);
  intV twoSided = sqrt(dotV(meanN, meanN)) < 0.5f;
  float3V n = safe_normalizeV(meanN, f3v((floatV)(0.0f), (floatV)(1.0f), (floatV)(0.0f)));
  float3V E = f3v((floatV)(0.0f), (floatV)(0.0f), (floatV)(0.0f));
  for (int li = 0; li < lightCount; ++li) {
    global const GiLight* l = &lights[li];
    float3V wi;
    float3V Ein = light_incidentV(l, p, &wi);
    floatV cn = dotV(n, wi);
    floatV c = GI_SEL(cn, fabs(cn), twoSided);
    intV lit = covered & (c > 0.0f) & (Ein.x + Ein.y + Ein.z > 0.0f);
    if (!GI_ANY(lit)) continue;
    c = GI_SEL((floatV)(0.0f), c, lit);
    floatV visibility = shadow_voxel_visibilityV(l, shadowViews, shadowOffsets, shadowDepths, centre, 0.5f * s);
    E = f3v(E.x + Ein.x * c * visibility, E.y + Ein.y * c * visibility, E.z + Ein.z * c * visibility);
  }
  floatV zero = (floatV)(0.0f);
  alpha = GI_SEL(zero, alpha, covered);
  float out[4][GI_VW];
  vstoreV((albedo.x * GI_INV_PI * E.x + emission.x) * alpha, 0, out[0]);
  vstoreV((albedo.y * GI_INV_PI * E.y + emission.y) * alpha, 0, out[1]);
  vstoreV((albedo.z * GI_INV_PI * E.z + emission.z) * alpha, 0, out[2]);
  vstoreV(alpha, 0, out[3]);
  int voxels[GI_VW];
  vstoreV(v, 0, voxels);
  for (int l = 0; l < valid; ++l) level0[voxels[l]] = (float4)(out[0][l], out[1][l], out[2][l], out[3][l]);
}

// The occupied list in blocks of GI_VW entries, each work-item a contiguous run of blocks (in
// order, so that vox_inject_prefetch's look-ahead lands in its own run). The count is on the
// device, so the launch cannot be sized to it: launched over N³ / GI_VW items with one block each,
// only the first work-groups had work and PoCL ran nearly all of it on one of its two threads
// (docs/PERFORMANCE.md, "Voxel light injection on both cores"). The host launches a fixed number of
// items on CPU devices (VoxelScene::inject) and N³ / GI_VW on GPUs (one block each).
kernel void vct_inject(GiVoxelGrid grid, global const uint* acc, global const uint* occupied,
                       global const uint* occupiedCount, global const GiLight* lights, int lightCount,
                       global const GiView* shadowViews, global const uint* shadowOffsets,
                       global const float* shadowDepths, global float4* level0) {
  int count = (int)occupiedCount[0];
  int blocks = (count + GI_VW - 1) / GI_VW, items = (int)get_global_size(0);
  int run = (blocks + items - 1) / items, b0 = (int)get_global_id(0) * run;
  for (int b = b0; b < min(b0 + run, blocks); ++b)
    vox_inject_block(grid, acc, occupied, count, b * GI_VW, lights, lightCount, shadowViews, shadowOffsets,
                     shadowDepths, level0);
}

// The 8 children of parent cell `cell` in the volume of edge nc, child k = dx + 2·dy + 4·dz.
inline void vox_children(global const float4* vol, int nc, int3 cell, float4 ch[8]) {
  size_t first = ((size_t)(2 * cell.z) * nc + 2 * cell.y) * nc + 2 * cell.x;
  size_t row = (size_t)nc, slice = (size_t)nc * nc;
  ch[0] = vol[first];
  ch[1] = vol[first + 1];
  ch[2] = vol[first + row];
  ch[3] = vol[first + row + 1];
  ch[4] = vol[first + slice];
  ch[5] = vol[first + slice + 1];
  ch[6] = vol[first + slice + row];
  ch[7] = vol[first + slice + row + 1];
}

// Parent voxels of `level` (≥ 1) from the isotropic level below. Straight-line code (no loop):
// PoCL vectorizes it across work-items (PERFORMANCE_FACTS point 1).
kernel void vct_mip_isotropic(int N, int level, global float4* iso) {
  int n = N >> level;
  size_t v = get_global_id(0);
  if (v >= (size_t)n * n * n) return;
  float4 ch[8];
  vox_children(iso + vox_level_offset(N, level - 1), 2 * n, vox_cell(v, n), ch);
  // Summed in child order k = 0 … 7 from 0 (the order of the host mirror in the tests).
  float4 sum = (float4)(0.0f) + ch[0];
  sum += ch[1];
  sum += ch[2];
  sum += ch[3];
  sum += ch[4];
  sum += ch[5];
  sum += ch[6];
  sum += ch[7];
  iso[vox_level_offset(N, level) + v] = sum * 0.125f;
}

// Level 1 from level 0 using the occupancy bits (bit v & 31 of word v >> 5 set for every voxel
// the voxelization touched): level 0 is zero wherever its bit is clear (the injection, the bounce
// and the clear write only listed voxels), so a parent without an occupied child is 0 and its 8
// children need not be read — most of the 32 MB of level 0 at 128³. A work-item takes 16 parents
// along x (n ≥ 16): their children span 32 voxels of each of the 4 child rows, one occupancy word
// per row; per block of 4 parents (one byte of each word) either zero or the children's rows
// loaded as float16 and summed in vct_mip_isotropic's child order k = 0 … 7 (the same bits).
// 8 consecutive children of a row, loaded once: the even ones (x = 0, 2, 4, 6) and the odd ones,
// one per parent, as the 4 float4 of a float16.
inline void vox_row_children(global const float4* r, float16* even, float16* odd) {
  float16 a = vload16(0, (global const float*)r), b = vload16(1, (global const float*)r);
  *even = (float16)(a.s0123, a.s89ab, b.s0123, b.s89ab);
  *odd = (float16)(a.s4567, a.scdef, b.s4567, b.scdef);
}
kernel void vct_mip_isotropic_first(int N, global const uint* occupancy, global float4* iso) {
  int n = N >> 1;
  size_t v = 16 * get_global_id(0);  // the work-item's first parent
  if (v >= (size_t)n * n * n) return;
  int3 cell = vox_cell(v, n);
  size_t first = ((size_t)(2 * cell.z) * N + 2 * cell.y) * N + 2 * cell.x;
  size_t row = (size_t)N, slice = (size_t)N * N;
  uint w00 = occupancy[first >> 5], w10 = occupancy[(first + row) >> 5], w01 = occupancy[(first + slice) >> 5],
       w11 = occupancy[(first + slice + row) >> 5];
  global float* out = (global float*)(iso + vox_level_offset(N, 1) + v);
  for (int b = 0; b < 4; ++b) {
    size_t c = first + 8 * b;
    uint any = ((w00 | w10 | w01 | w11) >> (8 * b)) & 0xffu;
    float16 sum = (float16)(0.0f);
    if (any != 0u) {
      const size_t rows[4] = {c, c + row, c + slice, c + slice + row};  // children k = 0–1, 2–3, 4–5, 6–7
#pragma unroll
      for (int r = 0; r < 4; ++r) {
        float16 even, odd;
        vox_row_children(iso + rows[r], &even, &odd);
        sum += even;
        sum += odd;
      }
      sum *= 0.125f;
    }
    vstore16(sum, b, out);
  }
}

// Column (i, j) of a parent's 2×2×2 children seen along direction dir (0..5 = +x, −x, +y, −y, +z,
// −z): the front and back child's index in the child volume of edge nc; b = 2 × the parent's cell.
inline void vox_column(int dir, int i, int j, int3 b, int nc, size_t* front, size_t* back) {
  int axis = dir / 2;
  int f = (dir & 1) == 0 ? 0 : 1;  // travelling along +axis: the lower child is in front
  int3 c0, c1;
  if (axis == 0) { c0 = (int3)(f, i, j); c1 = (int3)(1 - f, i, j); }
  else if (axis == 1) { c0 = (int3)(i, f, j); c1 = (int3)(i, 1 - f, j); }
  else { c0 = (int3)(i, j, f); c1 = (int3)(i, j, 1 - f); }
  *front = ((size_t)(b.z + c0.z) * nc + (b.y + c0.y)) * nc + (b.x + c0.x);
  *back = ((size_t)(b.z + c1.z) * nc + (b.y + c1.y)) * nc + (b.x + c1.x);
}

// Work-item gid of a kernel over 6 directions × n³ parent cells: returns the cell's index, sets
// its direction (≥ 6: past the end) and 2 × its cell coordinates.
inline size_t vox_directional_item(size_t gid, int n, int* dir, int3* childBase) {
  int s3 = 3 * (31 - clz(n));  // cells = n³ = 2^s3
  *dir = (int)(gid >> s3);
  size_t v = gid & (((size_t)1 << s3) - 1);
  *childBase = 2 * vox_cell(v, n);
  return v;
}

// A parent seen along direction dir (0..5 = +x, −x, +y, −y, +z, −z) from its 8 children
// (vox_children order): per column (i, j) of vox_column the front child composited over the back
// one, c_f + (1 − α_f)·c_b, the 4 columns averaged in vox_column's (j, i) order.
inline float4 vox_aniso_parent(int dir, const float4 ch[8]) {
  int axis = dir / 2, f = dir & 1;
  // Child index steps: along the compositing axis, and along the column axes i and j.
  int along = axis == 0 ? 1 : (axis == 1 ? 2 : 4);
  int si = axis == 0 ? 2 : 1, sj = axis == 2 ? 2 : 4;
  float4 sum = (float4)(0.0f);
#pragma unroll
  for (int j = 0; j < 2; ++j)
#pragma unroll
    for (int i = 0; i < 2; ++i) {
      int column = i * si + j * sj;
      float4 front = ch[column + f * along], back = ch[column + (1 - f) * along];
      sum += front + (1.0f - front.w) * back;
    }
  return sum * 0.25f;
}

// Parent voxels of level 1, all 6 directions, from the isotropic level 0: one work-item per parent
// reads its 8 children once and writes the 6 directional volumes.
kernel void vct_mip_anisotropic_first(int N, global const float4* iso, global float4* aniso) {
  int n = N >> 1;
  size_t v = get_global_id(0);
  if (v >= (size_t)n * n * n) return;
  float4 ch[8];
  vox_children(iso, N, vox_cell(v, n), ch);
#pragma unroll
  for (int dir = 0; dir < 6; ++dir) aniso[vox_aniso_offset(N, 1, dir) + v] = vox_aniso_parent(dir, ch);
}

// Directional voxels (GI_VCT_DIRECTIONAL = 1): level 0's 6 directional volumes from the isotropic
// level 0 and the voxels' mean normals, over the whole grid (voxels whose occupancy bit is clear
// are zero in `iso`, buildMips' contract, and written as zero here, so that nothing is left of an
// earlier voxelization; so are voxels every triangle of which an alpha cut-out removed, α = 0).
kernel void vct_directional_level0(GiVoxelGrid grid, global const uint* occupancy, global const uint* acc,
                                   global const float4* iso, int slab, global float4* aniso) {
  int N = grid.resolution;
  size_t v = get_global_id(0);
  if (v >= (size_t)N * N * N) return;
  float4 c = (float4)(0.0f);
  float coverage[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  if (((occupancy[v >> 5] >> (v & 31)) & 1u) && acc[v * GI_VOX_RECORD + GI_VOX_OPACITY] != 0u) {
    VoxelSurface s = vox_resolve(grid, acc, v);
    c = iso[v];
#pragma unroll
    for (int dir = 0; dir < 6; ++dir) coverage[dir] = vox_directional_coverage(s.normal, s.twoSided, slab, dir);
  }
#pragma unroll
  for (int dir = 0; dir < 6; ++dir) aniso[vox_aniso_offset(N, 0, dir) + v] = coverage[dir] * c;
}

// Parent voxels of `level` (≥ 2, or ≥ 1 with directional voxels), all 6 directions, each from the
// matching directional volume of level − 1; one work-item per parent (the direction a
// compile-time constant in each unrolled step).
kernel void vct_mip_anisotropic(int N, int level, global float4* aniso) {
  int n = N >> level;
  size_t v = get_global_id(0);
  if (v >= (size_t)n * n * n) return;
  int3 cell = vox_cell(v, n);
#pragma unroll
  for (int dir = 0; dir < 6; ++dir) {
    float4 ch[8];
    vox_children((global const float4*)aniso + vox_aniso_offset(N, level - 1, dir), 2 * n, cell, ch);
    aniso[vox_aniso_offset(N, level, dir) + v] = vox_aniso_parent(dir, ch);
  }
}

// lobe = (k0, k1) of voxel_types.h.
kernel void vct_sh_project(GiVoxelGrid grid, global const uint* acc, global const float4* level0, float2 lobe,
                           global float4* sh) {
  int N = grid.resolution;
  size_t v = get_global_id(0);
  if (v >= (size_t)N * N * N) return;
  float4 k = (float4)(0.0f);
  if (acc[v * GI_VOX_RECORD + GI_VOX_OPACITY] != 0u) {
    VoxelSurface vs = vox_resolve(grid, acc, v);
    k = vs.twoSided ? (float4)(2.0f * lobe.x, 0.0f, 0.0f, 0.0f)
                    : (float4)(lobe.x, lobe.y * vs.normal.y, lobe.y * vs.normal.z, lobe.y * vs.normal.x);
  }
  float4 L = level0[v];  // premultiplied
  sh[3 * v + 0] = L.x * k;
  sh[3 * v + 1] = L.y * k;
  sh[3 * v + 2] = L.z * k;
}

// SH coefficients of the parent voxels of `level` (≥ 1): mean of the 8 children.
kernel void vct_mip_sh_isotropic(int N, int level, global float4* sh) {
  int n = N >> level, nc = n * 2;
  size_t v = get_global_id(0);
  if (v >= (size_t)n * n * n) return;
  int3 cell = vox_cell(v, n);
  int x = cell.x, y = cell.y, z = cell.z;
  global const float4* child = sh + 3 * vox_level_offset(N, level - 1);
  float4 sum[3] = {(float4)(0.0f), (float4)(0.0f), (float4)(0.0f)};
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        size_t c = ((size_t)(2 * z + dz) * nc + (2 * y + dy)) * nc + (2 * x + dx);
        for (int ch = 0; ch < 3; ++ch) sum[ch] += child[3 * c + ch];
      }
  global float4* out = sh + 3 * (vox_level_offset(N, level) + v);
  for (int ch = 0; ch < 3; ++ch) out[ch] = sum[ch] * 0.125f;
}

// SH coefficients of the parent voxels of `level` (≥ 1), all 6 directions: per column the front
// child's coefficients plus the back child's times (1 − α_front), α from the radiance mips (iso
// level 0 below level 1, else the matching directional volume), the 4 columns averaged.
kernel void vct_mip_sh_anisotropic(int N, int level, global const float4* iso, global const float4* aniso,
                                   global float4* sh, global float4* shAniso) {
  int n = N >> level, nc = n * 2, dir;
  int3 b;  // 2 × the parent's cell: its first child
  size_t v = vox_directional_item(get_global_id(0), n, &dir, &b);
  if (dir >= 6) return;
  size_t childOffset = level == 1 ? 0 : vox_aniso_offset(N, level - 1, dir);
  global const float4* alpha = (level == 1 ? iso : aniso) + childOffset;
  global const float4* child = (level == 1 ? (global const float4*)sh : (global const float4*)shAniso) + 3 * childOffset;
  float4 sum[3] = {(float4)(0.0f), (float4)(0.0f), (float4)(0.0f)};
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      size_t f, k;
      vox_column(dir, i, j, b, nc, &f, &k);
      float transmit = 1.0f - alpha[f].w;
      for (int ch = 0; ch < 3; ++ch) sum[ch] += child[3 * f + ch] + transmit * child[3 * k + ch];
    }
  global float4* out = shAniso + 3 * (vox_aniso_offset(N, level, dir) + v);
  for (int ch = 0; ch < 3; ++ch) out[ch] = sum[ch] * 0.25f;
}

// The empty-space map (VoxelScene::buildEmptySpace; cone_lanes.h, vct_cone_lanes): map[offset(l) + i]
// (offset as in `iso`, one byte per cell) is 0 when no level-0 voxel under the cells i … i + 1 of
// level l along each axis (those inside the volume) has its occupancy bit set, else 1. Level 0 is
// zero wherever the bit is clear (buildMips' contract), and every mip cell (isotropic mean,
// anisotropic front-to-back composites, SH coefficients) is a sum of products of its children, so
// it is exactly 0 when they all are: a trilinear lookup at level l whose 8 taps start at cell i
// reads only zeros where the map is 0. occupied[offset(l) − N³ + c] (scratch, levels ≥ 1): 1 if a
// voxel under cell c of level l is occupied.

// Level 1 of `occupied`: a cell's 8 children are bits 2x, 2x + 1 of 4 occupancy rows (2x is even,
// so both bits lie in one word).
kernel void vct_occupied_first(int N, global const uint* occupancy, global uchar* occupied) {
  int n = N >> 1;
  size_t c = get_global_id(0);
  if (c >= (size_t)n * n * n) return;
  int3 cell = vox_cell(c, n);
  size_t first = ((size_t)(2 * cell.z) * N + 2 * cell.y) * N + 2 * cell.x, row = (size_t)N, slice = (size_t)N * N;
  uint any = occupancy[first >> 5] | occupancy[(first + row) >> 5] | occupancy[(first + slice) >> 5] |
             occupancy[(first + slice + row) >> 5];
  occupied[c] = (uchar)(((any >> (first & 31)) & 3u) != 0u);
}

// Level `level` ≥ 2 of `occupied` from the level below: any of the 8 children.
kernel void vct_occupied_level(int N, int level, global uchar* occupied) {
  int n = N >> level, nc = 2 * n;
  size_t c = get_global_id(0);
  if (c >= (size_t)n * n * n) return;
  int3 cell = vox_cell(c, n);
  size_t N3 = (size_t)N * N * N;
  global const uchar* child = occupied + (vox_level_offset(N, level - 1) - N3) +
                              ((size_t)(2 * cell.z) * nc + 2 * cell.y) * nc + 2 * cell.x;
  size_t row = (size_t)nc, slice = (size_t)nc * nc;
  uint any = child[0] | child[1] | child[row] | child[row + 1] | child[slice] | child[slice + 1] |
             child[slice + row] | child[slice + row + 1];
  occupied[vox_level_offset(N, level) - N3 + c] = (uchar)(any != 0u);
}

// Level 0 of the map from the occupancy bits, one work-item per word (32 voxels along x, N ≥ 32):
// per row of the block (y, z), (y + 1, z), (y, z + 1), (y + 1, z + 1) (rows past the grid left out),
// bit b | bit b + 1 (the next word's bit 0 for b = 31, none past the row's end).
kernel void vct_empty_space_first(int N, global const uint* occupancy, global uchar* map) {
  int wordsPerRow = N >> 5;
  size_t w = get_global_id(0);
  if (w >= (size_t)N * N * wordsPerRow) return;
  int xWord = (int)(w % wordsPerRow);
  size_t rowIndex = w / wordsPerRow;
  int y = (int)(rowIndex % N), z = (int)(rowIndex / N);
  int dy = y + 1 < N ? 1 : 0, dz = z + 1 < N ? 1 : 0;
  size_t rows[4] = {w, w + (size_t)dy * wordsPerRow, w + (size_t)dz * N * wordsPerRow,
                    w + ((size_t)dz * N + dy) * wordsPerRow};
  uint m = 0u;
#pragma unroll
  for (int r = 0; r < 4; ++r) {
    uint word = occupancy[rows[r]], next = xWord + 1 < wordsPerRow ? occupancy[rows[r] + 1] : 0u;
    m |= word | (word >> 1) | (next << 31);
  }
  uint16 bit = (uint16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  vstore16(convert_uchar16(((uint16)(m) >> bit) & 1u), 0, map + 32 * w);
  vstore16(convert_uchar16(((uint16)(m >> 16) >> bit) & 1u), 0, map + 32 * w + 16);
}

// Level `level` ≥ 1 of the map from `occupied`: any of the cells i … i + 1 inside the volume.
kernel void vct_empty_space(int N, int level, global const uchar* occupied, global uchar* map) {
  int n = N >> level;
  size_t c = get_global_id(0);
  if (c >= (size_t)n * n * n) return;
  int3 i = vox_cell(c, n);
  int dx = i.x + 1 < n ? 1 : 0, dy = i.y + 1 < n ? n : 0, dz = i.z + 1 < n ? n * n : 0;
  global const uchar* o = occupied + (vox_level_offset(N, level) - (size_t)N * N * N) + c;
  uint any = o[0] | o[dx] | o[dy] | o[dy + dx] | o[dz] | o[dz + dx] | o[dz + dy] | o[dz + dy + dx];
  map[vox_level_offset(N, level) + c] = (uchar)(any != 0u);
}
