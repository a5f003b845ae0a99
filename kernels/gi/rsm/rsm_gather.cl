// RSM gather (Dachsbacher & Stamminger 2005; ALGORITHMS.md §2.1) at reduced resolution.
//
// Low-resolution pixel (u, v) is evaluated at full-resolution pixel (u·GI_DOWN, v·GI_DOWN) (the
// geometry-aware upsampler, kernels/gi/filters/discontinuity.cl, uses the same convention). The
// receiver x is projected into the light's RSM; GI_SAMPLES texels at offsets
// (r_max·ξ1·sin 2πξ2, r_max·ξ1·cos 2πξ2) (texel units, ξ from the Halton (2, 3) sequence, the
// same pattern for every pixel) are treated as VPLs (ALGORITHMS.md §2 formula, d_min clamp). The
// radius r = r_max·ξ1 puts sample density 1/(2π r_max² ξ1) per texel² on the disc, so each sample
// is weighted by 2π r_max² ξ1 / N (unbiased for the disc; `weights` holds these per sample).
// Output: irradiance E (float4) per low-resolution pixel, accumulated over lights.
//
// Every sample is a per-lane load of a scattered texel (GI_VW adjacent pixels project to different
// texels), and the instructions of those loads dominated the gather (docs/PERFORMANCE.md,
// "Instant radiosity"). So `rsm_pack` first packs each RSM texel into one 16-byte record, read
// per lane with two 64-bit hardware gathers on AVX-512 CPUs (RSM_GATHER_RECORDS), else one 128-bit
// load per lane:
//   word 0     the texel's depth in the light's view, d = −z_view;
//   words 1–3  flux R, G, B (floats) whose 15 low mantissa bits hold the normal's view-space x,
//              y, z as signed integers m = round(s·n) (s: largest component ±16383),
// with the flux divided by |m|, so m·u·(Φ/|m|) = n̂·u·Φ up to the direction's rounding
// (≤ 5.3e-5 rad) and the flux's (8 mantissa bits left: ≤ 2^-9 relative; the stored bits are the
// nearest to Φ/|m| *with* the normal bits in place, so the decoder reads the words as floats with
// no masking). The texel's lateral view-space position is not stored: the RSM resolve intersects
// the ray through the texel centre, so it is (t + ½ − res/2)·s (orthographic, s the texel size) or
// d·(t + ½ − res/2)·s (perspective, s the texel size at distance 1). The record array has a
// one-texel border of zero records (zero flux and normal) around the RSM: samples outside the
// RSM are clamped onto it and contribute 0, with no test in the sample loop. Texels without a
// surface or with zero flux get the same zero record (they contributed 0 before too).
#include "common/math.h"
#include "common/shared_types.h"
#include "common/vector_width.h"

#ifndef GI_DOWN
#define GI_DOWN 2
#endif

// Bits of each normal component in the low mantissa bits of its flux word. 13 bits (±4095,
// 2e-4 rad) left errors of 0.4 % in the Cornell test (coplanar texels near the receiver, whose
// cosine should be 0); 15 bits: 5.3e-5 rad, and 8 mantissa bits of flux (≤ 2^-9 relative).
#define RSM_N_BITS 15
#define RSM_N_MAX 16383.0f

// Lane-wise: the float nearest to f ≥ 0 whose low RSM_N_BITS bits are `low` (candidates: the
// truncated value and one step above and below it). Values below the smallest normal float
// become it (≈ 1.2e-38 W: no denormal operands in the gather).
inline uintV rsm_flux_bits(floatV f, uintV low) {
  const uint step = 1u << RSM_N_BITS;
  uintV upper = max(as_uintV(f) & ~(step - 1u), (uintV)(0x00800000u));
  uintV best = upper | low, up = (upper + step) | low, down = (upper - step) | low;
  floatV bestErr = fabs(as_floatV(best) - f), upErr = fabs(as_floatV(up) - f), downErr = fabs(as_floatV(down) - f);
  best = GI_SEL(best, up, upErr < bestErr);
  bestErr = GI_SEL(bestErr, upErr, upErr < bestErr);
  return GI_SEL(best, down, downErr < bestErr && upper - step >= (uintV)(0x00800000u));
}

