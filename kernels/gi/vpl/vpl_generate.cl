// VPL generation from one light's reflective shadow map (ALGORITHMS.md §2, §2.2).
//
// Flux-importance sampling with a marginal/conditional CDF over the RSM texels, built on the
// device every frame (no read-back):
//   vpl_row_cdf       one work-item per RSM row: inclusive prefix of luminance(Φ) along the row
//                     (texel CDF, unnormalised) and the row's total;
//   vpl_marginal_cdf  one work-item: inclusive prefix of the row totals (row CDF);
//   vpl_sample        one work-item per VPL k: Halton point (radical inverse of k+1 in bases 2
//                     and 3); u2 picks the row by the row CDF, u1 the texel within it. The texel is
//                     picked with probability pdf = lum(Φ_texel) / Σ lum, and the VPL gets
//                     flux Φ_texel / (N · pdf) — an unbiased estimate of the RSM's total flux.
// Deterministic: no atomics, the same arithmetic in the same order every frame.
//
// VPL layout (float4 ×3 per VPL, consecutive): (position, d_min²), (normal, 0), (flux Φ_p, 0).
// d_min defaults to 0.5 × the RSM texel footprint at the VPL (ALGORITHMS.md §2): the texel size
// for orthographic RSMs, texel size at unit distance × view depth for perspective ones. A
// positive `dminOverride` replaces it.
#include "common/math.h"
#include "common/shared_types.h"
#include "gi/vpl/vpl_sequence.h"

kernel void vpl_row_cdf(global const float4* flux, int res, global float* texelCdf, global float* rowSum) {
  int row = get_global_id(0);
  if (row >= res) return;
  global const float4* f = flux + (size_t)row * res;
  global float* c = texelCdf + (size_t)row * res;
  float s = 0.0f;
  for (int x = 0; x < res; ++x) {
    s += max(luminance(f[x].xyz), 0.0f);
    c[x] = s;
  }
  rowSum[row] = s;
}

kernel void vpl_marginal_cdf(global const float* rowSum, int res, global float* rowCdf) {
  if (get_global_id(0) != 0) return;
  float s = 0.0f;
  for (int y = 0; y < res; ++y) {
    s += rowSum[y];
    rowCdf[y] = s;
  }
}

// First index in [0, n) whose inclusive prefix exceeds t (the last one if none does).
inline int cdf_search(global const float* cdf, int n, float t) {
  int lo = 0, hi = n - 1;
  while (lo < hi) {
    int mid = (lo + hi) >> 1;
    if (cdf[mid] > t) hi = mid;
    else lo = mid + 1;
  }
  return lo;
}

kernel void vpl_sample(GiView view, global const float4* rsmPosition, global const float4* rsmNormal,
                       global const float4* rsmFlux, int res, global const float* texelCdf,
                       global const float* rowCdf, int count, float dminOverride, int firstVpl,
                       global float4* vpls) {
  int k = get_global_id(0);
  if (k >= count) return;
  global float4* out = vpls + (size_t)(firstVpl + k) * 3;
  float total = rowCdf[res - 1];
  if (!(total > 0.0f)) {
    out[0] = (float4)(0.0f, 0.0f, 0.0f, 1.0f);
    out[1] = (float4)(0.0f);
    out[2] = (float4)(0.0f);
    return;
  }
  float u1 = radical_inverse((uint)k + 1u, 2u), u2 = radical_inverse((uint)k + 1u, 3u);
  int y = cdf_search(rowCdf, res, u2 * total);
  float rowTotal = rowCdf[y] - (y > 0 ? rowCdf[y - 1] : 0.0f);
  global const float* tc = texelCdf + (size_t)y * res;
  int x = cdf_search(tc, res, u1 * tc[res - 1]);
  size_t t = (size_t)y * res + x;
  float4 p = rsmPosition[t];
  float3 phi = rsmFlux[t].xyz;
  float lum = max(luminance(phi), 0.0f);
  // pdf = (rowTotal / total) · (lum / rowTotal) = lum / total.
  float3 w = lum > 0.0f ? phi * (total / ((float)count * lum)) : (float3)(0.0f);
  float footprint = view.texel_world_size;
  if (!view.orthographic) {
    float3 axis = -(float3)(view.view[2], view.view[6], view.view[10]);
    footprint *= fabs(dot(p.xyz - vload3(0, view.eye), axis));
  }
  float dmin = dminOverride > 0.0f ? dminOverride : 0.5f * footprint;
  out[0] = (float4)(p.xyz, dmin * dmin);
  out[1] = (float4)(rsmNormal[t].xyz, 0.0f);
  out[2] = (float4)(w, 0.0f);
}
