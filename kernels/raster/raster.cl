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

// Builds the record of one (clipped) triangle in clip space. Returns false when it covers no pixel
// centre or is culled.
inline bool setup_triangle(float4 c0, float4 c1, float4 c2, const GiView* view, uint triangle, uint flags,
                           bool cullBack, GiRasterTriangle* r) {
  float W = (float)view->width, H = (float)view->height;
  float iw0 = 1.0f / c0.w, iw1 = 1.0f / c1.w, iw2 = 1.0f / c2.w;
  float sx0 = (c0.x * iw0 * 0.5f + 0.5f) * W, sy0 = (0.5f - c0.y * iw0 * 0.5f) * H;
  float sx1 = (c1.x * iw1 * 0.5f + 0.5f) * W, sy1 = (0.5f - c1.y * iw1 * 0.5f) * H;
  float sx2 = (c2.x * iw2 * 0.5f + 0.5f) * W, sy2 = (0.5f - c2.y * iw2 * 0.5f) * H;
  float q0 = view->orthographic ? c0.z * iw0 * 0.5f + 0.5f : iw0;
  float q1 = view->orthographic ? c1.z * iw1 * 0.5f + 0.5f : iw1;
  float q2 = view->orthographic ? c2.z * iw2 * 0.5f + 0.5f : iw2;
  long fx0 = (long)rint(sx0 * GI_SUBPIXEL_ONE), fy0 = (long)rint(sy0 * GI_SUBPIXEL_ONE);
  long fx1 = (long)rint(sx1 * GI_SUBPIXEL_ONE), fy1 = (long)rint(sy1 * GI_SUBPIXEL_ONE);
  long fx2 = (long)rint(sx2 * GI_SUBPIXEL_ONE), fy2 = (long)rint(sy2 * GI_SUBPIXEL_ONE);
  // Orientation in y-down pixel space: a counter-clockwise (front-facing) triangle has area2 < 0.
  long area2 = (fx1 - fx0) * (fy2 - fy0) - (fx2 - fx0) * (fy1 - fy0);
  if (area2 == 0) return false;
  if (area2 > 0 && cullBack) return false;
  if (area2 < 0) {  // swap vertices 1 and 2 so the edge functions are positive inside
    long t = fx1; fx1 = fx2; fx2 = t;
    t = fy1; fy1 = fy2; fy2 = t;
  }
  // Pixel-centre bounding box: pixel px has its centre at (px + 0.5) · 256 in fixed point.
  long minX = min(fx0, min(fx1, fx2)), maxX = max(fx0, max(fx1, fx2));
  long minY = min(fy0, min(fy1, fy2)), maxY = max(fy0, max(fy1, fy2));
  long halfPixel = GI_SUBPIXEL_ONE / 2;
  int x0 = (int)max((long)0, (minX - halfPixel + GI_SUBPIXEL_ONE - 1) >> GI_SUBPIXEL_BITS);
  int y0 = (int)max((long)0, (minY - halfPixel + GI_SUBPIXEL_ONE - 1) >> GI_SUBPIXEL_BITS);
  int x1 = (int)min((long)view->width - 1, (maxX - halfPixel) >> GI_SUBPIXEL_BITS);
  int y1 = (int)min((long)view->height - 1, (maxY - halfPixel) >> GI_SUBPIXEL_BITS);
  if (x0 > x1 || y0 > y1) return false;  // covers no pixel centre

  // E(P) = (b - a) × (P - a) = A·Px + B·Py + C for the edges 0→1, 1→2, 2→0. Top-left rule (y down,
  // this orientation): top edge = horizontal going right, left edge = going up. Pixel centres
  // exactly on any other edge belong to the neighbour, so those edges need E > 0 (C - 1).
#define GI_EDGE(e, ax, ay, bx, by)                                   \
  {                                                                  \
    long A = -((by) - (ay)), B = (bx) - (ax);                        \
    long C = -(A * (ax) + B * (ay));                                 \
    bool topLeft = ((ay) == (by) && (bx) > (ax)) || ((by) < (ay));   \
    r->a[e] = (int)A;                                                \
    r->b[e] = (int)B;                                                \
    r->c[e] = topLeft ? C : C - 1;                                   \
  }
  GI_EDGE(0, fx0, fy0, fx1, fy1)
  GI_EDGE(1, fx1, fy1, fx2, fy2)
  GI_EDGE(2, fx2, fy2, fx0, fy0)
#undef GI_EDGE
  // Depth plane q(px, py) over continuous pixel coordinates (original vertex order).
  float dx1 = sx1 - sx0, dy1 = sy1 - sy0, dx2 = sx2 - sx0, dy2 = sy2 - sy0;
  float det = dx1 * dy2 - dx2 * dy1;
  float dq1 = q1 - q0, dq2 = q2 - q0;
  float qa = (dq1 * dy2 - dq2 * dy1) / det;
  float qb = (dx1 * dq2 - dx2 * dq1) / det;
  r->q[0] = qa;
  r->q[1] = qb;
  r->q[2] = q0 - qa * sx0 - qb * sy0;
  r->bbox[0] = x0; r->bbox[1] = y0; r->bbox[2] = x1; r->bbox[3] = y1;
  r->triangle = triangle;
  r->flags = flags | GI_RASTER_FLAG_VALID;
  r->pad[0] = r->pad[1] = r->pad[2] = 0;
  return true;
}