// GI_VW texels of an RSM row per work-item -> their records in the bordered array (its border
// records are written once by the host: depth 1, zero flux and normal).
kernel void rsm_pack(GiView view, global const float* position, global const float* normal,
                     global const float* flux, global uint* records) {
  int tx0 = get_global_id(0) * GI_VW, ty = get_global_id(1), res = view.width;
  if (tx0 >= res || ty >= res) return;
  int valid = min(GI_VW, res - tx0);
  size_t i = (size_t)ty * res + tx0, o = (size_t)(ty + 1) * (res + 2) + tx0 + 1;
  floatV px, py, pz, pw, nx, ny, nz, fr, fg, fb, unused;
  if (valid == GI_VW) {
    GI_AOS4_LOAD(position + 4 * i, px, py, pz, pw)
    GI_AOS4_LOAD(normal + 4 * i, nx, ny, nz, unused)
    GI_AOS4_LOAD(flux + 4 * i, fr, fg, fb, unused)
  } else {
    float tp[4 * GI_VW], tn[4 * GI_VW], tf[4 * GI_VW];
    for (int l = 0; l < 4 * GI_VW; ++l) {
      bool in = l < 4 * valid;
      tp[l] = in ? position[4 * i + l] : 0.0f;
      tn[l] = in ? normal[4 * i + l] : 0.0f;
      tf[l] = in ? flux[4 * i + l] : 0.0f;
    }
    GI_AOS4_LOAD(tp, px, py, pz, pw)
    GI_AOS4_LOAD(tn, nx, ny, nz, unused)
    GI_AOS4_LOAD(tf, fr, fg, fb, unused)
  }
  const float* V = view.view;
  floatV vx = V[0] * nx + V[4] * ny + V[8] * nz, vy = V[1] * nx + V[5] * ny + V[9] * nz,
         vz = V[2] * nx + V[6] * ny + V[10] * nz;
  floatV depth = -(V[2] * px + V[6] * py + V[10] * pz + V[14]);
  floatV s = RSM_N_MAX / fmax(fmax(fmax(fabs(vx), fabs(vy)), fabs(vz)), 1e-30f);
  intV mx = convert_intV(rint(vx * s)), my = convert_intV(rint(vy * s)), mz = convert_intV(rint(vz * s));
  floatV fmx = convert_floatV(mx), fmy = convert_floatV(my), fmz = convert_floatV(mz);
  floatV len = sqrt(fmx * fmx + fmy * fmy + fmz * fmz);
  intV lit = pw > 0.0f && (fr > 0.0f || fg > 0.0f || fb > 0.0f) && len > 0.0f;
  floatV inv = 1.0f / GI_SEL((floatV)(1.0f), len, lit);
  const uint lowMask = (1u << RSM_N_BITS) - 1u;
  uintV zero = (uintV)(0u);
  uintV w0 = GI_SEL(as_uintV((floatV)(1.0f)), as_uintV(depth), lit);
  uintV w1 = GI_SEL(zero, rsm_flux_bits(fr * inv, as_uintV(mx) & lowMask), lit);
  uintV w2 = GI_SEL(zero, rsm_flux_bits(fg * inv, as_uintV(my) & lowMask), lit);
  uintV w3 = GI_SEL(zero, rsm_flux_bits(fb * inv, as_uintV(mz) & lowMask), lit);
  if (valid == GI_VW) {
    GI_AOS4_STORE((global float*)(records + 4 * o), as_floatV(w0), as_floatV(w1), as_floatV(w2), as_floatV(w3))
  } else {
    float tr[4 * GI_VW];
    GI_AOS4_STORE(tr, as_floatV(w0), as_floatV(w1), as_floatV(w2), as_floatV(w3))
    for (int l = 0; l < 4 * valid; ++l) records[4 * o + l] = as_uint(tr[l]);
  }
}

// a > b ? a : b and a < b ? a : b: one maxps/minps on x86. fmax/fmin (and max/min on floats)
// treat NaN operands and cost a compare and a blend more per call; here no operand is NaN except
// where a clamp below maps it to its bound.
inline floatV rsm_max(floatV a, floatV b) { return GI_SEL(b, a, a > b); }
inline floatV rsm_min(floatV a, floatV b) { return GI_SEL(b, a, a < b); }

