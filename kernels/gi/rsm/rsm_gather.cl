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
// GI_VW adjacent low-resolution pixels per work-item; their RSM texels differ, so RSM reads are
// per-lane loads: one 128-bit load per lane and plane (GI_GATHER_AOS4), not four scalar ones.
#include "common/math.h"
#include "common/shared_types.h"
#include "common/vector_width.h"

#ifndef GI_DOWN
#define GI_DOWN 2
#endif

#if GI_VW == 1
#define SEL(a, b, c) ((c) ? (b) : (a))
#else
#define SEL(a, b, c) select(a, b, c)
#endif

// GI_RSM_ROWS low-resolution rows per work-item, evaluated together sample by sample: pixels of
// neighbouring rows project to neighbouring RSM texels, so the rows after the first mostly read
// cache lines the first has just loaded (the gather is bound by those reads: with every sample
// reading one cached texel it took a third of the time). 4 rows: −35 % CPU time against 1 row
// on the AVX2 EPYC; each pixel's sum is unchanged (same samples, same order, same operations).
#ifndef GI_RSM_ROWS
#define GI_RSM_ROWS 4
#endif

// offsets: float2 per sample in texels; weights: float per sample (2π r_max² ξ1 / N).
// rsm: position, normal, flux as float4 planes (read as float arrays).
kernel void rsm_gather(int width, int height, int lowWidth, int lowHeight, global const float* gPosition,
                       global const float* gNormal, GiView rsmView, global const float* rsmPosition,
                       global const float* rsmNormal, global const float* rsmFlux, int samples,
                       global const float2* offsets, global const float* weights, float dminOverride,
                       int accumulate, global float4* lowIrradiance) {
  int gx = get_global_id(0), v0 = get_global_id(1) * GI_RSM_ROWS;
  int u0 = gx * GI_VW;
  if (u0 >= lowWidth || v0 >= lowHeight) return;
  intV uc = min(u0 + GI_LANES, lowWidth - 1);
  const float* M = rsmView.view_proj;
  int res = rsmView.width;
  floatV px[GI_RSM_ROWS], py[GI_RSM_ROWS], pz[GI_RSM_ROWS], pw[GI_RSM_ROWS], nx[GI_RSM_ROWS], ny[GI_RSM_ROWS],
      nz[GI_RSM_ROWS], sx[GI_RSM_ROWS], sy[GI_RSM_ROWS], er[GI_RSM_ROWS], eg[GI_RSM_ROWS], eb[GI_RSM_ROWS];
#pragma unroll
  for (int r = 0; r < GI_RSM_ROWS; ++r) {
    int fy = min(min(v0 + r, lowHeight - 1) * GI_DOWN, height - 1);  // rows past the image repeat the last
    intV pix = (intV)(fy * width) + min(uc * GI_DOWN, width - 1);
    floatV unused;
    GI_GATHER_AOS4(float, gPosition, pix, px[r], py[r], pz[r], pw[r])
    GI_GATHER_AOS4(float, gNormal, pix, nx[r], ny[r], nz[r], unused)
    // Project into the RSM (column-major view_proj).
    floatV cx = M[0] * px[r] + M[4] * py[r] + M[8] * pz[r] + M[12];
    floatV cy = M[1] * px[r] + M[5] * py[r] + M[9] * pz[r] + M[13];
    floatV cw = M[3] * px[r] + M[7] * py[r] + M[11] * pz[r] + M[15];
    floatV invW = 1.0f / SEL(cw, (floatV)(1.0f), cw == 0.0f);
    sx[r] = (cx * invW * 0.5f + 0.5f) * (float)res;
    sy[r] = (0.5f - cy * invW * 0.5f) * (float)res;
    er[r] = eg[r] = eb[r] = (floatV)(0.0f);
  }
  float fixedDmin2 = dminOverride * dminOverride;
  float3 axis = -(float3)(rsmView.view[2], rsmView.view[6], rsmView.view[10]);
  float3 eye = vload3(0, rsmView.eye);
  for (int s = 0; s < samples; ++s) {
    float2 o = offsets[s];
    float w = weights[s];
#pragma unroll
    for (int r = 0; r < GI_RSM_ROWS; ++r) {
      intV tx = convert_intV(floor(sx[r] + o.x)), ty = convert_intV(floor(sy[r] + o.y));
      intV inside = tx >= 0 && tx < res && ty >= 0 && ty < res;
      intV t = clamp(ty, 0, res - 1) * res + clamp(tx, 0, res - 1);
      floatV qx, qy, qz, mx, my, mz, fr, fg, fb, qw, mw, fw;
      GI_GATHER_AOS4(float, rsmPosition, t, qx, qy, qz, qw)
      GI_GATHER_AOS4(float, rsmNormal, t, mx, my, mz, mw)
      GI_GATHER_AOS4(float, rsmFlux, t, fr, fg, fb, fw)
      floatV vx = qx - px[r], vy = qy - py[r], vz = qz - pz[r];
      floatV d2 = vx * vx + vy * vy + vz * vz;
      floatV cp = -(mx * vx + my * vy + mz * vz);
      floatV cr = nx[r] * vx + ny[r] * vy + nz[r] * vz;
      floatV dmin2;
      if (dminOverride > 0.0f) {
        dmin2 = (floatV)(fixedDmin2);
      } else {
        floatV fp = (floatV)(rsmView.texel_world_size);
        if (!rsmView.orthographic) fp *= fabs((qx - eye.x) * axis.x + (qy - eye.y) * axis.y + (qz - eye.z) * axis.z);
        dmin2 = 0.25f * fp * fp;
      }
      floatV g = max(cp, 0.0f) * max(cr, 0.0f) / (max(d2, 1e-20f) * max(d2, dmin2));
      g = SEL((floatV)(0.0f), g * w, inside != 0);
      er[r] += fr * g;
      eg[r] += fg * g;
      eb[r] += fb * g;
    }
  }
#pragma unroll
  for (int r = 0; r < GI_RSM_ROWS; ++r) {
    int v = v0 + r;
    if (v >= lowHeight) break;
    floatV keep = SEL((floatV)(0.0f), (floatV)(GI_INV_PI), pw[r] > 0.0f);
    floatV ker = er[r] * keep, keg = eg[r] * keep, keb = eb[r] * keep;
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
