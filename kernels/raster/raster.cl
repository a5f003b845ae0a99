// The compute rasterizer (one machinery for camera G-buffers, shadow maps and RSMs).
//
// Pipeline per view:
//   raster_setup      one work-item per scene triangle: transform, frustum cull, clip against the
//                     near plane and a guard band, back-face cull, snap to 1/256 pixel, build exact
//                     integer edge functions with the top-left rule; append GiRasterTriangle records.
//   raster_bin_count  count, per GI_TILE×GI_TILE screen tile, the records whose edges can cover
//   raster_bin_scan   one of its pixel centres; exclusive prefix sum -> per-tile list offsets;
//   raster_bin_fill   write the record indices into the per-tile lists.
//   raster_tiles      per tile, a row of GI_VW pixels per work-item: test every listed record and
//                     keep the nearest by a 64-bit key (depth bits << 32 | triangle index).
// Output: a visibility buffer (triangle index per pixel, GI_INVALID_ID for background) and the
// linear view depth. Attributes are resolved afterwards (gbuffer.cl) from the triangle index.
//
// Why keys: the per-tile lists are filled with atomics, so their order changes run to run; taking
// the minimum key makes the result independent of that order (ties broken by triangle index),
// so images are bit-identical across runs (ALGORITHMS.md §7).
#include "common/math.h"
#include "common/material.h"
#include "common/vector_width.h"
#include "raster/raster_types.h"
#include "raster/view.h"

#ifndef GI_TILE
#define GI_TILE 16
#endif
#define GI_MAX_CLIP_VERTS 9

#if GI_VW == 1
#define GI_SELECT(a, b, c) ((c) ? (b) : (a))
#else
#define GI_SELECT(a, b, c) select(a, b, c)
#endif

// Sutherland–Hodgman step: keeps the part of the polygon where dot(plane, v) >= 0.
inline int clip_polygon(float4* in, int n, float4* out, float4 plane) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    float4 a = in[i], b = in[(i + 1) % n];
    float da = dot(plane, a), db = dot(plane, b);
    if (da >= 0.0f) out[m++] = a;
    if ((da >= 0.0f) != (db >= 0.0f)) out[m++] = a + (b - a) * (da / (da - db));
  }
  return m;
}

inline void emit_triangle(float4 c0, float4 c1, float4 c2, const GiView* view, uint triangle, uint flags,
                          bool cullBack, global GiRasterTriangle* out, global uint* counters, uint capacity) {
  float W = (float)view->width, H = (float)view->height;
  float4 clip[3] = {c0, c1, c2};
  float sx[3], sy[3], q[3];
  long fx[3], fy[3];
  for (int i = 0; i < 3; ++i) {
    float iw = 1.0f / clip[i].w;
    sx[i] = (clip[i].x * iw * 0.5f + 0.5f) * W;
    sy[i] = (0.5f - clip[i].y * iw * 0.5f) * H;
    q[i] = view->orthographic ? clip[i].z * iw * 0.5f + 0.5f : iw;
    fx[i] = (long)rint(sx[i] * GI_SUBPIXEL_ONE);
    fy[i] = (long)rint(sy[i] * GI_SUBPIXEL_ONE);
  }
  // Orientation in y-down pixel space: a counter-clockwise (front-facing) triangle has area2 < 0.
  long area2 = (fx[1] - fx[0]) * (fy[2] - fy[0]) - (fx[2] - fx[0]) * (fy[1] - fy[0]);
  if (area2 == 0) return;
  if (area2 > 0 && cullBack) return;
  int i1 = 1, i2 = 2;
  if (area2 < 0) { i1 = 2; i2 = 1; }  // make the edge functions positive inside
  int idx[3] = {0, i1, i2};

  // Pixel-centre bounding box: pixel px has its centre at (px + 0.5) · 256 in fixed point.
  long minX = min(fx[0], min(fx[1], fx[2])), maxX = max(fx[0], max(fx[1], fx[2]));
  long minY = min(fy[0], min(fy[1], fy[2])), maxY = max(fy[0], max(fy[1], fy[2]));
  long halfPixel = GI_SUBPIXEL_ONE / 2;
  int x0 = (int)max((long)0, (minX - halfPixel + GI_SUBPIXEL_ONE - 1) >> GI_SUBPIXEL_BITS);
  int y0 = (int)max((long)0, (minY - halfPixel + GI_SUBPIXEL_ONE - 1) >> GI_SUBPIXEL_BITS);
  int x1 = (int)min((long)view->width - 1, (maxX - halfPixel) >> GI_SUBPIXEL_BITS);
  int y1 = (int)min((long)view->height - 1, (maxY - halfPixel) >> GI_SUBPIXEL_BITS);
  if (x0 > x1 || y0 > y1) return;  // covers no pixel centre

  GiRasterTriangle r;
  for (int e = 0; e < 3; ++e) {
    int ia = idx[e], ib = idx[(e + 1) % 3];
    long ax = fx[ia], ay = fy[ia], bx = fx[ib], by = fy[ib];
    // E(P) = (b - a) × (P - a) = A·Px + B·Py + C
    long A = -(by - ay), B = bx - ax;
    long C = -(A * ax + B * ay);
    // Top-left rule (y down, this orientation): top edge = horizontal going right, left edge =
    // going up. Pixel centres exactly on other edges belong to the neighbour: E > 0 there.
    bool topLeft = (ay == by && bx > ax) || (by < ay);
    r.a[e] = (int)A;
    r.b[e] = (int)B;
    r.c[e] = topLeft ? C : C - 1;
  }
  // Depth plane q(px, py) over continuous pixel coordinates.
  float dx1 = sx[1] - sx[0], dy1 = sy[1] - sy[0], dx2 = sx[2] - sx[0], dy2 = sy[2] - sy[0];
  float det = dx1 * dy2 - dx2 * dy1;
  float dq1 = q[1] - q[0], dq2 = q[2] - q[0];
  float qa = (dq1 * dy2 - dq2 * dy1) / det;
  float qb = (dx1 * dq2 - dx2 * dq1) / det;
  r.q[0] = qa;
  r.q[1] = qb;
  r.q[2] = q[0] - qa * sx[0] - qb * sy[0];
  r.bbox[0] = x0; r.bbox[1] = y0; r.bbox[2] = x1; r.bbox[3] = y1;
  r.triangle = triangle;
  r.flags = flags;
  r.pad[0] = r.pad[1] = r.pad[2] = 0;
  uint slot = atomic_inc(&counters[0]);
  if (slot < capacity) out[slot] = r;
}