// floor() lane-wise as one rounding instruction: PoCL's library floor() is a compare-and-blend
// sequence on x86 (no vroundps); clang's element-wise builtin maps to llvm.floor. x86 only:
// oclgrind (a SPIR target) cannot execute llvm.floor and rejected the kernels.
#if defined(__x86_64__) && defined(__has_builtin) && __has_builtin(__builtin_elementwise_floor)
#define RSM_FLOOR(x) __builtin_elementwise_floor(x)
#else
#define RSM_FLOOR(x) floor(x)
#endif

// GI_RSM_ROWS low-resolution rows per work-item, evaluated together sample by sample: pixels of
// neighbouring rows project to neighbouring RSM texels, so the rows after the first mostly read
// cache lines the first has just loaded. Each pixel's sum is independent of this choice.
#ifndef GI_RSM_ROWS
#define GI_RSM_ROWS 4
#endif

// Block sums prefetch the record RSM_PREFETCH samples ahead (CPUs): the loop is short enough that
// out-of-order execution no longer hides the record loads' misses (−35 % CPU time on Sponza).
#define RSM_PREFETCH 8

// Sample centre per block (rsm.sample_centre=block): a block is GI_RSM_BLOCK_W low-resolution
// pixels of the work-item's GI_RSM_ROWS rows; its kernels need GI_VW to divide GI_RSM_BLOCK_W.
#ifndef GI_RSM_BLOCK_W
#define GI_RSM_BLOCK_W 8
#endif
#define RSM_BLOCK_PIXELS (GI_RSM_BLOCK_W * GI_RSM_ROWS)
// Projections are clamped to ±2^20 texels before they become integers (receivers far outside
// the RSM: their samples all read the border anyway).
#define RSM_TEXEL_LIMIT 1048576.0f

// The per-row state of the receivers: RSM coordinates (sx, sy), the terms of u = receiver −
// texel (cx, cy, dr; see rsm_gather_rows) and −n in the light's view space.
typedef struct {
  floatV sx, sy, cx, cy, dr, nx, ny, nz;
} RsmReceivers;

// The receivers' projection into the RSM, (sx, sy) in texels, from a position (column-major
// view_proj M). One formula for the vector rows and the scalar block-centre search.
#define RSM_PROJECT(M, res, px, py, pz, sx, sy, ONE)                                 \
  {                                                                                 \
    __typeof__(px) hx_ = M[0] * px + M[4] * py + M[8] * pz + M[12];                 \
    __typeof__(px) hy_ = M[1] * px + M[5] * py + M[9] * pz + M[13];                 \
    __typeof__(px) hw_ = M[3] * px + M[7] * py + M[11] * pz + M[15];                \
    __typeof__(px) invW_ = 1.0f / GI_SEL(hw_, ONE, hw_ == 0.0f);                    \
    sx = (hx_ * invW_ * 0.5f + 0.5f) * (float)(res);                                \
    sy = (0.5f - hy_ * invW_ * 0.5f) * (float)(res);                                \
  }

// GI_VW records at the lanes' word offsets `at` (4 × record index) -> their four words as intV
// planes w0..w3 (word 0..3). With AVX-512 (GI_VW 16 on x86 CPUs) this is the hardware gather of
// each record's two 64-bit halves (two vpgatherdq per 8 lanes) and one even/odd split per plane.
// The portable form (GI_GATHER_SPAN4: one 128-bit load per lane, then a transposition), as PoCL
// compiles it for AVX-512, extracts the offsets lane by lane, splits each record into two 64-bit
// loads and transposes across registers: 626 instructions per sample for the 64 pixels of a
// work-item against 292 with these gathers, and 1.7× the CPU time on Sponza (docs/PERFORMANCE.md,
// "`rsm` gather with AVX-512 hardware gathers"). Gathering the four 32-bit words separately
// (vpgatherdd, twice the loads) took 1.3× the time of the 64-bit halves. Not used with AVX2 (GI_VW
// 8): AVX2 gathers were 2× slower than the portable form on the AMD Zen 3 this engine also runs
// on. Not used on AMD CPUs either: on the AVX-512 AMD EPYC of 2 Dec 2026 (fifth session) the
// portable form's gather took 9.6–10.9 ms against 11.4–16.2 ms with these gathers (six alternating
// idle pairs, docs/PERFORMANCE.md, "rsm gather on an AMD AVX-512 CPU"). The builtin takes a flat
// pointer: x86 OpenCL CPU devices have one address space (only they define __AVX512F__); other
// devices, and compilers without the builtin, take the portable form.
#if defined(__has_builtin) && GI_VW == 16 && defined(__AVX512F__) && !defined(GI_CPU_AMD)
#if __has_builtin(__builtin_ia32_gathersiv8di)
#define RSM_GATHER_HALVES(records, k, at8)                                                              \
  as_int16(__builtin_ia32_gathersiv8di((long8)(0), (const void*)(size_t)((records) + 2 * (k)), (at8), \
                                       (uchar)0xff, 4))
