// Discontinuity (geometry-aware) filter and geometry-aware upsampling (ALGORITHMS.md §3).
//
// Neighbour q contributes to pixel p only if |z_q − z_p| ≤ τ_z·z_p, n_q·n_p ≥ cos τ_n (geometric
// normals) and, when asked, q has p's instance id. Box weights over a GI_FX × GI_FY window
// (offsets −⌊GI_FX/2⌋ … GI_FX−1−⌊GI_FX/2⌋, so a window of the interleave pattern's size holds
// exactly one pixel of every pixel class), renormalised by the accepted weights. The filtered
// quantity is irradiance E; the output is the radiance L = ρ/π · E (the albedo is applied after
// filtering, so texture detail stays sharp).
//
// One pass, straight from the G-buffer. On a CPU device (GI_VW = 8 or 16) a work-item takes
// GI_VW adjacent pixels of GI_FILTER_ROWS consecutive rows: it first copies the rows its window
// needs (GI_FILTER_ROWS + GI_FY − 1 of them, GI_FILTER_APRON columns either side) into private
// SoA planes, the float4 records transposed with vector swizzles, then every window offset is
// one unaligned vector load per plane from those (PERFORMANCE_FACTS.md points 2, 6, 7). The
// copy's depth is NaN outside the image and at pixels without a surface, so the one comparison
// |z_q − z_p| ≤ τ_z·z_p also rejects them: the window loop has no border or empty-pixel tests.
// (A separate padded-plane pass cost a DRAM write and read-back of 32 bytes per pixel.)
//
// Separable form (`igi.filter=separable`, the thesis's separable blur, seed 000 §4): a GI_FX × 1
// pass writing the filtered E, then a 1 × GI_FY pass over it writing L (GI_VW = 1: two launches;
// CPU: both in one launch, GI_FILTER_SEPARABLE, the row pass kept in private memory). Each pass runs the same
// test against its centre pixel, so without discontinuities it is the n×m box; at discontinuities
// a pixel can receive light through an intermediate that passed both tests (a cross-shaped path
// the 2D window would reject). GI_FX + GI_FY taps instead of GI_FX · GI_FY.
// GI_VW = 1 (GPUs): one pixel per work-item, neighbours read from the G-buffer.
#include "common/math.h"
#include "common/shared_types.h"
#include "common/vector_width.h"

#ifndef GI_FX
#define GI_FX 4
#endif
#ifndef GI_FY
#define GI_FY 4
#endif
#ifndef GI_SAME_INSTANCE
#define GI_SAME_INSTANCE 0
#endif
// 1: write L = ρ/π · filtered E (the last pass); 0: write the filtered E itself (the first pass of
// the separable form, whose second pass filters it again along the other axis).
#ifndef GI_FILTER_APPLY_ALBEDO
#define GI_FILTER_APPLY_ALBEDO 1
#endif
#if GI_FX > 16 || GI_FY > 16
#error "discontinuity filter window larger than 16x16"
#endif

#if GI_VW == 1
kernel void discontinuity_filter(int width, int height, global const float4* irradiance, global const float* depth,
                                 global const float4* geoNormal, global const uint* instance,
                                 global const float4* albedo, float tauZ, float cosTauN, global float4* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  size_t p = (size_t)y * width + x;
  uint id = instance[p];
  if (id == GI_INVALID_ID) {
    out[p] = (float4)(0.0f);
    return;
  }
  float z = depth[p], tz = tauZ * z;
  float3 n = geoNormal[p].xyz, sum = (float3)(0.0f);
  float ws = 0.0f;
  for (int dy = -(GI_FY / 2); dy < GI_FY - GI_FY / 2; ++dy)
    for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) {
      int qx = x + dx, qy = y + dy;
      if (qx < 0 || qy < 0 || qx >= width || qy >= height) continue;
      size_t q = (size_t)qy * width + qx;
      uint qid = instance[q];
      if (qid == GI_INVALID_ID || !(fabs(depth[q] - z) <= tz) || !(dot(geoNormal[q].xyz, n) >= cosTauN) ||
          (GI_SAME_INSTANCE && qid != id))
        continue;
      sum += irradiance[q].xyz;
      ws += 1.0f;
    }
  float3 e = ws > 0.0f ? sum / ws : irradiance[p].xyz;