kernel void raster_setup(global const float4* positions, global const uint4* triangles,
                         global const GiMaterial* materials, GiView view, uint triangleCount,
                         global GiRasterTriangle* out, global uint* counters, uint capacity) {
  uint t = get_global_id(0);
  if (t >= triangleCount) return;
  uint4 tri = triangles[t];
  float4 c[3];
  c[0] = mat4_mul(view.view_proj, positions[tri.x]);
  c[1] = mat4_mul(view.view_proj, positions[tri.y]);
  c[2] = mat4_mul(view.view_proj, positions[tri.z]);
  // Trivial reject: all vertices outside one frustum plane (far plane not tested: depth ranges
  // of shadow views are fitted to the scene).
  for (int axis = 0; axis < 3; ++axis) {
    bool allLow = true, allHigh = axis < 2;
    for (int i = 0; i < 3; ++i) {
      float v = axis == 0 ? c[i].x : axis == 1 ? c[i].y : c[i].z;
      allLow = allLow && v < -c[i].w;
      if (axis < 2) allHigh = allHigh && v > c[i].w;
    }
    if (allLow || allHigh) return;
  }
  if (!(isfinite(c[0].w) && isfinite(c[1].w) && isfinite(c[2].w))) return;

  global const GiMaterial* m = &materials[tri.w];
  bool cullBack = view.cull_backfaces && !m->double_sided;
  uint flags = m->alpha_mode == GI_ALPHA_MASK ? GI_RASTER_FLAG_ALPHA_TEST : 0u;

  // Guard band in NDC units: pixel coordinates stay within GI_GUARD_BAND_PIXELS of the viewport.
  float gx = 1.0f + 2.0f * GI_GUARD_BAND_PIXELS / (float)view.width;
  float gy = 1.0f + 2.0f * GI_GUARD_BAND_PIXELS / (float)view.height;
  bool inside = true;
  for (int i = 0; i < 3; ++i)
    inside = inside && c[i].z >= -c[i].w && fabs(c[i].x) <= gx * c[i].w && fabs(c[i].y) <= gy * c[i].w;
  if (inside) {
    emit_triangle(c[0], c[1], c[2], &view, t, flags, cullBack, out, counters, capacity);
    return;
  }
  float4 polyA[GI_MAX_CLIP_VERTS], polyB[GI_MAX_CLIP_VERTS];
  polyA[0] = c[0]; polyA[1] = c[1]; polyA[2] = c[2];
  int n = 3;
  n = clip_polygon(polyA, n, polyB, (float4)(0.0f, 0.0f, 1.0f, 1.0f));  // near: z + w >= 0
  if (n < 3) return;
  n = clip_polygon(polyB, n, polyA, (float4)(-1.0f, 0.0f, 0.0f, gx));
  if (n < 3) return;
  n = clip_polygon(polyA, n, polyB, (float4)(1.0f, 0.0f, 0.0f, gx));
  if (n < 3) return;
  n = clip_polygon(polyB, n, polyA, (float4)(0.0f, -1.0f, 0.0f, gy));
  if (n < 3) return;
  n = clip_polygon(polyA, n, polyB, (float4)(0.0f, 1.0f, 0.0f, gy));
  for (int i = 1; i + 1 < n; ++i)
    emit_triangle(polyB[0], polyB[i], polyB[i + 1], &view, t, flags, cullBack, out, counters, capacity);
}