#endif
#endif
#ifdef RSM_GATHER_HALVES
// Lanes 0–7 and 8–15: words 0–1 (k = 0) and 2–3 (k = 1) of each record, which the even/odd
// elements of those halves hold.
#define RSM_GATHER_RECORDS(records, at, w0, w1, w2, w3)  \
  {                                                      \
    intV lo01_ = RSM_GATHER_HALVES(records, 0, (at).lo); \
    intV hi01_ = RSM_GATHER_HALVES(records, 0, (at).hi); \
    intV lo23_ = RSM_GATHER_HALVES(records, 1, (at).lo); \
    intV hi23_ = RSM_GATHER_HALVES(records, 1, (at).hi); \
    w0 = (intV)(lo01_.even, hi01_.even);                 \
    w1 = (intV)(lo01_.odd, hi01_.odd);                   \
    w2 = (intV)(lo23_.even, hi23_.even);                 \
    w3 = (intV)(lo23_.odd, hi23_.odd);                   \
  }
#else
#define RSM_GATHER_RECORDS(records, at, w0, w1, w2, w3) GI_GATHER_SPAN4(int, records, at, w0, w1, w2, w3)
#endif

// Per-pixel centres (rsm.sample_centre=pixel, the paper's form): every sample is the texel
// floor(s + o) of the receiver's own projection s, one per-lane record load per sample and row.
inline __attribute__((always_inline)) void rsm_pixel_centre_sum(
    const RsmReceivers* R, int res, float ts, global const int* records, int sBegin, int sEnd,
    global const float2* offsets, global const float* weights, float dminOverride, floatV* er, floatV* eg, floatV* eb,
    const int ortho, const int clampToRsm) {
  int pitch = res + 2;
  float fixedDmin2 = dminOverride * dminOverride;
  // Perspective texel centre: x_view = d·(ts·t + lateral), y_view = −d·(ts·t' + lateral).
  float lateral = ts * (0.5f - 0.5f * (float)res);
  // Texel coordinates are clamped to [−1, res]: samples outside the RSM read the border.
  floatV loClamp = (floatV)(-1.0f), hiClamp = (floatV)((float)res), zero = (floatV)(0.0f);
  for (int s = sBegin; s < sEnd; ++s) {
    float2 o = offsets[s];
    // The weight carries the 2^-(32 − RSM_N_BITS) of the normal's decoding below (a power of two:
    // the products round exactly as with the unscaled factors).
    float w = weights[s] * (1.0f / (float)(1 << (32 - RSM_N_BITS)));
#pragma unroll
    for (int r = 0; r < GI_RSM_ROWS; ++r) {
      floatV fx, fy;
      if (clampToRsm) {
        fx = RSM_FLOOR(rsm_min(rsm_max(R[r].sx + o.x, loClamp), hiClamp));
        fy = RSM_FLOOR(rsm_min(rsm_max(R[r].sy + o.y, loClamp), hiClamp));
      } else {
        fx = RSM_FLOOR(R[r].sx + o.x);
        fy = RSM_FLOOR(R[r].sy + o.y);
      }
      // The record's word offset 4·((fy + 1)·pitch + fx + 1), exact in float (< 2^24).
      intV at = convert_intV(fy * (float)(4 * pitch) + (fx * 4.0f + (float)(4 * (pitch + 1))));
      intV w0, w1, w2, w3;
      RSM_GATHER_RECORDS(records, at, w0, w1, w2, w3)
      floatV d = as_floatV(w0);
      floatV ux, uy;
      if (ortho) {
        ux = R[r].cx - ts * fx;
        uy = R[r].cy + ts * fy;
      } else {
        ux = R[r].cx - d * (ts * fx + lateral);
        uy = R[r].cy + d * (ts * fy + lateral);
      }
      floatV uz = d - R[r].dr;
      // The normal's integers m times 2^(32 − RSM_N_BITS) (the sign-extending shift back is
      // left out: the scale is exact and `w` undoes it).
      floatV mx = convert_floatV(w1 << (32 - RSM_N_BITS));
      floatV my = convert_floatV(w2 << (32 - RSM_N_BITS));
      floatV mz = convert_floatV(w3 << (32 - RSM_N_BITS));
      floatV d2 = ux * ux + uy * uy + uz * uz;
      floatV cp = mx * ux + my * uy + mz * uz;
      floatV cr = R[r].nx * ux + R[r].ny * uy + R[r].nz * uz;
      floatV dmin2;
      if (dminOverride > 0.0f) {
        dmin2 = (floatV)(fixedDmin2);
      } else if (ortho) {
        dmin2 = (floatV)(0.25f * ts * ts);
      } else {
        dmin2 = (0.25f * ts * ts) * d * d;
      }
      floatV g = rsm_max(cp, zero) * rsm_max(cr, zero) * w / (rsm_max(d2, (floatV)(1e-20f)) * rsm_max(d2, dmin2));
      er[r] += as_floatV(w1) * g;
      eg[r] += as_floatV(w2) * g;
      eb[r] += as_floatV(w3) * g;
    }
  }
}