#if GI_FILTER_APPLY_ALBEDO
  out[p] = (float4)(albedo[p].xyz * (e * GI_INV_PI), 0.0f);
#else
  out[p] = (float4)(e, 0.0f);
#endif
}
#else

// Output rows per work-item: the window's extra GI_FY − 1 rows are copied once per GI_FILTER_ROWS.
#ifndef GI_FILTER_ROWS
#define GI_FILTER_ROWS 16
#endif
// Copied columns either side: ≥ the window's half-width, a multiple of 4 (copied 4 pixels at a time).
#if GI_FX <= 8
#define GI_FILTER_APRON 4
#else
#define GI_FILTER_APRON 8
#endif
#define GI_FILTER_SPAN (GI_VW + 2 * GI_FILTER_APRON) // copied columns per row
#define GI_FILTER_IN_ROWS (GI_FILTER_ROWS + GI_FY - 1)
#define GI_FILTER_PLANES (7 + GI_SAME_INSTANCE)      // E r, g, b; depth; normal x, y, z; [instance]

// 4 pixels from G-buffer index i to plane column d (plane k at d + k·GI_FILTER_SPAN).
inline void filterCopyQuad(size_t i, global const float* irradiance, global const float* depth,
                           global const float* geoNormal, global const uint* instance, float* d) {
  float16 e = vload16(0, irradiance + 4 * i), n = vload16(0, geoNormal + 4 * i);
  uint4 id = vload4(0, instance + i);
  vstore4(e.s048c, 0, d);
  vstore4(e.s159d, 0, d + GI_FILTER_SPAN);
  vstore4(e.s26ae, 0, d + 2 * GI_FILTER_SPAN);
  vstore4(select(vload4(0, depth + i), (float4)(NAN), id == GI_INVALID_ID), 0, d + 3 * GI_FILTER_SPAN);
  vstore4(n.s048c, 0, d + 4 * GI_FILTER_SPAN);
  vstore4(n.s159d, 0, d + 5 * GI_FILTER_SPAN);
  vstore4(n.s26ae, 0, d + 6 * GI_FILTER_SPAN);
#if GI_SAME_INSTANCE
  vstore4(as_float4(id), 0, d + 7 * GI_FILTER_SPAN);
#endif
}

// Copies GI_FILTER_SPAN pixels of row y starting at column xs into plane row `o` (plane k at
// o + k·GI_FILTER_SPAN): vector loads and swizzles when the span is inside the image, else pixel
// by pixel with NaN depth outside it.
inline void filterCopyRow(int width, int height, int xs, int y, global const float* irradiance,
                          global const float* depth, global const float* geoNormal, global const uint* instance,
                          float* o) {
  if (y >= 0 && y < height && xs >= 0 && xs + GI_FILTER_SPAN <= width) {
    size_t row = (size_t)y * width + xs;
#pragma unroll
    for (int a = 0; a < GI_FILTER_APRON; a += 4) {
      filterCopyQuad(row + a, irradiance, depth, geoNormal, instance, o + a);
      filterCopyQuad(row + GI_FILTER_APRON + GI_VW + a, irradiance, depth, geoNormal, instance,
                     o + GI_FILTER_APRON + GI_VW + a);
    }
    size_t i = row + GI_FILTER_APRON;
    floatV r, g, b, nx, ny, nz, unused;
    GI_AOS4_LOAD(irradiance + 4 * i, r, g, b, unused)
    GI_AOS4_LOAD(geoNormal + 4 * i, nx, ny, nz, unused)
    uintV id = vloadV(0, instance + i);
    float* d = o + GI_FILTER_APRON;
    vstoreV(r, 0, d);
    vstoreV(g, 0, d + GI_FILTER_SPAN);
    vstoreV(b, 0, d + 2 * GI_FILTER_SPAN);
    vstoreV(select(vloadV(0, depth + i), (floatV)(NAN), id == GI_INVALID_ID), 0, d + 3 * GI_FILTER_SPAN);
    vstoreV(nx, 0, d + 4 * GI_FILTER_SPAN);
    vstoreV(ny, 0, d + 5 * GI_FILTER_SPAN);
    vstoreV(nz, 0, d + 6 * GI_FILTER_SPAN);
#if GI_SAME_INSTANCE
    vstoreV(as_floatV(id), 0, d + 7 * GI_FILTER_SPAN);
#endif
  } else {
    for (int j = 0; j < GI_FILTER_SPAN; ++j) {
      int x = xs + j;
      bool in = y >= 0 && y < height && x >= 0 && x < width;
      size_t i = in ? (size_t)y * width + x : 0;
      uint id = in ? instance[i] : GI_INVALID_ID;
      float4 e = in ? vload4(i, irradiance) : (float4)(0.0f), n = in ? vload4(i, geoNormal) : (float4)(0.0f);
      o[j] = e.x;
      o[j + GI_FILTER_SPAN] = e.y;
      o[j + 2 * GI_FILTER_SPAN] = e.z;
      o[j + 3 * GI_FILTER_SPAN] = id == GI_INVALID_ID ? NAN : depth[i];
      o[j + 4 * GI_FILTER_SPAN] = n.x;
      o[j + 5 * GI_FILTER_SPAN] = n.y;
      o[j + 6 * GI_FILTER_SPAN] = n.z;
#if GI_SAME_INSTANCE
      o[j + 7 * GI_FILTER_SPAN] = as_float(id);
#endif
    }
  }
}