// True when the record can cover a pixel centre of tile (tx, ty): no edge function is negative at
// all four corner pixel centres (E is affine, so its maximum over the tile is at a corner).
inline bool covers_tile(global const GiRasterTriangle* r, int tx, int ty) {
  long X0 = (long)(tx * GI_TILE) * GI_SUBPIXEL_ONE + GI_SUBPIXEL_ONE / 2;
  long Y0 = (long)(ty * GI_TILE) * GI_SUBPIXEL_ONE + GI_SUBPIXEL_ONE / 2;
  long X1 = X0 + (long)(GI_TILE - 1) * GI_SUBPIXEL_ONE, Y1 = Y0 + (long)(GI_TILE - 1) * GI_SUBPIXEL_ONE;
  for (int e = 0; e < 3; ++e) {
    long a = r->a[e], b = r->b[e];
    long best = max(a * X0, a * X1) + max(b * Y0, b * Y1) + r->c[e];
    if (best < 0) return false;
  }
  return true;
}

kernel void raster_bin_count(global const GiRasterTriangle* tris, global const uint* counters, uint capacity,
                             int tilesX, int tilesY, global uint* tileCounts) {
  uint i = get_global_id(0);
  if (i >= min(counters[0], capacity)) return;
  global const GiRasterTriangle* r = &tris[i];
  int tx0 = r->bbox[0] / GI_TILE, tx1 = r->bbox[2] / GI_TILE;
  int ty0 = r->bbox[1] / GI_TILE, ty1 = r->bbox[3] / GI_TILE;
  for (int ty = ty0; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx)
      if (covers_tile(r, tx, ty)) atomic_inc(&tileCounts[ty * tilesX + tx]);
}

// Exclusive prefix sum over the tile counts (serial: a few thousand tiles at most), also
// initialising the fill cursors. counters[1] receives the total number of list entries.
kernel void raster_bin_scan(global const uint* tileCounts, uint tileCount, global uint* tileOffsets,
                            global uint* tileCursors, global uint* counters) {
  if (get_global_id(0) != 0) return;
  uint sum = 0;
  for (uint t = 0; t < tileCount; ++t) {
    tileOffsets[t] = sum;
    tileCursors[t] = sum;
    sum += tileCounts[t];
  }
  counters[1] = sum;
}

kernel void raster_bin_fill(global const GiRasterTriangle* tris, global const uint* counters, uint capacity,
                            int tilesX, int tilesY, global uint* tileCursors, global uint* binList,
                            uint binCapacity) {
  uint i = get_global_id(0);
  if (i >= min(counters[0], capacity)) return;
  global const GiRasterTriangle* r = &tris[i];
  int tx0 = r->bbox[0] / GI_TILE, tx1 = r->bbox[2] / GI_TILE;
  int ty0 = r->bbox[1] / GI_TILE, ty1 = r->bbox[3] / GI_TILE;
  for (int ty = ty0; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx)
      if (covers_tile(r, tx, ty)) {
        uint slot = atomic_inc(&tileCursors[ty * tilesX + tx]);
        if (slot < binCapacity) binList[slot] = i;
      }
}

// Alpha-mask test of one pixel against a triangle: barycentrics by ray-plane intersection with
// the source triangle (exact, perspective-correct, independent of clipping).
inline bool alpha_cut_out(const GiView* view, float px, float py, uint triangle, global const float4* positions,
                          global const float2* uvs, global const uint4* triangles, global const GiMaterial* materials,
                          global const GiTexture* textures, global const uchar4* texels) {
  uint4 tri = triangles[triangle];
  float3 o, d;
  view_pixel_ray(view, px, py, &o, &d);
  float3 tuv = ray_triangle_barycentrics(o, d, positions[tri.x].xyz, positions[tri.y].xyz, positions[tri.z].xyz);
  float2 uv = (1.0f - tuv.y - tuv.z) * uvs[tri.x] + tuv.y * uvs[tri.y] + tuv.z * uvs[tri.z];
  return material_cut_out(&materials[tri.w], textures, texels, uv, 0.0f);
}