// One centre texel c for the whole block (rsm.sample_centre=block): sample s is the texel
// c + D_s with D_s = floor(o_s + ½) (the pattern around c's texel centre), the same record for
// every lane and row: one scalar 16-byte load and decode per sample, broadcast to the block's
// GI_VW × GI_RSM_ROWS receivers (the `vpl` gather's form). The weights are the pattern's, so the
// estimate is unbiased for the disc around c instead of around each receiver's own projection.
inline __attribute__((always_inline)) void rsm_block_centre_sum(
    int2 centre, const RsmReceivers* R, int res, float ts, global const int4* records, int sBegin, int sEnd,
    global const int2* blockOffsets, global const float* weights, float dminOverride, floatV* er, floatV* eg,
    floatV* eb, const int ortho) {
  int pitch = res + 2;
  float lateral = ts * (0.5f - 0.5f * (float)res);
  floatV zero = (floatV)(0.0f);
  for (int s = sBegin; s < sEnd; ++s) {
#if GI_VW > 1
    {
      int2 q = blockOffsets[min(s + RSM_PREFETCH, sEnd - 1)];
      __builtin_prefetch(records + (clamp(centre.y + q.y, -1, res) + 1) * pitch + clamp(centre.x + q.x, -1, res) + 1);
    }
#endif
    int2 o = blockOffsets[s];
    int tx = clamp(centre.x + o.x, -1, res), ty = clamp(centre.y + o.y, -1, res);
    int4 rec = records[(ty + 1) * pitch + tx + 1];
    float d = as_float(rec.x), w = weights[s];
    float mx = (float)((rec.y << (32 - RSM_N_BITS)) >> (32 - RSM_N_BITS));
    float my = (float)((rec.z << (32 - RSM_N_BITS)) >> (32 - RSM_N_BITS));
    float mz = (float)((rec.w << (32 - RSM_N_BITS)) >> (32 - RSM_N_BITS));
    float fr = as_float(rec.y) * w, fg = as_float(rec.z) * w, fb = as_float(rec.w) * w;
    // The texel's lateral terms: ux = cx − px, uy = cy + py (see rsm_gather_rows).
    float px = ortho ? ts * (float)tx : d * (ts * (float)tx + lateral);
    float py = ortho ? ts * (float)ty : d * (ts * (float)ty + lateral);
    float dmin2 = dminOverride > 0.0f ? dminOverride * dminOverride : (ortho ? 0.25f * ts * ts : (0.25f * ts * ts) * d * d);
#pragma unroll
    for (int r = 0; r < GI_RSM_ROWS; ++r) {
      floatV ux = R[r].cx - px, uy = R[r].cy + py, uz = d - R[r].dr;
      floatV d2 = ux * ux + uy * uy + uz * uz;
      floatV cp = mx * ux + my * uy + mz * uz;
      floatV cr = R[r].nx * ux + R[r].ny * uy + R[r].nz * uz;
      floatV g = rsm_max(cp, zero) * rsm_max(cr, zero) / (rsm_max(d2, (floatV)(1e-20f)) * rsm_max(d2, (floatV)(dmin2)));
      er[r] += fr * g;
      eg[r] += fg * g;
      eb[r] += fb * g;
    }
  }
}