#ifndef GI_FILTER_SEPARABLE
#define GI_FILTER_SEPARABLE 0
#endif

// The §3 test of copied row q's column o against the pixels (z, n, id) of the lanes.
inline intV filterAccepts(float (*q)[GI_FILTER_SPAN], int o, floatV z, floatV tz, floatV nx, floatV ny, floatV nz,
                          floatV id, float cosTauN) {
  floatV dz = fabs(vloadV(0, q[3] + o) - z);  // NaN outside the image and where no surface: rejected
  floatV dn = vloadV(0, q[4] + o) * nx + vloadV(0, q[5] + o) * ny + vloadV(0, q[6] + o) * nz;
  intV ok = (dz <= tz) & (dn >= cosTauN);
#if GI_SAME_INSTANCE
  ok &= as_uintV(vloadV(0, q[7] + o)) == as_uintV(id);
#endif
  return ok;
}

// Adds neighbour E (r, g, b) and weight 1 to the sums of the lanes that accept it.
inline void filterAccumulate(intV ok, floatV r, floatV g, floatV b, floatV* sr, floatV* sg, floatV* sb, floatV* ws) {
  *sr += select((floatV)(0.0f), r, ok);
  *sg += select((floatV)(0.0f), g, ok);
  *sb += select((floatV)(0.0f), b, ok);
  *ws += select((floatV)(0.0f), (floatV)(1.0f), ok);
}

