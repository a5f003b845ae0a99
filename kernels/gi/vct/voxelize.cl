// Voxelization in compute (ALGORITHMS.md §5; Crassin et al. 2011 as in seed 003 §3.4.1, without
// the hardware rasterizer): every triangle adds its material to every voxel it overlaps.
//
// One work-item per triangle. It walks the voxel columns along the triangle's dominant normal axis
// (only the few voxels of each column that the triangle's plane can reach), keeps the voxels that
// pass the separating-axis triangle–box test (Akenine-Möller 2001: 3 box normals, the triangle
// normal, 9 edge cross products) against the voxel grown by GI_VOX_GROW (conservative under float
// rounding: a voxel the triangle touches is never missed), and adds, with integer atomics (order-
// independent, so bit-identical run to run: ALGORITHMS.md §7), the material at the triangle's
// point nearest the voxel centre. See voxel_types.h for the accumulator records.
#include "common/material.h"
#include "gi/vct/voxel_types.h"

#define GI_VOX_GROW 1e-4f  // relative growth of the voxel for the overlap test

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
  float3 n = cross(e0, e1);
  float r = h * (fabs(n.x) + fabs(n.y) + fabs(n.z));
  float tol = 8.0f * FLT_EPSILON * length(e0) * length(e1) * (fabs(a.x) + fabs(a.y) + fabs(a.z) + h);
  if (fabs(dot(n, a)) > r + tol) return false;
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
  float d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return (float2)(0.0f, 0.0f);
  float3 bp = p - b;
  float d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return (float2)(1.0f, 0.0f);
  float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return (float2)(d1 / (d1 - d3), 0.0f);
  float3 cp = p - c;
  float d5 = dot(ab, cp), d6 = dot(ac, cp);
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
inline int vox_fixed_signed(float v, float unit) { return (int)rint(v * unit); }