// The block's centre texel: the floored projection of one of its surface receivers, the one
// within `tolerance` texels (in x and in y) of the most others — candidates in a fixed order,
// starting near the block's middle, stopping at the first that covers all. Receivers beyond the
// tolerance from it use their own centres. Scalar and over the whole block, so the choice does
// not depend on GI_VW. *found = 0 when the block has no surface.
inline int2 rsm_block_centre(int width, int height, int lowWidth, int lowHeight, global const float* gPosition,
                             const float* M, int res, int bu0, int bv0, int tolerance, int* found) {
  int tx[RSM_BLOCK_PIXELS], ty[RSM_BLOCK_PIXELS], n = 0;
  for (int r = 0; r < GI_RSM_ROWS; ++r) {
    for (int c = 0; c < GI_RSM_BLOCK_W; ++c) {
      int u = bu0 + c, v = bv0 + r;
      if (u >= lowWidth || v >= lowHeight) continue;
      float4 p = vload4((size_t)min(v * GI_DOWN, height - 1) * width + min(u * GI_DOWN, width - 1), gPosition);
      if (!(p.w > 0.0f)) continue;
      float sx, sy;
      RSM_PROJECT(M, res, p.x, p.y, p.z, sx, sy, 1.0f)
      tx[n] = (int)floor(fmin(fmax(sx, -RSM_TEXEL_LIMIT), RSM_TEXEL_LIMIT));
      ty[n] = (int)floor(fmin(fmax(sy, -RSM_TEXEL_LIMIT), RSM_TEXEL_LIMIT));
      ++n;
    }
  }
  *found = n > 0;
  if (n == 0) return (int2)(0, 0);
  int start = (n / 2 + GI_RSM_BLOCK_W / 2) % n, best = start, bestCount = 0;
  for (int j = 0; j < n && bestCount < n; ++j) {
    int k = (start + j) % n, count = 0;
    for (int i = 0; i < n; ++i) count += abs(tx[i] - tx[k]) <= tolerance && abs(ty[i] - ty[k]) <= tolerance;
    if (count > bestCount) {
      bestCount = count;
      best = k;
    }
  }
  return (int2)(tx[best], ty[best]);
}