// Same test, same summation order (dy outer, dx inner) as the host mirror in the tests.
kernel void discontinuity_filter(int width, int height, global const float* irradiance, global const float* depth,
                                 global const float* geoNormal, global const uint* instance,
                                 global const float* albedo, float tauZ, float cosTauN, global float* out) {
  int x0 = get_global_id(0) * GI_VW, y0 = get_global_id(1) * GI_FILTER_ROWS;
  if (x0 >= width || y0 >= height) return;
  float rows[GI_FILTER_IN_ROWS][GI_FILTER_PLANES][GI_FILTER_SPAN];
  for (int r = 0; r < GI_FILTER_IN_ROWS; ++r)
    filterCopyRow(width, height, x0 - GI_FILTER_APRON, y0 - GI_FY / 2 + r, irradiance, depth, geoNormal, instance,
                  &rows[r][0][0]);
#if GI_FILTER_SEPARABLE
  // Separable form, fused: the row pass over every copied row (its E filtered along x at this
  // work-item's columns, each row pixel tested against itself), then below the column pass over
  // those values. The same values as the two-pass form (GI_VW = 1 runs it as two launches).
  float rowE[GI_FILTER_IN_ROWS][3][GI_VW];
  for (int r = 0; r < GI_FILTER_IN_ROWS; ++r) {
    float(*c)[GI_FILTER_SPAN] = rows[r];
    floatV z = vloadV(0, c[3] + GI_FILTER_APRON), nx = vloadV(0, c[4] + GI_FILTER_APRON),
           ny = vloadV(0, c[5] + GI_FILTER_APRON), nz = vloadV(0, c[6] + GI_FILTER_APRON);
    floatV id = GI_SAME_INSTANCE ? vloadV(0, c[GI_FILTER_PLANES - 1] + GI_FILTER_APRON) : z;
    floatV tz = tauZ * z, sr = (floatV)(0.0f), sg = (floatV)(0.0f), sb = (floatV)(0.0f), ws = (floatV)(0.0f);
#pragma unroll
    for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) {
      int o = GI_FILTER_APRON + dx;
      filterAccumulate(filterAccepts(c, o, z, tz, nx, ny, nz, id, cosTauN), vloadV(0, c[0] + o), vloadV(0, c[1] + o),
                       vloadV(0, c[2] + o), &sr, &sg, &sb, &ws);
    }
    intV accepted = ws > 0.0f;
    floatV wdiv = select((floatV)(1.0f), ws, accepted);
    vstoreV(select(vloadV(0, c[0] + GI_FILTER_APRON), sr / wdiv, accepted), 0, rowE[r][0]);
    vstoreV(select(vloadV(0, c[1] + GI_FILTER_APRON), sg / wdiv, accepted), 0, rowE[r][1]);
    vstoreV(select(vloadV(0, c[2] + GI_FILTER_APRON), sb / wdiv, accepted), 0, rowE[r][2]);
  }
#endif
  for (int r = 0; r < GI_FILTER_ROWS; ++r) {
    int y = y0 + r;
    if (y >= height) break;
    float(*own)[GI_FILTER_SPAN] = rows[r + GI_FY / 2];
    floatV z = vloadV(0, own[3] + GI_FILTER_APRON), nx = vloadV(0, own[4] + GI_FILTER_APRON),
           ny = vloadV(0, own[5] + GI_FILTER_APRON), nz = vloadV(0, own[6] + GI_FILTER_APRON);
    floatV id = GI_SAME_INSTANCE ? vloadV(0, own[GI_FILTER_PLANES - 1] + GI_FILTER_APRON) : z;
    size_t i = (size_t)y * width + x0;
    bool whole = x0 + GI_VW <= width;
    // The albedo is loaded before the window loop so that its cache misses overlap the arithmetic.
    floatV ar = (floatV)(0.0f), ag = (floatV)(0.0f), ab = (floatV)(0.0f), unused;
#if GI_FILTER_APPLY_ALBEDO
    if (whole) GI_AOS4_LOAD(albedo + 4 * i, ar, ag, ab, unused)
#endif
    floatV sr = (floatV)(0.0f), sg = (floatV)(0.0f), sb = (floatV)(0.0f), ws = (floatV)(0.0f);
    floatV tz = tauZ * z;
#if GI_FILTER_SEPARABLE
    // Column pass over the row-filtered E, tested against this pixel.
#pragma unroll
    for (int dy = 0; dy < GI_FY; ++dy) {
      filterAccumulate(filterAccepts(rows[r + dy], GI_FILTER_APRON, z, tz, nx, ny, nz, id, cosTauN),
                       vloadV(0, rowE[r + dy][0]), vloadV(0, rowE[r + dy][1]), vloadV(0, rowE[r + dy][2]), &sr, &sg,
                       &sb, &ws);
    }
    floatV ownR = vloadV(0, rowE[r + GI_FY / 2][0]), ownG = vloadV(0, rowE[r + GI_FY / 2][1]),
           ownB = vloadV(0, rowE[r + GI_FY / 2][2]);
#else
#pragma unroll
    for (int dy = 0; dy < GI_FY; ++dy) {
      float(*q)[GI_FILTER_SPAN] = rows[r + dy];
#pragma unroll
      for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) {
        int o = GI_FILTER_APRON + dx;
        filterAccumulate(filterAccepts(q, o, z, tz, nx, ny, nz, id, cosTauN), vloadV(0, q[0] + o), vloadV(0, q[1] + o),
                         vloadV(0, q[2] + o), &sr, &sg, &sb, &ws);
      }
    }
    floatV ownR = vloadV(0, own[0] + GI_FILTER_APRON), ownG = vloadV(0, own[1] + GI_FILTER_APRON),
           ownB = vloadV(0, own[2] + GI_FILTER_APRON);