kernel void raster_tiles(global const GiRasterTriangle* tris, global const uint* tileOffsets,
                         global const uint* tileCounts, global const uint* binList, int tilesX, int tilesY,
                         GiView view, global const float4* positions, global const float2* uvs,
                         global const uint4* triangles, global const GiMaterial* materials,
                         global const GiTexture* textures, global const uchar4* texels,
                         global uint* outTriangle, global float* outDepth) {
  const int groupsPerRow = GI_TILE / GI_VW;
  uint gid = get_global_id(0);
  uint tile = gid / (uint)(GI_TILE * groupsPerRow);
  if (tile >= (uint)(tilesX * tilesY)) return;
  int sub = (int)(gid % (uint)(GI_TILE * groupsPerRow));
  int row = sub / groupsPerRow;
  int tx = (int)tile % tilesX, ty = (int)tile / tilesX;
  int py = ty * GI_TILE + row;
  int px0 = tx * GI_TILE + (sub % groupsPerRow) * GI_VW;
  if (py >= view.height || px0 >= view.width) return;

  intV px = px0 + GI_LANES;
  longV X = convert_longV(px) * GI_SUBPIXEL_ONE + GI_SUBPIXEL_ONE / 2;
  long Y = (long)py * GI_SUBPIXEL_ONE + GI_SUBPIXEL_ONE / 2;
  floatV pxf = convert_floatV(px) + 0.5f;
  float pyf = (float)py + 0.5f;
  ulongV best = (ulongV)(0xFFFFFFFFFFFFFFFFul);

  uint begin = tileOffsets[tile], count = tileCounts[tile];
  for (uint k = 0; k < count; ++k) {
    global const GiRasterTriangle* r = &tris[binList[begin + k]];
    if (py < r->bbox[1] || py > r->bbox[3]) continue;
    long rowC0 = r->b[0] * Y + r->c[0], rowC1 = r->b[1] * Y + r->c[1], rowC2 = r->b[2] * Y + r->c[2];
    longV e0 = (long)r->a[0] * X + rowC0;
    longV e1 = (long)r->a[1] * X + rowC1;
    longV e2 = (long)r->a[2] * X + rowC2;
    longV inside = (e0 >= 0) & (e1 >= 0) & (e2 >= 0);
    if (!GI_ANY(inside)) continue;
    floatV q = r->q[0] * pxf + (r->q[1] * pyf + r->q[2]);
    uintV hi = view.orthographic ? as_uintV(fmax(q, (floatV)(0.0f))) : ~as_uintV(q);
    ulongV key = (convert_ulongV(hi) << 32) | (ulong)r->triangle;
    longV nearer = inside & (longV)(key < best);
    if ((r->flags & GI_RASTER_FLAG_ALPHA_TEST) && GI_ANY(nearer)) {
      long lanes[GI_VW];
      vstoreV(nearer, 0, lanes);
      for (int l = 0; l < GI_VW; ++l)
        if (lanes[l] && alpha_cut_out(&view, (float)(px0 + l) + 0.5f, pyf, r->triangle, positions, uvs, triangles,
                                      materials, textures, texels))
          lanes[l] = 0;
      nearer = vloadV(0, lanes);
    }
    best = GI_SELECT(best, key, nearer);
  }

  uintV hiBits = convert_uintV(best >> 32);
  uintV triOut = convert_uintV(best & (ulongV)(0xFFFFFFFFul));
  floatV depth;
  if (view.orthographic)
    depth = view.znear + as_floatV(hiBits) * (view.zfar - view.znear);
  else
    depth = 1.0f / as_floatV(~hiBits);
  depth = GI_SELECT(depth, (floatV)(GI_INF), (intV)(triOut == (uintV)(GI_INVALID_ID)));

  size_t base = (size_t)py * (size_t)view.width + (size_t)px0;
  if (px0 + GI_VW <= view.width) {
    vstoreV(triOut, 0, outTriangle + base);
    vstoreV(depth, 0, outDepth + base);
  } else {
    uint t[GI_VW];
    float d[GI_VW];
    vstoreV(triOut, 0, t);
    vstoreV(depth, 0, d);
    for (int l = 0; l < view.width - px0; ++l) {
      outTriangle[base + l] = t[l];
      outDepth[base + l] = d[l];
    }
  }
}