// offsets: float2 per sample in texels; weights: float per sample (2π r_max² ξ1 / N);
// blockOffsets: int2 per sample, floor(offset + ½) (block kernels only). records: rsm_pack's
// output. sampleReach: the largest |offset| component (texels). `ortho` and `block` are
// compile-time constants in the kernels below.
inline void rsm_gather_rows(int width, int height, int lowWidth, int lowHeight, global const float* gPosition,
                            global const float* gNormal, const GiView* rsmView, global const int* records,
                            int samples, global const float2* offsets, global const float* weights,
                            global const int2* blockOffsets, int tolerance, int innerSamples, float dminOverride,
                            float sampleReach, int accumulate,
                            global float4* lowIrradiance, const int ortho, const int block) {
  int gx = get_global_id(0), v0 = get_global_id(1) * GI_RSM_ROWS;
  int u0 = gx * GI_VW;
  if (u0 >= lowWidth || v0 >= lowHeight) return;
  intV uc = min(u0 + GI_LANES, lowWidth - 1);
  const float* M = rsmView->view_proj;
  const float* V = rsmView->view;
  int res = rsmView->width;
  float ts = rsmView->texel_world_size;
  // Per row: the receiver's RSM coordinates (sx, sy) and its position in the light's view space.
  // For texel column t: orthographic ux = xv − x_texel = ts·(sx − ½ − t) = cx − ts·t;
  // perspective ux = xv − d_texel·ts·(t + ½ − res/2) = xv − d_texel·(ts·t + lateral). uy likewise
  // with the texel rows running down (y_view decreasing). uz = d_texel − d_receiver.
  RsmReceivers R[GI_RSM_ROWS];
  floatV er[GI_RSM_ROWS], eg[GI_RSM_ROWS], eb[GI_RSM_ROWS], keep[GI_RSM_ROWS];
  intV surface[GI_RSM_ROWS];
  intV anySurface = (intV)(0);
#pragma unroll
  for (int r = 0; r < GI_RSM_ROWS; ++r) {
    int fy = min(min(v0 + r, lowHeight - 1) * GI_DOWN, height - 1);  // rows past the image repeat the last
    intV pix = (intV)(fy * width) + min(uc * GI_DOWN, width - 1);
    floatV px, py, pz, pw, wx, wy, wz, unused;
    GI_GATHER_AOS4(float, gPosition, pix, px, py, pz, pw)
    GI_GATHER_AOS4(float, gNormal, pix, wx, wy, wz, unused)
    RSM_PROJECT(M, res, px, py, pz, R[r].sx, R[r].sy, (floatV)(1.0f))
    floatV xv = V[0] * px + V[4] * py + V[8] * pz + V[12];
    floatV yv = V[1] * px + V[5] * py + V[9] * pz + V[13];
    R[r].dr = -(V[2] * px + V[6] * py + V[10] * pz + V[14]);
    R[r].cx = ortho ? ts * (R[r].sx - 0.5f) : xv;
    R[r].cy = ortho ? ts * (0.5f - R[r].sy) : yv;
    // −n in view space: cos at the receiver = −n·u.
    R[r].nx = -(V[0] * wx + V[4] * wy + V[8] * wz);
    R[r].ny = -(V[1] * wx + V[5] * wy + V[9] * wz);
    R[r].nz = -(V[2] * wx + V[6] * wy + V[10] * wz);
    er[r] = eg[r] = eb[r] = (floatV)(0.0f);
    keep[r] = GI_SEL((floatV)(0.0f), (floatV)(GI_INV_PI), pw > 0.0f);
    surface[r] = pw > 0.0f;
    anySurface |= surface[r];
  }
  if (block) {
    int found;
    int2 c = rsm_block_centre(width, height, lowWidth, lowHeight, gPosition, M, res,
                              (u0 / GI_RSM_BLOCK_W) * GI_RSM_BLOCK_W, v0, tolerance, &found);
    // Receivers whose own texel is beyond the tolerance from c (other surfaces, e.g. across a
    // depth edge) are gathered around their own projections, as in the per-pixel form.
    intV own[GI_RSM_ROWS];
    intV anyOwn = (intV)(0), anyShared = (intV)(0);
    floatV cxf = (floatV)((float)c.x), cyf = (floatV)((float)c.y), tol = (floatV)((float)tolerance);
    floatV lim = (floatV)(RSM_TEXEL_LIMIT);
#pragma unroll
    for (int r = 0; r < GI_RSM_ROWS; ++r) {
      floatV tx = floor(fmin(fmax(R[r].sx, -lim), lim)), ty = floor(fmin(fmax(R[r].sy, -lim), lim));
      own[r] = surface[r] & (fabs(tx - cxf) > tol || fabs(ty - cyf) > tol);
      anyOwn |= own[r];
      anyShared |= surface[r] & ~own[r];
    }
    // The first innerSamples samples (the host puts those of radius < rsm.block_inner × r_max
    // first) around every receiver's own projection, the rest around c (or, for receivers beyond
    // the tolerance, around their own projections too).
    if (GI_ANY(anySurface) && innerSamples > 0)
      rsm_pixel_centre_sum(R, res, ts, records, 0, innerSamples, offsets, weights, dminOverride, er, eg, eb, ortho, 1);
    floatV pr[GI_RSM_ROWS], pg[GI_RSM_ROWS], pb[GI_RSM_ROWS];
#pragma unroll
    for (int r = 0; r < GI_RSM_ROWS; ++r) {
      pr[r] = er[r];
      pg[r] = eg[r];
      pb[r] = eb[r];
    }
    if (found && GI_ANY(anyShared))
      rsm_block_centre_sum(c, R, res, ts, (global const int4*)records, innerSamples, samples, blockOffsets, weights,
                           dminOverride, er, eg, eb, ortho);
    if (GI_ANY(anyOwn)) {
      rsm_pixel_centre_sum(R, res, ts, records, innerSamples, samples, offsets, weights, dminOverride, pr, pg, pb, ortho, 1);
#pragma unroll
      for (int r = 0; r < GI_RSM_ROWS; ++r) {
        er[r] = GI_SEL(er[r], pr[r], own[r]);
        eg[r] = GI_SEL(eg[r], pg[r], own[r]);
        eb[r] = GI_SEL(eb[r], pb[r], own[r]);
      }
    }
  } else if (GI_ANY(anySurface)) {
    // When every lane's disc (offsets within ±sampleReach texels in x and y) lies in [−1, res],
    // the clamps are no-ops (rounding is monotonic: fl(s + o) ≥ fl(s − reach) ≥ −1): one loop
    // without them (−4 of ≈ 59 vector operations per row and sample; most of Sponza's
    // work-items). Lanes without a surface count too: their records are read all the same.
    intV inside = (intV)(-1);
#pragma unroll
    for (int r = 0; r < GI_RSM_ROWS; ++r)
      inside &= R[r].sx - sampleReach >= -1.0f && R[r].sx + sampleReach <= (float)res &&
                R[r].sy - sampleReach >= -1.0f && R[r].sy + sampleReach <= (float)res;
    if (GI_ALL(inside))
      rsm_pixel_centre_sum(R, res, ts, records, 0, samples, offsets, weights, dminOverride, er, eg, eb, ortho, 0);
    else
      rsm_pixel_centre_sum(R, res, ts, records, 0, samples, offsets, weights, dminOverride, er, eg, eb, ortho, 1);
  }
#pragma unroll
  for (int r = 0; r < GI_RSM_ROWS; ++r) {
    int v = v0 + r;
    if (v >= lowHeight) break;
    floatV ker = er[r] * keep[r], keg = eg[r] * keep[r], keb = eb[r] * keep[r];
#if GI_VW == 1
    {
      size_t o = (size_t)v * lowWidth + u0;
      float4 prev = accumulate ? lowIrradiance[o] : (float4)(0.0f);
      lowIrradiance[o] = prev + (float4)(ker, keg, keb, 0.0f);
    }
#else
    float vals[3][GI_VW];
    vstoreV(ker, 0, vals[0]);
    vstoreV(keg, 0, vals[1]);
    vstoreV(keb, 0, vals[2]);
    for (int l = 0; l < GI_VW; ++l) {
      if (u0 + l >= lowWidth) break;
      size_t o = (size_t)v * lowWidth + u0 + l;
      float4 prev = accumulate ? lowIrradiance[o] : (float4)(0.0f);
      lowIrradiance[o] = prev + (float4)(vals[0][l], vals[1][l], vals[2][l], 0.0f);
    }
#endif
  }
}

