// Voxelization in compute (ALGORITHMS.md §5; Crassin et al. 2011 as in seed 003 §3.4.1, without
// the hardware rasterizer): every triangle adds its material to every voxel it overlaps.
//
// vct_voxelize_trianglewise (the tests' reference): one work-item per triangle. It walks the voxel
// columns along the triangle's dominant normal axis (only the few voxels of each column that the
// triangle's plane can reach), keeps the voxels that pass the separating-axis triangle–box test
// (Akenine-Möller 2001: 3 box normals, the triangle normal, 9 edge cross products) against the
// voxel grown by GI_VOX_GROW (conservative under float rounding: a voxel the triangle touches is
// never missed), and adds, with integer atomics (order-independent, so bit-identical run to run:
// ALGORITHMS.md §7), the material at the triangle's point nearest the voxel centre. See
// voxel_types.h for the accumulator records.
// vct_voxelize (used by VoxelScene): the same walk, tests and values with the triangles' columns
// spread over SIMD lanes (section "Voxelization in lanes" below); same accumulator bits.
#include "common/material.h"
#include "common/vector_width.h"
#include "common/texture_lanes.h"
#include "gi/vct/voxel_types.h"

#define GI_VOX_GROW 1e-4f  // relative growth of the voxel for the overlap test

// Dot and cross products written out (not the builtins, whose rounding depends on how the OpenCL
// library evaluates them): vct_voxelize's lanes (vector_width.h's dotV/crossV) round the same
// expressions the same way, so both kernels give the same bits.
inline float vox_dot(float3 a, float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float3 vox_cross(float3 a, float3 b) {
  return (float3)(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

// Separating-axis test of triangle (a, b, c) against the box centred at the origin with half-size h.
inline bool tri_box_overlap(float3 a, float3 b, float3 c, float h) {
  // Box normals: the triangle's bounding box against the box.
  if (fmin(a.x, fmin(b.x, c.x)) > h || fmax(a.x, fmax(b.x, c.x)) < -h) return false;
  if (fmin(a.y, fmin(b.y, c.y)) > h || fmax(a.y, fmax(b.y, c.y)) < -h) return false;
  if (fmin(a.z, fmin(b.z, c.z)) > h || fmax(a.z, fmax(b.z, c.z)) < -h) return false;
  float3 e0 = b - a, e1 = c - b, e2 = a - c;
  // Triangle normal: the box's projection radius on n against the plane's distance. For (nearly)
  // degenerate triangles n is rounding noise; the tolerance (a bound on the rounding error of
  // n·a) keeps the test from rejecting them, and the edge axes decide.
  float3 n = vox_cross(e0, e1);
  float r = h * (fabs(n.x) + fabs(n.y) + fabs(n.z));
  float tol = 8.0f * FLT_EPSILON * sqrt(vox_dot(e0, e0)) * sqrt(vox_dot(e1, e1)) * (fabs(a.x) + fabs(a.y) + fabs(a.z) + h);
  if (fabs(vox_dot(n, a)) > r + tol) return false;
  // Edge × box axis (9 axes). For axis u = e × x̂ etc., project the 3 vertices and the box.
  float3 edges[3] = {e0, e1, e2};
  for (int k = 0; k < 3; ++k) {
    float3 e = edges[k];
    // u = e × (1,0,0) = (0, e.z, -e.y)
    float pa = e.z * a.y - e.y * a.z, pb = e.z * b.y - e.y * b.z, pc = e.z * c.y - e.y * c.z;
    float rad = h * (fabs(e.z) + fabs(e.y));
    if (fmin(pa, fmin(pb, pc)) > rad || fmax(pa, fmax(pb, pc)) < -rad) return false;
    // u = e × (0,1,0) = (-e.z, 0, e.x)
    pa = -e.z * a.x + e.x * a.z; pb = -e.z * b.x + e.x * b.z; pc = -e.z * c.x + e.x * c.z;
    rad = h * (fabs(e.z) + fabs(e.x));
    if (fmin(pa, fmin(pb, pc)) > rad || fmax(pa, fmax(pb, pc)) < -rad) return false;
    // u = e × (0,0,1) = (e.y, -e.x, 0)
    pa = e.y * a.x - e.x * a.y; pb = e.y * b.x - e.x * b.y; pc = e.y * c.x - e.x * c.y;
    rad = h * (fabs(e.y) + fabs(e.x));
    if (fmin(pa, fmin(pb, pc)) > rad || fmax(pa, fmax(pb, pc)) < -rad) return false;
  }
  return true;
}

// Barycentric coordinates (of b and c) of the point of triangle (a, b, c) nearest to p
// (Ericson, Real-Time Collision Detection §5.1.5, region by region).
inline float2 nearest_on_triangle(float3 p, float3 a, float3 b, float3 c) {
  float3 ab = b - a, ac = c - a, ap = p - a;
  float d1 = vox_dot(ab, ap), d2 = vox_dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return (float2)(0.0f, 0.0f);
  float3 bp = p - b;
  float d3 = vox_dot(ab, bp), d4 = vox_dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return (float2)(1.0f, 0.0f);
  float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return (float2)(d1 / (d1 - d3), 0.0f);
  float3 cp = p - c;
  float d5 = vox_dot(ab, cp), d6 = vox_dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return (float2)(0.0f, 1.0f);
  float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return (float2)(0.0f, d2 / (d2 - d6));
  float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (float2)(1.0f - w, w);
  }
  float denom = 1.0f / (va + vb + vc);
  return (float2)(vb * denom, vc * denom);
}

inline uint vox_fixed(float v, float unit) { return (uint)(v * unit + 0.5f); }
// A signed value in [-1, 1] in fixed point plus GI_VOX_SIGNED_BIAS (voxel_types.h).
inline uint vox_fixed_biased(float v, float unit) { return (uint)((int)rint(v * unit)) + GI_VOX_SIGNED_BIAS; }

// Zeroes the accumulators, level 0 of the radiance chain and the occupancy bits at the voxels the
// previous voxelization listed (`occupied`, `occupiedCount` entries): every other voxel is still
// zero from the buffers' initial fill, so the grid is clear without writing all of it (128³:
// 134 MB of accumulators). GI_VOX_CLEAR_ENTRIES list entries per work-item; launched over
// N³ / GI_VOX_CLEAR_ENTRIES items, as the count is on the device (one item per entry made most of
// the 2M items of 128³ exit at once). Voxels of one occupancy word may clear it from several
// work-items: all store 0.
#define GI_VOX_CLEAR_ENTRIES 32
kernel void vct_clear_occupied(global const uint* occupied, global const uint* occupiedCount, global uint* acc,
                               global float4* level0, global uint* occupancy) {
  uint count = occupiedCount[0];
  size_t first = get_global_id(0) * GI_VOX_CLEAR_ENTRIES;
  for (size_t i = first; i < min(first + GI_VOX_CLEAR_ENTRIES, (size_t)count); ++i) {
    size_t v = occupied[i];
    ((global uint16*)acc)[v] = (uint16)(0u);  // the voxel's whole record (GI_VOX_RECORD = 16)
    level0[v] = (float4)(0.0f);
    occupancy[v >> 5] = 0u;
  }
}

// The occupied list from the occupancy bits (bit v & 31 of word v >> 5 set by vct_voxelize), in
// increasing voxel order, so that the passes over it (clear, injection) walk memory in order and
// the list is the same bits every run. Three passes over spans of GI_VOX_SPAN_WORDS words:
// count the bits of each span, scan the counts (one work-item; N³/2048 spans), write each span's
// voxels from its offset.
#define GI_VOX_SPAN_WORDS 64

kernel void vct_occupancy_count(global const uint* occupancy, uint spans, global uint* spanCounts) {
  size_t s = get_global_id(0);
  if (s >= spans) return;
  global const uint* w = occupancy + s * GI_VOX_SPAN_WORDS;
  uint c = 0;
  for (int k = 0; k < GI_VOX_SPAN_WORDS; ++k) c += popcount(w[k]);
  spanCounts[s] = c;
}

kernel void vct_occupancy_list(global const uint* occupancy, global const uint* spanOffsets, uint spans,
                               global uint* occupied) {
  size_t s = get_global_id(0);
  if (s >= spans) return;
  uint o = spanOffsets[s];
  for (int k = 0; k < GI_VOX_SPAN_WORDS; ++k) {
    uint word = (uint)s * GI_VOX_SPAN_WORDS + k, bits = occupancy[word];
    while (bits != 0u) {
      uint lowest = bits & (0u - bits);
      occupied[o++] = word * 32u + (31u - clz(lowest));
      bits ^= lowest;
    }
  }
}

// Triangle `tri` in voxel units relative to the grid corner: its vertices, its voxel bounding box
// (grown by GI_VOX_GROW, clamped to the grid; empty where lo > hi), the dominant axis k of its face
// normal (the builtin cross product: both kernels walk along this k) and the texture level of
// detail (one voxel face plays the role of a pixel).
typedef struct {
  float3 v0, v1, v2;
  int3 lo, hi;
  int k;
  float lod;
} VoxTriangle;

inline VoxTriangle vox_triangle(GiVoxelGrid grid, global const float4* positions, global const float2* uvs,
                                global const GiMaterial* materials, global const GiTexture* textures, uint4 tri) {
  VoxTriangle r;
  float3 origin = vload3(0, grid.origin);
  float inv = 1.0f / grid.voxel_size;
  r.v0 = (positions[tri.x].xyz - origin) * inv;
  r.v1 = (positions[tri.y].xyz - origin) * inv;
  r.v2 = (positions[tri.z].xyz - origin) * inv;
  float3 lo = fmin(r.v0, fmin(r.v1, r.v2)), hi = fmax(r.v0, fmax(r.v1, r.v2));
  r.lo = max(convert_int3(floor(lo - GI_VOX_GROW)), (int3)(0));
  r.hi = min(convert_int3(floor(hi + GI_VOX_GROW)), (int3)(grid.resolution - 1));
  float3 faceN = cross(r.v1 - r.v0, r.v2 - r.v0);
  float3 an = fabs(faceN);
  r.k = (an.x >= an.y && an.x >= an.z) ? 0 : (an.y >= an.z ? 1 : 2);
  float2 uv0 = uvs[tri.x], uv1 = uvs[tri.y], uv2 = uvs[tri.z];
  float2 duv1 = uv1 - uv0, duv2 = uv2 - uv0;
  float uvArea2 = fabs(duv1.x * duv2.y - duv1.y * duv2.x);
  r.lod = texture_lod(textures, materials[tri.w].base_color_tex, 0.5f * uvArea2, 0.5f * length(faceN));
  return r;
}

kernel void vct_voxelize_trianglewise(GiVoxelGrid grid, global const float4* positions, global const float4* normals,
                         global const float2* uvs, global const uint4* triangles,
                         global const uint* triangleInstance, global const GiMaterial* materials,
                         global const GiTexture* textures, global const uchar4* texels,
                         global const uint* instanceEmits, uint triangleCount, global uint* acc,
                         global uint* occupancy) {
  uint t = get_global_id(0);
  if (t >= triangleCount) return;
  uint4 tri = triangles[t];
  int N = grid.resolution;
  VoxTriangle vt = vox_triangle(grid, positions, uvs, materials, textures, tri);
  int3 ilo = vt.lo, ihi = vt.hi;
  if (any(ilo > ihi)) return;
  float3 v0 = vt.v0, v1 = vt.v1, v2 = vt.v2;

  global const GiMaterial* m = &materials[tri.w];
  bool emits = instanceEmits[triangleInstance[t]] != 0u;
  float lod = vt.lod;
  float2 uv0 = uvs[tri.x], uv1 = uvs[tri.y], uv2 = uvs[tri.z];
  float3 n0 = normals[tri.x].xyz, n1 = normals[tri.y].xyz, n2 = normals[tri.z].xyz;
  float h = 0.5f * (1.0f + GI_VOX_GROW);

  // Walk columns along the dominant axis k of the face normal; (a, b) are the other two axes.
  int k = vt.k;
  int ia = k == 0 ? 1 : 0, ib = k == 2 ? 1 : 2;
  float3 planeN = vox_cross(v1 - v0, v2 - v0);  // written out, as vct_voxelize's lanes
  float nk = k == 0 ? planeN.x : (k == 1 ? planeN.y : planeN.z);
  float na = ia == 0 ? planeN.x : planeN.y, nb = ib == 1 ? planeN.y : planeN.z;
  float d = vox_dot(planeN, v0);
  int loA = ia == 0 ? ilo.x : ilo.y, hiA = ia == 0 ? ihi.x : ihi.y;
  int loB = ib == 1 ? ilo.y : ilo.z, hiB = ib == 1 ? ihi.y : ihi.z;
  int loK = k == 0 ? ilo.x : (k == 1 ? ilo.y : ilo.z), hiK = k == 0 ? ihi.x : (k == 1 ? ihi.y : ihi.z);
  for (int b = loB; b <= hiB; ++b) {
    for (int a = loA; a <= hiA; ++a) {
      int k0 = loK, k1 = hiK;
      // Only for triangles whose normal is well defined (not slivers degenerated to a segment).
      if (fabs(nk) > 1e-3f * sqrt(vox_dot(v1 - v0, v1 - v0)) * sqrt(vox_dot(v2 - v0, v2 - v0))) {
        // The plane's k-range over the column's (grown) square: extremes at its corners.
        float a0 = (float)a - GI_VOX_GROW, a1 = (float)(a + 1) + GI_VOX_GROW;
        float b0 = (float)b - GI_VOX_GROW, b1 = (float)(b + 1) + GI_VOX_GROW;
        float ka = -na / nk, kb = -nb / nk, kc = d / nk;
        float kmin = kc + fmin(ka * a0, ka * a1) + fmin(kb * b0, kb * b1);
        float kmax = kc + fmax(ka * a0, ka * a1) + fmax(kb * b0, kb * b1);
        k0 = max(k0, (int)floor(kmin - GI_VOX_GROW) - 1);
        k1 = min(k1, (int)floor(kmax + GI_VOX_GROW) + 1);
      }
      for (int kk = k0; kk <= k1; ++kk) {
        int3 vi = k == 0 ? (int3)(kk, a, b) : (k == 1 ? (int3)(a, kk, b) : (int3)(a, b, kk));
        float3 c = convert_float3(vi) + 0.5f;
        if (!tri_box_overlap(v0 - c, v1 - c, v2 - c, h)) continue;
        float2 bc = nearest_on_triangle(c, v0, v1, v2);
        float w0 = 1.0f - bc.x - bc.y;
        float3 p = w0 * v0 + bc.x * v1 + bc.y * v2;
        float2 uv = w0 * uv0 + bc.x * uv1 + bc.y * uv2;
        float opacity = material_cut_out(m, textures, texels, uv, lod) ? 0.0f : 1.0f;
        size_t v = (size_t)(vi.z * N + vi.y) * N + vi.x;
        // The first triangle to reach a voxel marks it occupied.
        global uint* record = acc + v * GI_VOX_RECORD;
        if (atomic_inc(record + GI_VOX_COUNT) == 0u) atomic_or(occupancy + (v >> 5), 1u << (v & 31));
        // Cut away here: the voxel counts the triangle, with nothing to add.
        if (opacity == 0.0f) continue;
        SurfaceSample sm = eval_material(m, textures, texels, uv, lod);
        float3 sn = w0 * n0 + bc.x * n1 + bc.y * n2;
        float snLength2 = vox_dot(sn, sn);  // safe_normalize, with the dot product written out
        sn = snLength2 > 1e-30f ? sn * rsqrt(snLength2) : planeN * rsqrt(vox_dot(planeN, planeN));
        float3 em = emits ? fmin(sm.emission, GI_VOX_EMISSION_MAX) : (float3)(0.0f);
        float3 off = clamp(p - c, -1.0f, 1.0f);
        atomic_add(record + GI_VOX_ALBEDO + 0, vox_fixed(clamp(sm.diffuse.x, 0.0f, 1.0f), GI_VOX_UNIT));
        atomic_add(record + GI_VOX_ALBEDO + 1, vox_fixed(clamp(sm.diffuse.y, 0.0f, 1.0f), GI_VOX_UNIT));
        atomic_add(record + GI_VOX_ALBEDO + 2, vox_fixed(clamp(sm.diffuse.z, 0.0f, 1.0f), GI_VOX_UNIT));
        if (emits) {
          atomic_add(record + GI_VOX_EMISSION + 0, vox_fixed(em.x, GI_VOX_EMISSION_UNIT));
          atomic_add(record + GI_VOX_EMISSION + 1, vox_fixed(em.y, GI_VOX_EMISSION_UNIT));
          atomic_add(record + GI_VOX_EMISSION + 2, vox_fixed(em.z, GI_VOX_EMISSION_UNIT));
        }
        atomic_add(record + GI_VOX_NORMAL + 0, vox_fixed_biased(sn.x, 0.25f * GI_VOX_UNIT));
        atomic_add(record + GI_VOX_NORMAL + 1, vox_fixed_biased(sn.y, 0.25f * GI_VOX_UNIT));
        atomic_add(record + GI_VOX_NORMAL + 2, vox_fixed_biased(sn.z, 0.25f * GI_VOX_UNIT));
        atomic_add(record + GI_VOX_OFFSET + 0, vox_fixed_biased(off.x, 0.25f * GI_VOX_UNIT));
        atomic_add(record + GI_VOX_OFFSET + 1, vox_fixed_biased(off.y, 0.25f * GI_VOX_UNIT));
        atomic_add(record + GI_VOX_OFFSET + 2, vox_fixed_biased(off.z, 0.25f * GI_VOX_UNIT));
        atomic_add(record + GI_VOX_OPACITY, vox_fixed(opacity, GI_VOX_UNIT));
      }
    }
  }
}

// ---- Voxelization in lanes (vct_voxelize): the triangle's voxel columns spread over SIMD lanes ----
//
// vct_voxelize_trianglewise above gives each triangle one work-item, which walks its columns one
// voxel at a time in scalar code: Sponza at 128³ has 262k triangles, half of them inside one voxel
// and a few hundred crossing thousands (load imbalance), and a loop per work-item leaves the
// SIMD lanes of the CPU idle (PERFORMANCE_FACTS point 1). Here the unit of work is a voxel column
// of a triangle (the voxels along the dominant normal axis k above one (a, b) cell of its bounding
// box, trimmed to where its plane can reach): vct_triangle_columns counts each triangle's columns,
// vct_exclusive_scan turns the counts into each triangle's first column in one list of all
// columns, and vct_voxelize gives each lane of a work-item one column of that list (GI_VW
// consecutive columns; each work-item takes one contiguous run of them), so small and large
// triangles fill the lanes alike. Each lane walks its column (2–3 voxels) with the same
// separating-axis test, nearest point, material and fixed-point values as the trianglewise
// kernel, lane-wise; the integer atomics (order-independent: ALGORITHMS.md §7) are issued per
// lane. Same bits as vct_voxelize_trianglewise (test VctVoxelize.LanesMatchOneTriangleAtATime).

// Per-triangle setup written by vct_triangle_columns (uint4): x = lo.x | lo.y << 8 | lo.z << 16 |
// k << 24 and y = hi.x | hi.y << 8 | hi.z << 16 (the clamped voxel bounding box, N <= 256, and the
// dominant axis of the face normal), z = the texture level of detail (float bits).
#define GI_VOX_UNPACK(p, s) convert_intV(((p) >> (s)) & 0xFFu)

kernel void vct_triangle_columns(GiVoxelGrid grid, global const float4* positions, global const float2* uvs,
                                 global const uint4* triangles, global const GiMaterial* materials,
                                 global const GiTexture* textures, uint triangleCount, global uint4* setup,
                                 global uint* columnCounts) {
  uint t = get_global_id(0);
  if (t >= triangleCount) return;
  VoxTriangle vt = vox_triangle(grid, positions, uvs, materials, textures, triangles[t]);
  int3 dim = vt.hi - vt.lo + 1;
  int k = vt.k;
  uint columns = any(vt.lo > vt.hi) ? 0u : (uint)(k == 0 ? dim.y * dim.z : (k == 1 ? dim.x * dim.z : dim.x * dim.y));
  columnCounts[t] = columns;
  setup[t] = (uint4)((uint)vt.lo.x | (uint)vt.lo.y << 8 | (uint)vt.lo.z << 16 | (uint)k << 24,
                     (uint)vt.hi.x | (uint)vt.hi.y << 8 | (uint)vt.hi.z << 16, as_uint(vt.lod), 0u);
}

// Exclusive prefix sum of counts[0 .. n) in place, the total to total[0]: one work-item (n is at
// most a few hundred thousand; a serial pass is well under a millisecond).
kernel void vct_exclusive_scan(global uint* counts, uint n, global uint* total) {
  if (get_global_id(0) != 0) return;
  uint sum = 0;
  for (uint s = 0; s < n; ++s) {
    uint c = counts[s];
    counts[s] = sum;
    sum += c;
  }
  total[0] = sum;
}

// Largest lane value (GI_VW lanes).

// tri_box_overlap() lane-wise: the same expressions, each lane its own triangle and box.
inline intV tri_box_overlapV(float3V a, float3V b, float3V c, float h) {
  intV ok = !((fmin(a.x, fmin(b.x, c.x)) > h) | (fmax(a.x, fmax(b.x, c.x)) < -h));
  ok &= !((fmin(a.y, fmin(b.y, c.y)) > h) | (fmax(a.y, fmax(b.y, c.y)) < -h));
  ok &= !((fmin(a.z, fmin(b.z, c.z)) > h) | (fmax(a.z, fmax(b.z, c.z)) < -h));
  if (!GI_ANY(ok)) return ok;
  float3V e0 = subV(b, a), e1 = subV(c, b), e2 = subV(a, c);
  float3V n = crossV(e0, e1);
  floatV r = h * (fabs(n.x) + fabs(n.y) + fabs(n.z));
  floatV tol = 8.0f * FLT_EPSILON * sqrt(dotV(e0, e0)) * sqrt(dotV(e1, e1)) * (fabs(a.x) + fabs(a.y) + fabs(a.z) + h);
  ok &= !(fabs(dotV(n, a)) > r + tol);
  // Edge × box axis (9 axes): project the 3 vertices and the box on u.
#define GI_VOX_EDGE_AXIS(pa, pb, pc, rad) \
  ok &= !((fmin(pa, fmin(pb, pc)) > (rad)) | (fmax(pa, fmax(pb, pc)) < -(rad)));
#define GI_VOX_EDGE(e)                                                                                        \
  GI_VOX_EDGE_AXIS(e.z * a.y - e.y * a.z, e.z * b.y - e.y * b.z, e.z * c.y - e.y * c.z, h * (fabs(e.z) + fabs(e.y))) \
  GI_VOX_EDGE_AXIS(-e.z * a.x + e.x * a.z, -e.z * b.x + e.x * b.z, -e.z * c.x + e.x * c.z, h * (fabs(e.z) + fabs(e.x))) \
  GI_VOX_EDGE_AXIS(e.y * a.x - e.x * a.y, e.y * b.x - e.x * b.y, e.y * c.x - e.x * c.y, h * (fabs(e.y) + fabs(e.x)))
  GI_VOX_EDGE(e0)
  GI_VOX_EDGE(e1)
  GI_VOX_EDGE(e2)
#undef GI_VOX_EDGE
#undef GI_VOX_EDGE_AXIS
  return ok;
}

// nearest_on_triangle() lane-wise: every region's answer, the first region that applies chosen
// (the scalar function's early returns in reverse order).
inline void nearest_on_triangleV(float3V p, float3V a, float3V b, float3V c, floatV* bu, floatV* bv) {
  float3V ab = subV(b, a), ac = subV(c, a), ap = subV(p, a);
  floatV d1 = dotV(ab, ap), d2 = dotV(ac, ap);
  float3V bp = subV(p, b);
  floatV d3 = dotV(ab, bp), d4 = dotV(ac, bp);
  floatV vc = d1 * d4 - d3 * d2;
  float3V cp = subV(p, c);
  floatV d5 = dotV(ab, cp), d6 = dotV(ac, cp);
  floatV vb = d5 * d2 - d1 * d6;
  floatV va = d3 * d6 - d5 * d4;
  floatV zero = (floatV)(0.0f), one = (floatV)(1.0f);
  floatV denom = 1.0f / (va + vb + vc);
  floatV u = vb * denom, v = vc * denom;
  floatV w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
  intV m = (va <= 0.0f) & ((d4 - d3) >= 0.0f) & ((d5 - d6) >= 0.0f);
  u = GI_SEL(u, one - w, m);
  v = GI_SEL(v, w, m);
  m = (vb <= 0.0f) & (d2 >= 0.0f) & (d6 <= 0.0f);
  u = GI_SEL(u, zero, m);
  v = GI_SEL(v, d2 / (d2 - d6), m);
  m = (d6 >= 0.0f) & (d5 <= d6);
  u = GI_SEL(u, zero, m);
  v = GI_SEL(v, one, m);
  m = (vc <= 0.0f) & (d1 >= 0.0f) & (d3 <= 0.0f);
  u = GI_SEL(u, d1 / (d1 - d3), m);
  v = GI_SEL(v, zero, m);
  m = (d3 >= 0.0f) & (d4 <= d3);
  u = GI_SEL(u, one, m);
  v = GI_SEL(v, zero, m);
  m = (d1 <= 0.0f) & (d2 <= 0.0f);
  *bu = GI_SEL(u, zero, m);
  *bv = GI_SEL(v, zero, m);
}

// Adds one triangle–voxel pair (lane l of `fields`: the fixed-point values of voxel_types.h's
// fields 0 … 11) to voxel v's record, as vct_voxelize_trianglewise does with one 32-bit atomic per
// field. Same sums, fewer atomics: additions of 0 are skipped (most pairs emit nothing), and with
// 64-bit atomics the fields go in pairs of adjacent words (albedo R+G, albedo B + emission R,
// emission G+B, normal x+y, normal z + offset x, offset y+z, opacity + count: every addend is
// non-negative (the signed fields biased, voxel_types.h) and no field's sum exceeds 32 bits, so
// the low word never carries into the high one).
#ifdef cl_khr_int64_base_atomics
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#define GI_VOX_PAIR(lo, hi) ((ulong)(lo) | (ulong)(hi) << 32)
#endif
inline void vox_accumulate(global uint* acc, global uint* occupancy, size_t v, int kept, int emits,
                           uint fields[GI_VOX_FIELDS - 2][GI_VW], int l) {
  global uint* record = acc + v * GI_VOX_RECORD;
  uint opacity = kept ? vox_fixed(1.0f, GI_VOX_UNIT) : 0u;  // cut away: counts the triangle, adds nothing
#ifdef cl_khr_int64_base_atomics
  global ulong* pairs = (global ulong*)record;
  uint count = (uint)(atom_add(pairs + GI_VOX_OPACITY / 2, GI_VOX_PAIR(opacity, 1u)) >> 32);
#else
  uint count = atomic_inc(record + GI_VOX_COUNT);
  if (kept) atomic_add(record + GI_VOX_OPACITY, opacity);
#endif
  // The first triangle to reach a voxel marks it occupied.
  if (count == 0u) atomic_or(occupancy + (v >> 5), 1u << (v & 31));
  if (!kept) return;
  uint emR = emits ? fields[GI_VOX_EMISSION][l] : 0u, emG = emits ? fields[GI_VOX_EMISSION + 1][l] : 0u;
  uint emB = emits ? fields[GI_VOX_EMISSION + 2][l] : 0u;
#ifdef cl_khr_int64_base_atomics
  ulong rg = GI_VOX_PAIR(fields[GI_VOX_ALBEDO][l], fields[GI_VOX_ALBEDO + 1][l]);
  ulong be = GI_VOX_PAIR(fields[GI_VOX_ALBEDO + 2][l], emR), gb = GI_VOX_PAIR(emG, emB);
  if (rg != 0ul) atom_add(pairs + GI_VOX_ALBEDO / 2, rg);
  if (be != 0ul) atom_add(pairs + (GI_VOX_ALBEDO + 2) / 2, be);
  if (gb != 0ul) atom_add(pairs + (GI_VOX_EMISSION + 1) / 2, gb);
#else
  uint unsignedFields[6] = {fields[GI_VOX_ALBEDO][l], fields[GI_VOX_ALBEDO + 1][l], fields[GI_VOX_ALBEDO + 2][l], emR, emG, emB};
  for (int f = 0; f < 6; ++f)
    if (unsignedFields[f] != 0u) atomic_add(record + GI_VOX_ALBEDO + f, unsignedFields[f]);
#endif
#ifdef cl_khr_int64_base_atomics
  for (int f = GI_VOX_NORMAL; f < GI_VOX_OFFSET + 3; f += 2) atom_add(pairs + f / 2, GI_VOX_PAIR(fields[f][l], fields[f + 1][l]));
#else
  for (int f = GI_VOX_NORMAL; f < GI_VOX_OFFSET + 3; ++f) atomic_add(record + f, fields[f][l]);
#endif
}

// The column walk of the trianglewise kernel for columns `first` … first + GI_VW − 1 of the list.
inline void vox_columns(GiVoxelGrid grid, uint first, uint total, global const float4* positions,
                        global const float4* normals, global const float2* uvs, global const uint4* triangles,
                        global const uint* triangleInstance, global const GiMaterial* materials,
                        global const GiTexture* textures, global const uchar4* texels,
                        global const uint* instanceEmits, uint triangleCount, global const uint4* setup,
                        global const uint* columnStart, global uint* acc, global uint* occupancy, uint* t0) {
  int N = grid.resolution;
  uintV column = (uintV)(first) + as_uintV(GI_LANES);
  intV valid = column < total;
  column = min(column, (uintV)(total - 1u));
  // The lane's triangle: the last one whose first column is <= column (triangles without columns
  // share their successor's first column and are skipped), found by stepping forward from *t0,
  // the triangle of the work-item's previous column (a group's lanes are a few triangles apart).
  uintV t = (uintV)(*t0);
  for (;;) {
    uintV next = min(t + 1u, (uintV)(triangleCount - 1u));
    intV advance = (next > t) & (GI_GATHER(uintV, columnStart, next) <= column);
    if (!GI_ANY(advance)) break;
    t = GI_SEL(t, next, advance);
  }
  *t0 = lane_max_int(convert_intV(t));
  intV j = convert_intV(column - GI_GATHER(uintV, columnStart, t));
  global const uint* setupU = (global const uint*)setup;
  uintV loP, hiP, lodBits, unused;
  GI_GATHER_AOS4(uint, setupU, t, loP, hiP, lodBits, unused)
  intV k = GI_VOX_UNPACK(loP, 24);
  intV lox = GI_VOX_UNPACK(loP, 0), loy = GI_VOX_UNPACK(loP, 8), loz = GI_VOX_UNPACK(loP, 16);
  intV hix = GI_VOX_UNPACK(hiP, 0), hiy = GI_VOX_UNPACK(hiP, 8), hiz = GI_VOX_UNPACK(hiP, 16);
  // Column axes: a = the first, b = the second axis other than k.
  intV kx = k == 0, ky = k == 1;
  intV loA = GI_SEL(lox, loy, kx), hiA = GI_SEL(hix, hiy, kx);
  intV loB = GI_SEL(loz, loy, k == 2), hiB = GI_SEL(hiz, hiy, k == 2);
  intV loK = GI_SEL(GI_SEL(loz, loy, ky), lox, kx), hiK = GI_SEL(GI_SEL(hiz, hiy, ky), hix, kx);
  intV dA = hiA - loA + 1;
  // j / dA exactly in float (j < 2^16 columns per triangle at N <= 256).
  intV row = convert_intV(convert_floatV(j) / convert_floatV(dA));
  intV a = loA + (j - row * dA), b = loB + row;

  global const uint* triU = (global const uint*)triangles;
  uintV i0, i1, i2, mat;
  GI_GATHER_AOS4(uint, triU, t, i0, i1, i2, mat)
  global const float* posF = (global const float*)positions;
  float3V v0, v1, v2;
  floatV unusedW;
  GI_GATHER_AOS4(float, posF, i0, v0.x, v0.y, v0.z, unusedW)
  GI_GATHER_AOS4(float, posF, i1, v1.x, v1.y, v1.z, unusedW)
  GI_GATHER_AOS4(float, posF, i2, v2.x, v2.y, v2.z, unusedW)
  float inv = 1.0f / grid.voxel_size;
  float3V origin = f3v((floatV)(grid.origin[0]), (floatV)(grid.origin[1]), (floatV)(grid.origin[2]));
  v0 = scaleV(subV(v0, origin), (floatV)(inv));
  v1 = scaleV(subV(v1, origin), (floatV)(inv));
  v2 = scaleV(subV(v2, origin), (floatV)(inv));
  float3V faceN = crossV(subV(v1, v0), subV(v2, v0));
  floatV nk = GI_SEL(GI_SEL(faceN.z, faceN.y, ky), faceN.x, kx);
  floatV na = GI_SEL(faceN.x, faceN.y, kx), nb = GI_SEL(faceN.z, faceN.y, k == 2);
  floatV d = dotV(faceN, v0);
  // The column's k-range: the trianglewise kernel's.
  intV k0 = loK, k1 = hiK;
  {
    float3V e0 = subV(v1, v0), e2 = subV(v2, v0);
    intV plane = fabs(nk) > 1e-3f * sqrt(dotV(e0, e0)) * sqrt(dotV(e2, e2));
    floatV a0 = convert_floatV(a) - GI_VOX_GROW, a1 = convert_floatV(a + 1) + GI_VOX_GROW;
    floatV b0 = convert_floatV(b) - GI_VOX_GROW, b1 = convert_floatV(b + 1) + GI_VOX_GROW;
    floatV ka = -na / nk, kb = -nb / nk, kc = d / nk;
    floatV kmin = kc + fmin(ka * a0, ka * a1) + fmin(kb * b0, kb * b1);
    floatV kmax = kc + fmax(ka * a0, ka * a1) + fmax(kb * b0, kb * b1);
    k0 = GI_SEL(k0, max(k0, convert_intV(floor(kmin - GI_VOX_GROW)) - 1), plane);
    k1 = GI_SEL(k1, min(k1, convert_intV(floor(kmax + GI_VOX_GROW)) + 1), plane);
  }
  intV steps = GI_SEL((intV)(0), max(k1 - k0 + 1, 0), valid);
  int maxSteps = lane_max_int(steps);
  if (maxSteps == 0) return;

  // Per-lane triangle attributes, read once per column.
  global const float* uvF = (global const float*)uvs;
  floatV u0, w0v, u1, w1v, u2, w2v;
  GI_GATHER_AOS2(float, uvF, i0, u0, w0v)
  GI_GATHER_AOS2(float, uvF, i1, u1, w1v)
  GI_GATHER_AOS2(float, uvF, i2, u2, w2v)
  global const float* nrmF = (global const float*)normals;
  float3V n0, n1, n2;
  GI_GATHER_AOS4(float, nrmF, i0, n0.x, n0.y, n0.z, unusedW)
  GI_GATHER_AOS4(float, nrmF, i1, n1.x, n1.y, n1.z, unusedW)
  GI_GATHER_AOS4(float, nrmF, i2, n2.x, n2.y, n2.z, unusedW)
  float3V faceUnit = scaleV(faceN, rsqrt(dotV(faceN, faceN)));
  // GiMaterial: 20 words = five 4-word records: base colour | emissive, metallic | roughness,
  // alpha cutoff, normal scale, alpha mode | textures (base, metallic-roughness, normal, emissive).
  global const float* mf = (global const float*)materials;
  global const int* mi = (global const int*)materials;
  uintV m5 = mat * 5u;
  floatV baseR, baseG, baseB, baseA, emR, emG, emB, metallicF, unusedF, cutoff, unusedScale;
  intV baseTex, mrTex, unusedNormalTex, emTex;
  GI_GATHER_AOS4(float, mf, m5, baseR, baseG, baseB, baseA)
  GI_GATHER_AOS4(float, mf, m5 + 1u, emR, emG, emB, metallicF)
  intV mode, unusedR, unusedC, unusedS;
  GI_GATHER_AOS4(float, mf, m5 + 2u, unusedF, cutoff, unusedScale, unusedF)
  GI_GATHER_AOS4(int, mi, m5 + 2u, unusedR, unusedC, unusedS, mode)
  GI_GATHER_AOS4(int, mi, m5 + 3u, baseTex, mrTex, unusedNormalTex, emTex)
  intV masked = mode == GI_ALPHA_MASK;
  uintV instance = GI_GATHER(uintV, triangleInstance, t);
  intV emits = GI_GATHER(intV, (global const int*)instanceEmits, instance) != 0;
  floatV lod = as_floatV(lodBits);
  intV hasBase = baseTex >= 0, hasMr = mrTex >= 0, hasEm = emTex >= 0;
  GiTexLevelV baseLevel, mrLevel, emLevel;
  if (GI_ANY(hasBase)) baseLevel = texture_levelV(textures, baseTex, lod);
  if (GI_ANY(hasMr)) mrLevel = texture_levelV(textures, mrTex, lod);
  if (GI_ANY(hasEm)) emLevel = texture_levelV(textures, emTex, lod);
  float h = 0.5f * (1.0f + GI_VOX_GROW);

  for (int s = 0; s < maxSteps; ++s) {
    intV kk = k0 + s;
    intV x = GI_SEL(a, kk, kx), y = GI_SEL(GI_SEL(b, kk, ky), a, kx), z = GI_SEL(b, kk, k == 2);
    float3V c = f3v(convert_floatV(x) + 0.5f, convert_floatV(y) + 0.5f, convert_floatV(z) + 0.5f);
    intV hit = (s < steps) & tri_box_overlapV(subV(v0, c), subV(v1, c), subV(v2, c), h);
    if (!GI_ANY(hit)) continue;
    intV voxel = (z * N + y) * N + x;
    floatV bu, bv;
    nearest_on_triangleV(c, v0, v1, v2, &bu, &bv);
    floatV w0 = 1.0f - bu - bv;
    float3V p = f3v(w0 * v0.x + bu * v1.x + bv * v2.x, w0 * v0.y + bu * v1.y + bv * v2.y,
                    w0 * v0.z + bu * v1.z + bv * v2.z);
    floatV u = w0 * u0 + bu * u1 + bv * u2, v = w0 * w0v + bu * w1v + bv * w2v;
    // eval_material() (and material_cut_out()) lane-wise; base colour sampled once for both.
    floatV cr = baseR, cg = baseG, cb = baseB, ca = baseA;
    intV sampleBase = hit & hasBase;
    if (GI_ANY(sampleBase)) {
      float4V tx = sample_texture_levelV(texels, baseLevel, u, v);
      cr *= GI_SEL((floatV)(1.0f), tx.x, hasBase);
      cg *= GI_SEL((floatV)(1.0f), tx.y, hasBase);
      cb *= GI_SEL((floatV)(1.0f), tx.z, hasBase);
      ca *= GI_SEL((floatV)(1.0f), tx.w, hasBase);
    }
    intV cut = masked & (ca < cutoff);
    intV kept = hit & !cut;
    floatV metallic = metallicF;
    if (GI_ANY(kept & hasMr)) metallic = GI_SEL(metallic, metallic * sample_texture_levelV(texels, mrLevel, u, v).z, hasMr);
    metallic = clamp(metallic, 0.0f, 1.0f);
    float3V em = f3v(emR, emG, emB);
    if (GI_ANY(kept & hasEm & emits)) {
      float4V e = sample_texture_levelV(texels, emLevel, u, v);
      em = selV(em, f3v(emR * e.x, emG * e.y, emB * e.z), hasEm);
    }
    em = f3v(fmin(em.x, GI_VOX_EMISSION_MAX), fmin(em.y, GI_VOX_EMISSION_MAX), fmin(em.z, GI_VOX_EMISSION_MAX));
    float3V sn = safe_normalizeV(f3v(w0 * n0.x + bu * n1.x + bv * n2.x, w0 * n0.y + bu * n1.y + bv * n2.y,
                                     w0 * n0.z + bu * n1.z + bv * n2.z), faceUnit);
    float3V off = f3v(clamp(p.x - c.x, -1.0f, 1.0f), clamp(p.y - c.y, -1.0f, 1.0f), clamp(p.z - c.z, -1.0f, 1.0f));
    // Fixed-point values (vox_fixed, vox_fixed_biased) of the lanes.
    uint fields[GI_VOX_FIELDS - 2][GI_VW];
#define GI_VOX_U(f, val) vstoreV(convert_uintV((val) * GI_VOX_UNIT + 0.5f), 0, fields[f]);
#define GI_VOX_E(f, val) vstoreV(convert_uintV((val) * GI_VOX_EMISSION_UNIT + 0.5f), 0, fields[f]);
#define GI_VOX_S(f, val) vstoreV(as_uintV(convert_intV(rint((val) * (0.25f * GI_VOX_UNIT)))) + GI_VOX_SIGNED_BIAS, 0, fields[f]);
    GI_VOX_U(GI_VOX_ALBEDO + 0, clamp(cr * (1.0f - metallic), 0.0f, 1.0f))
    GI_VOX_U(GI_VOX_ALBEDO + 1, clamp(cg * (1.0f - metallic), 0.0f, 1.0f))
    GI_VOX_U(GI_VOX_ALBEDO + 2, clamp(cb * (1.0f - metallic), 0.0f, 1.0f))
    GI_VOX_E(GI_VOX_EMISSION + 0, em.x)
    GI_VOX_E(GI_VOX_EMISSION + 1, em.y)
    GI_VOX_E(GI_VOX_EMISSION + 2, em.z)
    GI_VOX_S(GI_VOX_NORMAL + 0, sn.x)
    GI_VOX_S(GI_VOX_NORMAL + 1, sn.y)
    GI_VOX_S(GI_VOX_NORMAL + 2, sn.z)
    GI_VOX_S(GI_VOX_OFFSET + 0, off.x)
    GI_VOX_S(GI_VOX_OFFSET + 1, off.y)
    GI_VOX_S(GI_VOX_OFFSET + 2, off.z)
#undef GI_VOX_U
#undef GI_VOX_E
#undef GI_VOX_S
    int vl[GI_VW], hl[GI_VW], kl[GI_VW], el[GI_VW];
    vstoreV(voxel, 0, vl);
    vstoreV(hit, 0, hl);
    vstoreV(kept, 0, kl);
    vstoreV(emits, 0, el);
    for (int l = 0; l < GI_VW; ++l)
      if (hl[l]) vox_accumulate(acc, occupancy, (size_t)vl[l], kl[l], el[l], fields, l);
  }
}

kernel void vct_voxelize(GiVoxelGrid grid, global const float4* positions, global const float4* normals,
                         global const float2* uvs, global const uint4* triangles,
                         global const uint* triangleInstance, global const GiMaterial* materials,
                         global const GiTexture* textures, global const uchar4* texels,
                         global const uint* instanceEmits, uint triangleCount, global const uint4* setup,
                         global const uint* columnStart, global const uint* columnTotal, global uint* acc,
                         global uint* occupancy) {
  // A fixed number of work-items (the column count is on the device), each taking one contiguous
  // run of groups of GI_VW columns: consecutive triangles, so its search for each lane's triangle
  // steps forward from the last one, and its voxels are mostly neighbours (cache lines, pages).
  uint total = columnTotal[0];
  uint groups = (total + GI_VW - 1) / GI_VW, items = (uint)get_global_size(0), g = (uint)get_global_id(0);
  uint begin = (uint)(((ulong)groups * g) / items), end = (uint)(((ulong)groups * (g + 1)) / items);
  if (begin >= end) return;
  // The triangle of the first column: binary search for the last first column <= it.
  uint first = begin * GI_VW, t0 = 0;
  for (uint step = 1u << (31 - clz(triangleCount)); step > 0u; step >>= 1)
    if (t0 + step < triangleCount && columnStart[t0 + step] <= first) t0 += step;
  for (uint group = begin; group < end; ++group)
    vox_columns(grid, group * GI_VW, total, positions, normals, uvs, triangles, triangleInstance, materials, textures,
                texels, instanceEmits, triangleCount, setup, columnStart, acc, occupancy, &t0);
}