#endif
    // No neighbour accepted (not even the pixel itself, e.g. a zero normal): its own E. Pixels
    // without a surface (NaN depth): 0.
    intV accepted = ws > 0.0f;
    floatV wdiv = select((floatV)(1.0f), ws, accepted);
    floatV er = select(ownR, sr / wdiv, accepted), eg = select(ownG, sg / wdiv, accepted),
           eb = select(ownB, sb / wdiv, accepted);
    intV surface = !isnan(z);
    if (whole) {
      floatV zero = (floatV)(0.0f);
#if GI_FILTER_APPLY_ALBEDO
      floatV lr = select(zero, ar * (er * GI_INV_PI), surface), lg = select(zero, ag * (eg * GI_INV_PI), surface),
             lb = select(zero, ab * (eb * GI_INV_PI), surface);
#else
      floatV lr = select(zero, er, surface), lg = select(zero, eg, surface), lb = select(zero, eb, surface);
#endif
      GI_AOS4_STORE(out + 4 * i, lr, lg, lb, zero)
    } else {
      float v[4][GI_VW];
      vstoreV(er, 0, v[0]);
      vstoreV(eg, 0, v[1]);
      vstoreV(eb, 0, v[2]);
      vstoreV(convert_floatV(surface), 0, v[3]);
      for (int l = 0; x0 + l < width; ++l) {
        float3 e = (float3)(v[0][l], v[1][l], v[2][l]);
#if GI_FILTER_APPLY_ALBEDO
        e = vload3(0, albedo + 4 * (i + l)) * (e * GI_INV_PI);
#endif
        float3 L = v[3][l] != 0.0f ? e : (float3)(0.0f);
        vstore4((float4)(L, 0.0f), i + l, out);
      }
    }
  }
}
#endif

// Geometry-aware upsampling of irradiance computed at a reduced resolution (factor GI_UP, the
// low-resolution pixel (u, v) stands for full-resolution pixel (u·GI_UP, v·GI_UP) and carries
// that pixel's depth and geometric normal). Each full-resolution pixel takes the 2×2 nearest
// low-resolution pixels with bilinear weights, keeps those passing the §3 test against its own
// depth and normal, renormalises; if none passes it takes the nearest one. Output L = ρ/π · max(0, E).
//
// GI_VW adjacent pixels of a row per work-item: the row's own values are vector loads, the four
// taps per-lane loads (one 128-bit load per float4 record); the vertical tap rows and weights are
// shared by the lanes.
#ifndef GI_UP
#define GI_UP 2
#endif

