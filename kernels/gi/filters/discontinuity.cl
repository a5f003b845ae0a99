// Discontinuity (geometry-aware) filter and geometry-aware upsampling (ALGORITHMS.md §3).
//
// Neighbour q contributes to pixel p only if |z_q − z_p| ≤ τ_z·z_p, n_q·n_p ≥ cos τ_n (geometric
// normals) and, when asked, q has p's instance id. Box weights over a GI_FX × GI_FY window
// (offsets −⌊GI_FX/2⌋ … GI_FX−1−⌊GI_FX/2⌋, so a window of the interleave pattern's size holds
// exactly one pixel of every pixel class), renormalised by the accepted weights. The filtered
// quantity is irradiance E; the output is the radiance L = ρ/π · E (the albedo is applied after
// filtering, so texture detail stays sharp).
//
// Two passes (below): a padded SoA copy, then GI_VW pixels of a row per work-item with the window
// loops unrolled (compile-time GI_FX, GI_FY) and one vector load per plane and offset
// (PERFORMANCE_FACTS.md points 2, 6, 7).
#include "common/math.h"
#include "common/shared_types.h"
#include "common/vector_width.h"

#ifndef GI_FX
#define GI_FX 4
#endif
#ifndef GI_FY
#define GI_FY 4
#endif

// Pass 1 (16 pixels per work-item on every device): copy what the filter reads into padded float planes
// (SoA, GI_FILTER_PAD floats of margin before and after) so that pass 2 can load 16 neighbours
// of a row with one unaligned vector load: E r, g, b; view depth; geometric normal x, y, z;
// instance id (as uint bits).
#define GI_FILTER_PAD 64
kernel void discontinuity_prepare(int width, int height, global const float4* irradiance, global const float* depth,
                                  global const float4* geoNormal, global const uint* instance, global float* planes) {
  size_t g = get_global_id(0);
  size_t n = (size_t)width * height;
  size_t i0 = g * 16;
  if (i0 >= n) return;
  size_t L = n + 2 * GI_FILTER_PAD;
  global float* o = planes + GI_FILTER_PAD + i0;
  if (i0 + 16 <= n) {
    // 16 pixels: four float16 loads per float4 plane, transposed by swizzles (no gathers).
    global const float* e = (global const float*)(irradiance + i0);
    float16 a = vload16(0, e), b = vload16(1, e), c = vload16(2, e), d = vload16(3, e);
    vstore16((float16)(a.s048c, b.s048c, c.s048c, d.s048c), 0, o);
    vstore16((float16)(a.s159d, b.s159d, c.s159d, d.s159d), 0, o + L);
    vstore16((float16)(a.s26ae, b.s26ae, c.s26ae, d.s26ae), 0, o + 2 * L);
    vstore16(vload16(0, depth + i0), 0, o + 3 * L);
    global const float* q = (global const float*)(geoNormal + i0);
    a = vload16(0, q);
    b = vload16(1, q);
    c = vload16(2, q);
    d = vload16(3, q);
    vstore16((float16)(a.s048c, b.s048c, c.s048c, d.s048c), 0, o + 4 * L);
    vstore16((float16)(a.s159d, b.s159d, c.s159d, d.s159d), 0, o + 5 * L);
    vstore16((float16)(a.s26ae, b.s26ae, c.s26ae, d.s26ae), 0, o + 6 * L);
    vstore16(vload16(0, instance + i0), 0, (global uint*)(o + 7 * L));
  } else {
    for (size_t i = i0; i < n; ++i) {
      global float* p = planes + GI_FILTER_PAD + i;
      float4 e = irradiance[i], gn = geoNormal[i];
      p[0] = e.x;
      p[L] = e.y;
      p[2 * L] = e.z;
      p[3 * L] = depth[i];
      p[4 * L] = gn.x;
      p[5 * L] = gn.y;
      p[6 * L] = gn.z;
      ((global uint*)p)[7 * L] = instance[i];
    }
  }
}

#if GI_VW == 1
#define FSEL(a, b, c) ((c) ? (b) : (a))
#define FLOAD(p) (*(p))
#define ULOAD(p) (*(p))
#else
#define FSEL(a, b, c) select(a, b, c)
#define FLOAD(p) vloadV(0, p)
#define ULOAD(p) vloadV(0, p)
#endif

