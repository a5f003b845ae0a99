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

// offsets: float2 per sample in texels; weights: float per sample (2π r_max² ξ1 / N).
// rsm: position, normal, flux as float4 planes (read as float arrays).
kernel void rsm_gather(int width, int height, int lowWidth, int lowHeight, global const float* gPosition,
                       global const float* gNormal, GiView rsmView, global const float* rsmPosition,
                       global const float* rsmNormal, global const float* rsmFlux, int samples,
                       global const float2* offsets, global const float* weights, float dminOverride,
                       int accumulate, global float4* lowIrradiance) {
  int gx = get_global_id(0), v = get_global_id(1);
  int u0 = gx * GI_VW;
  if (u0 >= lowWidth || v >= lowHeight) return;
  intV u = u0 + GI_LANES;
  intV uc = min(u, lowWidth - 1);
  int fy = min(v * GI_DOWN, height - 1);
  intV pix = (intV)(fy * width) + min(uc * GI_DOWN, width - 1);
  floatV px, py, pz, pw, nx, ny, nz, unused;
  GI_GATHER_AOS4(float, gPosition, pix, px, py, pz, pw)
  GI_GATHER_AOS4(float, gNormal, pix, nx, ny, nz, unused)
  // Project into the RSM (column-major view_proj).
  const float* M = rsmView.view_proj;
  floatV cx = M[0] * px + M[4] * py + M[8] * pz + M[12];
  floatV cy = M[1] * px + M[5] * py + M[9] * pz + M[13];
  floatV cw = M[3] * px + M[7] * py + M[11] * pz + M[15];
  int res = rsmView.width;
  floatV invW = 1.0f / SEL(cw, (floatV)(1.0f), cw == 0.0f);
  floatV sx = (cx * invW * 0.5f + 0.5f) * (float)res, sy = (0.5f - cy * invW * 0.5f) * (float)res;
  float fixedDmin2 = dminOverride * dminOverride;
  float3 axis = -(float3)(rsmView.view[2], rsmView.view[6], rsmView.view[10]);
  float3 eye = vload3(0, rsmView.eye);
  floatV er = (floatV)(0.0f), eg = (floatV)(0.0f), eb = (floatV)(0.0f);
  for (int s = 0; s < samples; ++s) {
    float2 o = offsets[s];
    float w = weights[s];
    intV tx = convert_intV(floor(sx + o.x)), ty = convert_intV(floor(sy + o.y));
    intV inside = tx >= 0 && tx < res && ty >= 0 && ty < res;
    intV t = clamp(ty, 0, res - 1) * res + clamp(tx, 0, res - 1);
    floatV qx, qy, qz, mx, my, mz, fr, fg, fb, qw, mw, fw;
    GI_GATHER_AOS4(float, rsmPosition, t, qx, qy, qz, qw)
    GI_GATHER_AOS4(float, rsmNormal, t, mx, my, mz, mw)
    GI_GATHER_AOS4(float, rsmFlux, t, fr, fg, fb, fw)
    floatV vx = qx - px, vy = qy - py, vz = qz - pz;
    floatV d2 = vx * vx + vy * vy + vz * vz;
    floatV cp = -(mx * vx + my * vy + mz * vz);
    floatV cr = nx * vx + ny * vy + nz * vz;
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
    er += fr * g;
    eg += fg * g;
    eb += fb * g;
  }
  floatV keep = SEL((floatV)(0.0f), (floatV)(GI_INV_PI), pw > 0.0f);
  er *= keep;
  eg *= keep;
  eb *= keep;
#if GI_VW == 1
  {
    size_t o = (size_t)v * lowWidth + u;
    float4 prev = accumulate ? lowIrradiance[o] : (float4)(0.0f);
    lowIrradiance[o] = prev + (float4)(er, eg, eb, 0.0f);
  }
#else
  float vals[3][GI_VW];
  vstoreV(er, 0, vals[0]);
  vstoreV(eg, 0, vals[1]);
  vstoreV(eb, 0, vals[2]);
  for (int l = 0; l < GI_VW; ++l) {
    if (u0 + l >= lowWidth) break;
    size_t o = (size_t)v * lowWidth + u0 + l;
    float4 prev = accumulate ? lowIrradiance[o] : (float4)(0.0f);
    lowIrradiance[o] = prev + (float4)(vals[0][l], vals[1][l], vals[2][l], 0.0f);
  }
#endif
}