// Factor 2 with GI_VW > 1: lane l of a block starting at even x0 takes its horizontal taps at
// low-resolution columns b + ⌈l/2⌉ and b + ⌈l/2⌉ + 1 and its nearest pixel at b + ⌊l/2⌋ + 1,
// b = x0/2 − 1: all within GI_VW columns from b. Away from the image's left and right borders a
// block loads each plane once per tap row (low-resolution E contiguously, the guide pixels
// (2(b + r), ·) at fixed offsets from x0) and spreads it over the lanes with fixed swizzles instead
// of gathering per lane with computed indices (the cost that dominated this kernel). The lanes get
// the same values as the gathers give, so the result is bit-identical.
#if GI_UP == 2 && GI_VW > 1
#define GI_UP2_LANES 1
#if GI_VW == 16
#define UP2_TAP0(v) (v).s0112233445566778
#define UP2_TAP1(v) (v).s1223344556677889
#define UP2_NEAREST(v) (v).s1122334455667788
// Guide pixel of low-resolution column b + r relative to x0 (lanes past r = GI_VW/2 + 1 repeat it).
#define UP2_GUIDE_OFFSETS (int16)(-2, 0, 2, 4, 6, 8, 10, 12, 14, 16, 16, 16, 16, 16, 16, 16)
#else
#define UP2_TAP0(v) (v).s01122334
#define UP2_TAP1(v) (v).s12233445
#define UP2_NEAREST(v) (v).s11223344
#define UP2_GUIDE_OFFSETS (int8)(-2, 0, 2, 4, 6, 8, 8, 8)
#endif
#else
#define GI_UP2_LANES 0
#endif
kernel void geometry_aware_upsample(int width, int height, int lowWidth, int lowHeight,
                                    global const float* lowIrradiance, global const float* depth,
                                    global const float* geoNormal, global const uint* instance,
                                    global const float* albedo, float tauZ, float cosTauN,
                                    global float* out) {
  int gx = get_global_id(0), y = get_global_id(1);
  int x0 = gx * GI_VW;
  if (x0 >= width || y >= height) return;
  intV x = x0 + GI_LANES;
  bool whole = x0 + GI_VW <= width;  // every lane is a pixel: contiguous loads and stores
  size_t row = (size_t)y * width;
  intV own = (int)row + min(x, (intV)(width - 1));
  floatV z, nx, ny, nz, unused, ar, ag, ab;
  uintV id;
  if (whole) {
    z = vloadV(0, depth + row + x0);
    id = vloadV(0, instance + row + x0);
    GI_AOS4_LOAD(geoNormal + 4 * (row + x0), nx, ny, nz, unused)
    GI_AOS4_LOAD(albedo + 4 * (row + x0), ar, ag, ab, unused)
  } else {
    z = GI_GATHER(floatV, depth, own);
    id = GI_GATHER(uintV, instance, own);
    GI_GATHER_AOS4(float, geoNormal, own, nx, ny, nz, unused)
    GI_GATHER_AOS4(float, albedo, own, ar, ag, ab, unused)
  }
  floatV fx = (convert_floatV(x) + 0.5f) / (float)GI_UP - 0.5f;
  float fy = ((float)y + 0.5f) / (float)GI_UP - 0.5f;
  intV u0 = clamp(convert_intV(floor(fx)), 0, lowWidth - 1);
  int v0 = clamp((int)floor(fy), 0, lowHeight - 1);
  floatV ax = clamp(fx - convert_floatV(u0), 0.0f, 1.0f);
  float ay = clamp(fy - (float)v0, 0.0f, 1.0f);
  floatV sr = (floatV)(0.0f), sg = (floatV)(0.0f), sb = (floatV)(0.0f), wsum = (floatV)(0.0f);
  floatV tz = tauZ * z;
#if GI_UP2_LANES
  // The block and its taps inside the image: x0 ≥ 2 (b ≥ 0), guide pixels up to x0 + GI_VW + 1,
  // low-resolution columns b … b + GI_VW − 1 in the row.
  int b = x0 / 2 - 1;
  bool interior = whole && x0 >= 2 && x0 + GI_VW + 2 <= width && b + GI_VW <= lowWidth;
#endif
#pragma unroll
  for (int j = 0; j < 2; ++j) {
    int v = min(v0 + j, lowHeight - 1);
    int guideRow = min(v * GI_UP, height - 1) * width;
    float wy = j ? ay : 1.0f - ay;
#if GI_UP2_LANES
    floatV gz, gnx, gny, gnz, ger, geg, geb;  // per low-resolution column b + r (lane r)
    uintV gid;
    if (interior) {
      gz = GI_GATHER(floatV, depth + guideRow + x0, UP2_GUIDE_OFFSETS);
      gid = GI_GATHER(uintV, instance + guideRow + x0, UP2_GUIDE_OFFSETS);
      GI_GATHER_AOS4(float, geoNormal + 4 * (size_t)(guideRow + x0), UP2_GUIDE_OFFSETS, gnx, gny, gnz, unused)
      GI_AOS4_LOAD(lowIrradiance + 4 * (size_t)(v * lowWidth + b), ger, geg, geb, unused)
    }
#endif
#pragma unroll
    for (int k = 0; k < 2; ++k) {
      floatV w = (k ? ax : 1.0f - ax) * wy + 1e-4f;
      floatV qz, qnx, qny, qnz, er, eg, eb;
      uintV qid;
#if GI_UP2_LANES
      if (interior) {
        qz = k ? UP2_TAP1(gz) : UP2_TAP0(gz);
        qid = k ? UP2_TAP1(gid) : UP2_TAP0(gid);
        qnx = k ? UP2_TAP1(gnx) : UP2_TAP0(gnx);
        qny = k ? UP2_TAP1(gny) : UP2_TAP0(gny);
        qnz = k ? UP2_TAP1(gnz) : UP2_TAP0(gnz);
        er = k ? UP2_TAP1(ger) : UP2_TAP0(ger);
        eg = k ? UP2_TAP1(geg) : UP2_TAP0(geg);
        eb = k ? UP2_TAP1(geb) : UP2_TAP0(geb);
      } else
#endif
      {
        intV u = min(u0 + k, lowWidth - 1);
        intV q = guideRow + min(u * GI_UP, width - 1);
        qz = GI_GATHER(floatV, depth, q);
        qid = GI_GATHER(uintV, instance, q);
        GI_GATHER_AOS4(float, geoNormal, q, qnx, qny, qnz, unused)
        GI_GATHER_AOS4(float, lowIrradiance, v * lowWidth + u, er, eg, eb, unused)
      }
#if GI_VW == 1
      bool ok = qid != GI_INVALID_ID && fabs(qz - z) <= tz && qnx * nx + qny * ny + qnz * nz >= cosTauN;
#else
      intV ok = (qid != GI_INVALID_ID) & (fabs(qz - z) <= tz) & (qnx * nx + qny * ny + qnz * nz >= cosTauN);
#endif
      w = GI_SEL((floatV)(0.0f), w, ok);
      sr += w * er;
      sg += w * eg;
      sb += w * eb;
      wsum += w;
    }
  }
  // No tap accepted: the nearest low-resolution pixel.
  intV un = clamp(convert_intV(floor(fx + 0.5f)), 0, lowWidth - 1);
  int vn = clamp((int)floor(fy + 0.5f), 0, lowHeight - 1);
  floatV nr, ng, nb;
#if GI_UP2_LANES
  if (interior) {
    GI_AOS4_LOAD(lowIrradiance + 4 * (size_t)(vn * lowWidth + b), nr, ng, nb, unused)
    nr = UP2_NEAREST(nr);
    ng = UP2_NEAREST(ng);
    nb = UP2_NEAREST(nb);
  } else
#endif
  {
    GI_GATHER_AOS4(float, lowIrradiance, vn * lowWidth + un, nr, ng, nb, unused)
  }
  intV accepted = wsum > 0.0f;
  floatV wdiv = GI_SEL((floatV)(1.0f), wsum, accepted);
  // Irradiance is never negative; second-order's net E_s − E_n can be (ALGORITHMS.md §2.6).
  floatV zero = (floatV)(0.0f);
  intV surface = id != GI_INVALID_ID;
  floatV lr = GI_SEL(zero, ar * (max(GI_SEL(nr, sr / wdiv, accepted), 0.0f) * GI_INV_PI), surface);
  floatV lg = GI_SEL(zero, ag * (max(GI_SEL(ng, sg / wdiv, accepted), 0.0f) * GI_INV_PI), surface);
  floatV lb = GI_SEL(zero, ab * (max(GI_SEL(nb, sb / wdiv, accepted), 0.0f) * GI_INV_PI), surface);
  if (whole) {
    GI_AOS4_STORE(out + 4 * (row + x0), lr, lg, lb, zero)
  } else {
#if GI_VW == 1
    vstore4((float4)(lr, lg, lb, 0.0f), row + x0, out);
#else
    float v[3][GI_VW];
    vstoreV(lr, 0, v[0]);
    vstoreV(lg, 0, v[1]);
    vstoreV(lb, 0, v[2]);
    for (int l = 0; x0 + l < width; ++l) vstore4((float4)(v[0][l], v[1][l], v[2][l], 0.0f), row + x0 + l, out);
#endif
  }
}