// Pass 2: GI_VW adjacent pixels of a row per work-item; every window offset is one unaligned
// vector load per plane, lanes outside the image masked (the planes' margins keep the loads in
// bounds). Same test, same summation order (dy outer, dx inner) as the host mirror in the tests.
kernel void discontinuity_filter(int width, int height, global const float* planes, global const float4* albedo,
                                 float tauZ, float cosTauN, int sameInstance, global float4* out) {
  int gx = get_global_id(0), y = get_global_id(1);
  int x0 = gx * GI_VW;
  if (x0 >= width || y >= height) return;
  size_t L = (size_t)width * height + 2 * GI_FILTER_PAD;
  global const float* pr = planes;
  global const float* pg = planes + L;
  global const float* pb = planes + 2 * L;
  global const float* pz = planes + 3 * L;
  global const float* pnx = planes + 4 * L;
  global const float* pny = planes + 5 * L;
  global const float* pnz = planes + 6 * L;
  global const uint* pid = (global const uint*)(planes + 7 * L);
  size_t c = GI_FILTER_PAD + (size_t)y * width + x0;
  floatV z = FLOAD(pz + c), nx = FLOAD(pnx + c), ny = FLOAD(pny + c), nz = FLOAD(pnz + c);
  uintV id = ULOAD(pid + c);
  intV xl = x0 + GI_LANES;
  floatV sr = (floatV)(0.0f), sg = (floatV)(0.0f), sb = (floatV)(0.0f), ws = (floatV)(0.0f);
  floatV tz = tauZ * z;
#pragma unroll
  for (int dy = -(GI_FY / 2); dy < GI_FY - GI_FY / 2; ++dy) {
    int qy = y + dy;
    if (qy < 0 || qy >= height) continue;
#pragma unroll
    for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) {
      size_t q = (size_t)((long)GI_FILTER_PAD + (long)qy * width + x0 + dx);
      intV qx = xl + dx;
      uintV qid = ULOAD(pid + q);
      floatV dz = fabs(FLOAD(pz + q) - z);
      floatV dn = FLOAD(pnx + q) * nx + FLOAD(pny + q) * ny + FLOAD(pnz + q) * nz;
#if GI_VW == 1
      bool ok = qx >= 0 && qx < width && qid != GI_INVALID_ID && dz <= tz && dn >= cosTauN &&
                (sameInstance == 0 || qid == id);
      if (ok) {
        sr += FLOAD(pr + q);
        sg += FLOAD(pg + q);
        sb += FLOAD(pb + q);
        ws += 1.0f;
      }
#else
      intV ok = (qx >= 0) & (qx < width) & (qid != GI_INVALID_ID) & (dz <= tz) & (dn >= cosTauN) &
                ((intV)(sameInstance == 0 ? -1 : 0) | (qid == id));
      sr += FSEL((floatV)(0.0f), FLOAD(pr + q), ok);
      sg += FSEL((floatV)(0.0f), FLOAD(pg + q), ok);
      sb += FSEL((floatV)(0.0f), FLOAD(pb + q), ok);
      ws += FSEL((floatV)(0.0f), (floatV)(1.0f), ok);
#endif
    }
  }
#if GI_VW == 1
  {
    size_t i = (size_t)y * width + x0;
    float3 e = ws > 0.0f ? (float3)(sr, sg, sb) / ws : (float3)(pr[c], pg[c], pb[c]);
    out[i] = id == GI_INVALID_ID ? (float4)(0.0f) : (float4)(albedo[i].xyz * (e * GI_INV_PI), 0.0f);
  }
#else
  float v[4][GI_VW];
  vstoreV(sr, 0, v[0]);
  vstoreV(sg, 0, v[1]);
  vstoreV(sb, 0, v[2]);
  vstoreV(ws, 0, v[3]);
  for (int l = 0; l < GI_VW; ++l) {
    if (x0 + l >= width) break;
    size_t i = (size_t)y * width + x0 + l;
    uint il = pid[c + l];
    float3 e = v[3][l] > 0.0f ? (float3)(v[0][l], v[1][l], v[2][l]) / v[3][l] : (float3)(pr[c + l], pg[c + l], pb[c + l]);
    out[i] = il == GI_INVALID_ID ? (float4)(0.0f) : (float4)(albedo[i].xyz * (e * GI_INV_PI), 0.0f);
  }
#endif
}

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
  intV own = (int)row + min(x, width - 1);
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
