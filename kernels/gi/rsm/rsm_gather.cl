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
// with one 128-bit load per lane:
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
// sequence on x86 (no vroundps); clang's element-wise builtin maps to llvm.floor.
#if defined(__has_builtin) && __has_builtin(__builtin_elementwise_floor)
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

// offsets: float2 per sample in texels; weights: float per sample (2π r_max² ξ1 / N).
// records: rsm_pack's output. `ortho` is a compile-time constant in the two kernels below.
inline void rsm_gather_rows(int width, int height, int lowWidth, int lowHeight, global const float* gPosition,
                            global const float* gNormal, const GiView* rsmView, global const int* records,
                            int samples, global const float2* offsets, global const float* weights,
                            float dminOverride, int accumulate, global float4* lowIrradiance, const int ortho) {
  int gx = get_global_id(0), v0 = get_global_id(1) * GI_RSM_ROWS;
  int u0 = gx * GI_VW;
  if (u0 >= lowWidth || v0 >= lowHeight) return;
  intV uc = min(u0 + GI_LANES, lowWidth - 1);
  const float* M = rsmView->view_proj;
  const float* V = rsmView->view;
  int res = rsmView->width, pitch = res + 2;
  float ts = rsmView->texel_world_size;
  // Per row: the receiver's RSM coordinates (sx, sy) and its position in the light's view space.
  // For texel column t: orthographic ux = xv − x_texel = ts·(sx − ½ − t) = cx − ts·t;
  // perspective ux = xv − d_texel·ts·(t + ½ − res/2) = xv − d_texel·(ts·t + lateral). uy likewise
  // with the texel rows running down (y_view decreasing). uz = d_texel − d_receiver.
  floatV sx[GI_RSM_ROWS], sy[GI_RSM_ROWS], cx[GI_RSM_ROWS], cy[GI_RSM_ROWS], dr[GI_RSM_ROWS], nx[GI_RSM_ROWS],
      ny[GI_RSM_ROWS], nz[GI_RSM_ROWS], er[GI_RSM_ROWS], eg[GI_RSM_ROWS], eb[GI_RSM_ROWS], keep[GI_RSM_ROWS];
  intV anySurface = (intV)(0);
#pragma unroll
  for (int r = 0; r < GI_RSM_ROWS; ++r) {
    int fy = min(min(v0 + r, lowHeight - 1) * GI_DOWN, height - 1);  // rows past the image repeat the last
    intV pix = (intV)(fy * width) + min(uc * GI_DOWN, width - 1);
    floatV px, py, pz, pw, wx, wy, wz, unused;
    GI_GATHER_AOS4(float, gPosition, pix, px, py, pz, pw)
    GI_GATHER_AOS4(float, gNormal, pix, wx, wy, wz, unused)
    // Project into the RSM (column-major view_proj).
    floatV hx = M[0] * px + M[4] * py + M[8] * pz + M[12];
    floatV hy = M[1] * px + M[5] * py + M[9] * pz + M[13];
    floatV hw = M[3] * px + M[7] * py + M[11] * pz + M[15];
    floatV invW = 1.0f / GI_SEL(hw, (floatV)(1.0f), hw == 0.0f);
    sx[r] = (hx * invW * 0.5f + 0.5f) * (float)res;
    sy[r] = (0.5f - hy * invW * 0.5f) * (float)res;
    floatV xv = V[0] * px + V[4] * py + V[8] * pz + V[12];
    floatV yv = V[1] * px + V[5] * py + V[9] * pz + V[13];
    dr[r] = -(V[2] * px + V[6] * py + V[10] * pz + V[14]);
    cx[r] = ortho ? ts * (sx[r] - 0.5f) : xv;
    cy[r] = ortho ? ts * (0.5f - sy[r]) : yv;
    // −n in view space: cos at the receiver = −n·u.
    nx[r] = -(V[0] * wx + V[4] * wy + V[8] * wz);
    ny[r] = -(V[1] * wx + V[5] * wy + V[9] * wz);
    nz[r] = -(V[2] * wx + V[6] * wy + V[10] * wz);
    er[r] = eg[r] = eb[r] = (floatV)(0.0f);
    keep[r] = GI_SEL((floatV)(0.0f), (floatV)(GI_INV_PI), pw > 0.0f);
    anySurface |= pw > 0.0f;
  }
  if (GI_ANY(anySurface)) {
    float fixedDmin2 = dminOverride * dminOverride;
    // Perspective texel centre: x_view = d·(ts·t + lateral), y_view = −d·(ts·t' + lateral).
    float lateral = ts * (0.5f - 0.5f * (float)res);
    // Texel coordinates are clamped to [−1, res]: samples outside the RSM read the border.
    floatV loClamp = (floatV)(-1.0f), hiClamp = (floatV)((float)res), zero = (floatV)(0.0f);
    for (int s = 0; s < samples; ++s) {
      float2 o = offsets[s];
      float w = weights[s];
#pragma unroll
      for (int r = 0; r < GI_RSM_ROWS; ++r) {
        floatV fx = RSM_FLOOR(rsm_min(rsm_max(sx[r] + o.x, loClamp), hiClamp));
        floatV fy = RSM_FLOOR(rsm_min(rsm_max(sy[r] + o.y, loClamp), hiClamp));
        uintV t = convert_uintV(convert_intV(fy) * pitch + convert_intV(fx) + (pitch + 1));
        intV w0, w1, w2, w3;
        GI_GATHER_AOS4(int, records, t, w0, w1, w2, w3)
        floatV d = as_floatV(w0);
        floatV ux, uy;
        if (ortho) {
          ux = cx[r] - ts * fx;
          uy = cy[r] + ts * fy;
        } else {
          ux = cx[r] - d * (ts * fx + lateral);
          uy = cy[r] + d * (ts * fy + lateral);
        }
        floatV uz = d - dr[r];
        floatV mx = convert_floatV(((w1) << (32 - RSM_N_BITS)) >> (32 - RSM_N_BITS));
        floatV my = convert_floatV(((w2) << (32 - RSM_N_BITS)) >> (32 - RSM_N_BITS));
        floatV mz = convert_floatV(((w3) << (32 - RSM_N_BITS)) >> (32 - RSM_N_BITS));
        floatV d2 = ux * ux + uy * uy + uz * uz;
        floatV cp = mx * ux + my * uy + mz * uz;
        floatV cr = nx[r] * ux + ny[r] * uy + nz[r] * uz;
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
      global const float *weights, float dminOverride, int accumulate, global float4 *lowIrradiance
#define RSM_GATHER_CALL(ortho)                                                                                \
  rsm_gather_rows(width, height, lowWidth, lowHeight, gPosition, gNormal, &rsmView, records, samples, offsets, \
                  weights, dminOverride, accumulate, lowIrradiance, ortho)

// Orthographic RSMs (directional lights) and perspective ones (spot and point lights).
kernel void rsm_gather_ortho(RSM_GATHER_ARGS) { RSM_GATHER_CALL(1); }
kernel void rsm_gather_perspective(RSM_GATHER_ARGS) { RSM_GATHER_CALL(0); }