#define RSM_GATHER_ARGS                                                                                       \
  int width, int height, int lowWidth, int lowHeight, global const float *gPosition, global const float *gNormal, \
      GiView rsmView, global const int *records, int samples, global const float2 *offsets,                   \
      global const float *weights, global const int2 *blockOffsets, int tolerance, int innerSamples,          \
      float dminOverride, float sampleReach,                                                                  \
      int accumulate, global float4 *lowIrradiance
#define RSM_GATHER_CALL(ortho, block)                                                                         \
  rsm_gather_rows(width, height, lowWidth, lowHeight, gPosition, gNormal, &rsmView, records, samples, offsets, \
                  weights, blockOffsets, tolerance, innerSamples, dminOverride, sampleReach, accumulate, lowIrradiance, \
                  ortho, block)

// Orthographic RSMs (directional lights) and perspective ones (spot and point lights); per-pixel
// sample centres, and (where GI_VW divides the block width) per-block ones.
kernel void rsm_gather_ortho(RSM_GATHER_ARGS) { RSM_GATHER_CALL(1, 0); }
kernel void rsm_gather_perspective(RSM_GATHER_ARGS) { RSM_GATHER_CALL(0, 0); }
#if GI_RSM_BLOCK_W % GI_VW == 0
kernel void rsm_gather_block_ortho(RSM_GATHER_ARGS) { RSM_GATHER_CALL(1, 1); }
kernel void rsm_gather_block_perspective(RSM_GATHER_ARGS) { RSM_GATHER_CALL(0, 1); }
#endif