// Zeroes the accumulators, level 0 of the radiance chain and the occupancy bits at the voxels the
// previous voxelization listed (`occupied`, `occupiedCount` entries): every other voxel is still
// zero from the buffers' initial fill, so the grid is clear without writing all of it (128³:
// 134 MB of accumulators). One work-item per listed voxel; launched over N³ items, as the count is
// on the device. Voxels of one occupancy word may clear it from several work-items: all store 0.
kernel void vct_clear_occupied(global const uint* occupied, global const uint* occupiedCount, global uint* acc,
                               global float4* level0, global uint* occupancy) {
  size_t i = get_global_id(0);
  if (i >= occupiedCount[0]) return;
  size_t v = occupied[i];
  ((global uint16*)acc)[v] = (uint16)(0u);  // the voxel's whole record (GI_VOX_RECORD = 16)
  level0[v] = (float4)(0.0f);
  occupancy[v >> 5] = 0u;
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

kernel void vct_occupancy_scan(global uint* spanCounts, uint spans, global uint* occupiedCount) {
  if (get_global_id(0) != 0) return;
  uint total = 0;
  for (uint s = 0; s < spans; ++s) {
    uint c = spanCounts[s];
    spanCounts[s] = total;  // exclusive prefix sum: the span's first list entry
    total += c;
  }
  occupiedCount[0] = total;
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

kernel void vct_voxelize(GiVoxelGrid grid, global const float4* positions, global const float4* normals,
                         global const float2* uvs, global const uint4* triangles,
                         global const uint* triangleInstance, global const GiMaterial* materials,
                         global const GiTexture* textures, global const uchar4* texels,
                         global const uint* instanceEmits, uint triangleCount, global uint* acc,
                         global uint* occupancy) {
  uint t = get_global_id(0);
  if (t >= triangleCount) return;
  uint4 tri = triangles[t];
  float3 origin = vload3(0, grid.origin);
  float s = grid.voxel_size, inv = 1.0f / s;
  int N = grid.resolution;
  // Vertices in voxel units relative to the grid corner.
  float3 v0 = (positions[tri.x].xyz - origin) * inv;
  float3 v1 = (positions[tri.y].xyz - origin) * inv;
  float3 v2 = (positions[tri.z].xyz - origin) * inv;
  float3 lo = fmin(v0, fmin(v1, v2)), hi = fmax(v0, fmax(v1, v2));
  int3 ilo = max(convert_int3(floor(lo - GI_VOX_GROW)), (int3)(0));
  int3 ihi = min(convert_int3(floor(hi + GI_VOX_GROW)), (int3)(N - 1));
  if (any(ilo > ihi)) return;

  global const GiMaterial* m = &materials[tri.w];
  bool emits = instanceEmits[triangleInstance[t]] != 0u;
  float3 faceN = cross(v1 - v0, v2 - v0);
  float area2 = length(faceN);  // twice the area, in voxels²
  float2 uv0 = uvs[tri.x], uv1 = uvs[tri.y], uv2 = uvs[tri.z];
  float2 duv1 = uv1 - uv0, duv2 = uv2 - uv0;
  float uvArea2 = fabs(duv1.x * duv2.y - duv1.y * duv2.x);
  // Texture level of detail: one voxel face plays the role of a pixel.
  float lod = texture_lod(textures, m->base_color_tex, 0.5f * uvArea2, 0.5f * area2);
  float3 n0 = normals[tri.x].xyz, n1 = normals[tri.y].xyz, n2 = normals[tri.z].xyz;
  float h = 0.5f * (1.0f + GI_VOX_GROW);

  // Walk columns along the dominant axis k of the face normal; (i, j) are the other two axes.
  float3 an = fabs(faceN);
  int k = (an.x >= an.y && an.x >= an.z) ? 0 : (an.y >= an.z ? 1 : 2);
  int ia = k == 0 ? 1 : 0, ib = k == 2 ? 1 : 2;
  float nk = k == 0 ? faceN.x : (k == 1 ? faceN.y : faceN.z);
  float na = ia == 0 ? faceN.x : faceN.y, nb = ib == 1 ? faceN.y : faceN.z;
  float d = dot(faceN, v0);
  int loA = ia == 0 ? ilo.x : ilo.y, hiA = ia == 0 ? ihi.x : ihi.y;
  int loB = ib == 1 ? ilo.y : ilo.z, hiB = ib == 1 ? ihi.y : ihi.z;
  int loK = k == 0 ? ilo.x : (k == 1 ? ilo.y : ilo.z), hiK = k == 0 ? ihi.x : (k == 1 ? ihi.y : ihi.z);
  for (int b = loB; b <= hiB; ++b) {
    for (int a = loA; a <= hiA; ++a) {
      int k0 = loK, k1 = hiK;
      // Only for triangles whose normal is well defined (not slivers degenerated to a segment).
      if (fabs(nk) > 1e-3f * length(v1 - v0) * length(v2 - v0)) {
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
        float3 sn = safe_normalize(w0 * n0 + bc.x * n1 + bc.y * n2, normalize(faceN));
        float3 em = emits ? fmin(sm.emission, GI_VOX_EMISSION_MAX) : (float3)(0.0f);
        float3 off = clamp(p - c, -1.0f, 1.0f);
        global int* irecord = (global int*)record;
        atomic_add(record + GI_VOX_ALBEDO + 0, vox_fixed(clamp(sm.diffuse.x, 0.0f, 1.0f), GI_VOX_UNIT));
        atomic_add(record + GI_VOX_ALBEDO + 1, vox_fixed(clamp(sm.diffuse.y, 0.0f, 1.0f), GI_VOX_UNIT));
        atomic_add(record + GI_VOX_ALBEDO + 2, vox_fixed(clamp(sm.diffuse.z, 0.0f, 1.0f), GI_VOX_UNIT));
        if (emits) {
          atomic_add(record + GI_VOX_EMISSION + 0, vox_fixed(em.x, GI_VOX_EMISSION_UNIT));
          atomic_add(record + GI_VOX_EMISSION + 1, vox_fixed(em.y, GI_VOX_EMISSION_UNIT));
          atomic_add(record + GI_VOX_EMISSION + 2, vox_fixed(em.z, GI_VOX_EMISSION_UNIT));
        }
        atomic_add(irecord + GI_VOX_NORMAL + 0, vox_fixed_signed(sn.x, 0.25f * GI_VOX_UNIT));
        atomic_add(irecord + GI_VOX_NORMAL + 1, vox_fixed_signed(sn.y, 0.25f * GI_VOX_UNIT));
        atomic_add(irecord + GI_VOX_NORMAL + 2, vox_fixed_signed(sn.z, 0.25f * GI_VOX_UNIT));
        atomic_add(irecord + GI_VOX_OFFSET + 0, vox_fixed_signed(off.x, 0.25f * GI_VOX_UNIT));
        atomic_add(irecord + GI_VOX_OFFSET + 1, vox_fixed_signed(off.y, 0.25f * GI_VOX_UNIT));
        atomic_add(irecord + GI_VOX_OFFSET + 2, vox_fixed_signed(off.z, 0.25f * GI_VOX_UNIT));
        atomic_add(record + GI_VOX_OPACITY, vox_fixed(opacity, GI_VOX_UNIT));
      }
    }
  }
}