// Pieces of clipped triangles go after the one-slot-per-triangle region, appended atomically
// (rare: only triangles crossing the near plane or the guard band).
inline void append_clipped(float4 c0, float4 c1, float4 c2, const GiView* view, uint triangle, uint flags,
                           bool cullBack, global GiRasterTriangle* out, uint triangleCount,
                           global uint* counters, uint capacity) {
  GiRasterTriangle r;
  if (!setup_triangle(c0, c1, c2, view, triangle, flags, cullBack, &r)) return;
  uint slot = triangleCount + atomic_inc(&counters[0]);
  if (slot < capacity) out[slot] = r;
}

// One work-item per scene triangle. Unclipped triangles write their record to slot t (flags 0
// when culled), so no atomics are needed on the common path.
kernel void raster_setup(global const float4* positions, global const uint4* triangles,
                         global const GiMaterial* materials, GiView view, uint triangleCount,
                         global GiRasterTriangle* out, global uint* counters, uint capacity) {
  uint t = get_global_id(0);
  if (t >= triangleCount) return;
  uint4 tri = triangles[t];
  float4 c0 = mat4_mul(view.view_proj, positions[tri.x]);
  float4 c1 = mat4_mul(view.view_proj, positions[tri.y]);
  float4 c2 = mat4_mul(view.view_proj, positions[tri.z]);
  out[t].flags = 0u;
  // Trivial reject: all vertices outside one frustum plane (the far plane is not tested: depth
  // ranges of shadow views are fitted to the scene). NaN positions fail every test below.
  if ((c0.x < -c0.w && c1.x < -c1.w && c2.x < -c2.w) || (c0.x > c0.w && c1.x > c1.w && c2.x > c2.w) ||
      (c0.y < -c0.w && c1.y < -c1.w && c2.y < -c2.w) || (c0.y > c0.w && c1.y > c1.w && c2.y > c2.w) ||
      (c0.z < -c0.w && c1.z < -c1.w && c2.z < -c2.w))
    return;
  if (!(isfinite(c0.w) && isfinite(c1.w) && isfinite(c2.w))) return;

  global const GiMaterial* m = &materials[tri.w];
  bool cullBack = view.cull_backfaces && !m->double_sided;
  uint flags = m->alpha_mode == GI_ALPHA_MASK ? GI_RASTER_FLAG_ALPHA_TEST : 0u;

  // Guard band in NDC units: pixel coordinates stay within GI_GUARD_BAND_PIXELS of the viewport.
  float gx = 1.0f + 2.0f * GI_GUARD_BAND_PIXELS / (float)view.width;
  float gy = 1.0f + 2.0f * GI_GUARD_BAND_PIXELS / (float)view.height;
  bool inside = c0.z >= -c0.w && fabs(c0.x) <= gx * c0.w && fabs(c0.y) <= gy * c0.w &&
                c1.z >= -c1.w && fabs(c1.x) <= gx * c1.w && fabs(c1.y) <= gy * c1.w &&
                c2.z >= -c2.w && fabs(c2.x) <= gx * c2.w && fabs(c2.y) <= gy * c2.w;
  if (inside) {
    GiRasterTriangle r;
    if (setup_triangle(c0, c1, c2, &view, t, flags, cullBack, &r)) out[t] = r;
    return;
  }
  float4 polyA[GI_MAX_CLIP_VERTS], polyB[GI_MAX_CLIP_VERTS];
  polyA[0] = c0; polyA[1] = c1; polyA[2] = c2;
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
    append_clipped(polyB[0], polyB[i], polyB[i + 1], &view, t, flags, cullBack, out, triangleCount, counters, capacity);
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

// Records live in [0, triangleCount) (one slot per triangle) and [triangleCount, + counters[0])
// (clipped pieces).
inline uint record_count(global const uint* counters, uint triangleCount, uint capacity) {
  return min(triangleCount + counters[0], capacity);
}

kernel void raster_bin_count(global const GiRasterTriangle* tris, global const uint* counters, uint triangleCount,
                             uint capacity, int tilesX, int tilesY, global uint* tileCounts) {
  uint i = get_global_id(0);
  if (i >= record_count(counters, triangleCount, capacity)) return;
  global const GiRasterTriangle* r = &tris[i];
  if (!(r->flags & GI_RASTER_FLAG_VALID)) return;
  int tx0 = r->bbox[0] / GI_TILE, tx1 = r->bbox[2] / GI_TILE;
  int ty0 = r->bbox[1] / GI_TILE, ty1 = r->bbox[3] / GI_TILE;
  if (tx0 == tx1 && ty0 == ty1) {  // the common case: inside one tile
    atomic_inc(&tileCounts[ty0 * tilesX + tx0]);
    return;
  }
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

kernel void raster_bin_fill(global const GiRasterTriangle* tris, global const uint* counters, uint triangleCount,
                            uint capacity, int tilesX, int tilesY, global uint* tileCursors, global uint* binList,
                            uint binCapacity) {
  uint i = get_global_id(0);
  if (i >= record_count(counters, triangleCount, capacity)) return;
  global const GiRasterTriangle* r = &tris[i];
  if (!(r->flags & GI_RASTER_FLAG_VALID)) return;
  int tx0 = r->bbox[0] / GI_TILE, tx1 = r->bbox[2] / GI_TILE;
  int ty0 = r->bbox[1] / GI_TILE, ty1 = r->bbox[3] / GI_TILE;
  for (int ty = ty0; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx)
      if ((tx0 == tx1 && ty0 == ty1) || covers_tile(r, tx, ty)) {
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

// Writes one row of GI_VW pixels from (px0, py) (fewer at the image's right edge) from the
// lanes' nearest-hit keys (the depth's ordered bits << 32 | triangle, as the tile loops build
// them: the smallest key is the nearest): the triangle id and the depth decoded from the key
// (∞ where nothing was hit).
inline void raster_store_row(const GiView* view, ulongV best, int px0, int py, global uint* outTriangle,
                             global float* outDepth) {
  uintV hiBits = convert_uintV(best >> 32);
  uintV triOut = convert_uintV(best & (ulongV)(0xFFFFFFFFul));
  floatV depth = view->orthographic ? view->znear + as_floatV(hiBits) * (view->zfar - view->znear)
                                    : 1.0f / as_floatV(~hiBits);
  depth = GI_SEL(depth, (floatV)(GI_INF), (intV)(triOut == (uintV)(GI_INVALID_ID)));
  size_t base = (size_t)py * (size_t)view->width + (size_t)px0;
  int valid = min(GI_VW, view->width - px0);
  GI_STORE_LANES(uint, triOut, outTriangle, base, valid)
  GI_STORE_LANES(float, depth, outDepth, base, valid)
}

#if GI_VW == GI_TILE
// CPU form: one work-item per tile, GI_VW-wide vectors per tile row. The triangle loop is outside,
// and each triangle only visits the tile rows its bounding box spans, with edge functions and
// depth stepped incrementally from row to row.
kernel void raster_tiles(global const GiRasterTriangle* tris, global const uint* tileOffsets,
                         global const uint* tileCounts, global const uint* binList, int tilesX, int tilesY,
                         GiView view, global const float4* positions, global const float2* uvs,
                         global const uint4* triangles, global const GiMaterial* materials,
                         global const GiTexture* textures, global const uchar4* texels,
                         global uint* outTriangle, global float* outDepth) {
  uint tile = get_global_id(0);
  if (tile >= (uint)(tilesX * tilesY)) return;
  int tx = (int)tile % tilesX, ty = (int)tile / tilesX;
  int px0 = tx * GI_TILE, py0 = ty * GI_TILE;
  intV px = px0 + GI_LANES;
  longV X = convert_longV(px) * GI_SUBPIXEL_ONE + GI_SUBPIXEL_ONE / 2;
  floatV pxf = convert_floatV(px) + 0.5f;
  ulongV best[GI_TILE];
  for (int row = 0; row < GI_TILE; ++row) best[row] = (ulongV)(0xFFFFFFFFFFFFFFFFul);

  uint begin = tileOffsets[tile], count = tileCounts[tile];
  for (uint k = 0; k < count; ++k) {
    global const GiRasterTriangle* r = &tris[binList[begin + k]];
    int row0 = max(r->bbox[1], py0) - py0, row1 = min(r->bbox[3], py0 + GI_TILE - 1) - py0;
    long Y = (long)(py0 + row0) * GI_SUBPIXEL_ONE + GI_SUBPIXEL_ONE / 2;
    longV e0 = (long)r->a[0] * X + (r->b[0] * Y + r->c[0]);
    longV e1 = (long)r->a[1] * X + (r->b[1] * Y + r->c[1]);
    longV e2 = (long)r->a[2] * X + (r->b[2] * Y + r->c[2]);
    long step0 = (long)r->b[0] * GI_SUBPIXEL_ONE, step1 = (long)r->b[1] * GI_SUBPIXEL_ONE,
         step2 = (long)r->b[2] * GI_SUBPIXEL_ONE;
    floatV q = r->q[0] * pxf + (r->q[1] * ((float)(py0 + row0) + 0.5f) + r->q[2]);
    float qStep = r->q[1];
    ulong triBits = (ulong)r->triangle;
    bool alphaTested = (r->flags & GI_RASTER_FLAG_ALPHA_TEST) != 0;
    for (int row = row0; row <= row1; ++row) {
      // All three edge functions >= 0 <=> the sign bit of their OR is clear.
      longV inside = (e0 | e1 | e2) >= 0;
      if (GI_ANY(inside)) {
        uintV hi = view.orthographic ? as_uintV(fmax(q, (floatV)(0.0f))) : ~as_uintV(q);
        ulongV key = (convert_ulongV(hi) << 32) | triBits;
        longV nearer = inside & (longV)(key < best[row]);
        if (alphaTested && GI_ANY(nearer)) {
          long lanes[GI_VW];
          vstoreV(nearer, 0, lanes);
          for (int l = 0; l < GI_VW; ++l)
            if (lanes[l] && alpha_cut_out(&view, (float)(px0 + l) + 0.5f, (float)(py0 + row) + 0.5f, r->triangle,
                                          positions, uvs, triangles, materials, textures, texels))
              lanes[l] = 0;
          nearer = vloadV(0, lanes);
        }
        best[row] = select(best[row], key, nearer);
      }
      e0 += step0;
      e1 += step1;
      e2 += step2;
      q += qStep;
    }
  }

  for (int row = 0; row < GI_TILE; ++row) {
    int py = py0 + row;
    if (py >= view.height) break;
    raster_store_row(&view, best[row], px0, py, outTriangle, outDepth);
  }
}
#else
// GPU form: one work-item per GI_VW pixels of a tile row, every listed triangle tested.
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
    best = GI_SEL(best, key, nearer);
  }

  raster_store_row(&view, best, px0, py, outTriangle, outDepth);
}
#endif
