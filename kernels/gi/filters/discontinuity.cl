// Discontinuity (geometry-aware) filter and geometry-aware upsampling (ALGORITHMS.md §3).
//
// Neighbour q contributes to pixel p only if |z_q − z_p| ≤ τ_z·z_p, n_q·n_p ≥ cos τ_n (geometric
// normals) and, when asked, q has p's instance id. Box weights over a GI_FX × GI_FY window
// (offsets −⌊GI_FX/2⌋ … GI_FX−1−⌊GI_FX/2⌋, so a window of the interleave pattern's size holds
// exactly one pixel of every pixel class), renormalised by the accepted weights. The filtered
// quantity is irradiance E; the output is the radiance L = ρ/π · E (the albedo is applied after
// filtering, so texture detail stays sharp).
//
// One pixel per work-item with the window loops fully unrolled (compile-time GI_FX, GI_FY): no
// loop remains, so PoCL vectorises across work-items (PERFORMANCE_FACTS.md points 1 and 7).
#include "common/math.h"
#include "common/shared_types.h"

#ifndef GI_FX
#define GI_FX 4
#endif
#ifndef GI_FY
#define GI_FY 4
#endif

kernel void discontinuity_filter(int width, int height, global const float4* irradiance,
                                 global const float* depth, global const float4* geoNormal,
                                 global const uint* instance, global const float4* albedo, float tauZ,
                                 float cosTauN, int sameInstance, global float4* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  size_t i = (size_t)y * width + x;
  uint id = instance[i];
  if (id == GI_INVALID_ID) {
    out[i] = (float4)(0.0f);
    return;
  }
  float z = depth[i];
  float3 n = geoNormal[i].xyz;
  float3 sum = (float3)(0.0f);
  float wsum = 0.0f;
#pragma unroll
  for (int dy = -(GI_FY / 2); dy < GI_FY - GI_FY / 2; ++dy) {
#pragma unroll
    for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) {
      int qx = x + dx, qy = y + dy;
      if (qx >= 0 && qx < width && qy >= 0 && qy < height) {
        size_t q = (size_t)qy * width + qx;
        uint qid = instance[q];
        bool ok = qid != GI_INVALID_ID && fabs(depth[q] - z) <= tauZ * z && dot(geoNormal[q].xyz, n) >= cosTauN &&
                  (sameInstance == 0 || qid == id);
        if (ok) {
          sum += irradiance[q].xyz;
          wsum += 1.0f;
        }
      }
    }
  }
  float3 e = wsum > 0.0f ? sum / wsum : irradiance[i].xyz;
  out[i] = (float4)(albedo[i].xyz * (e * GI_INV_PI), 0.0f);
}

// Geometry-aware upsampling of irradiance computed at a reduced resolution (factor GI_UP, the
// low-resolution pixel (u, v) stands for full-resolution pixel (u·GI_UP, v·GI_UP) and carries
// that pixel's depth and geometric normal). Each full-resolution pixel takes the 2×2 nearest
// low-resolution pixels with bilinear weights, keeps those passing the §3 test against its own
// depth and normal, renormalises; if none passes it takes the nearest one. Output L = ρ/π · E.
#ifndef GI_UP
#define GI_UP 2
#endif
kernel void geometry_aware_upsample(int width, int height, int lowWidth, int lowHeight,
                                    global const float4* lowIrradiance, global const float* depth,
                                    global const float4* geoNormal, global const uint* instance,
                                    global const float4* albedo, float tauZ, float cosTauN,
                                    global float4* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  size_t i = (size_t)y * width + x;
  if (instance[i] == GI_INVALID_ID) {
    out[i] = (float4)(0.0f);
    return;
  }
  float z = depth[i];
  float3 n = geoNormal[i].xyz;
  float fx = ((float)x + 0.5f) / (float)GI_UP - 0.5f, fy = ((float)y + 0.5f) / (float)GI_UP - 0.5f;
  int u0 = clamp((int)floor(fx), 0, lowWidth - 1), v0 = clamp((int)floor(fy), 0, lowHeight - 1);
  float ax = clamp(fx - (float)u0, 0.0f, 1.0f), ay = clamp(fy - (float)v0, 0.0f, 1.0f);
  float3 sum = (float3)(0.0f);
  float wsum = 0.0f;
#pragma unroll
  for (int j = 0; j < 2; ++j) {
#pragma unroll
    for (int k = 0; k < 2; ++k) {
      int u = min(u0 + k, lowWidth - 1), v = min(v0 + j, lowHeight - 1);
      size_t q = (size_t)min(v * GI_UP, height - 1) * width + min(u * GI_UP, width - 1);
      float w = (k ? ax : 1.0f - ax) * (j ? ay : 1.0f - ay) + 1e-4f;
      bool ok = instance[q] != GI_INVALID_ID && fabs(depth[q] - z) <= tauZ * z && dot(geoNormal[q].xyz, n) >= cosTauN;
      if (ok) {
        sum += w * lowIrradiance[(size_t)v * lowWidth + u].xyz;
        wsum += w;
      }
    }
  }
  int un = clamp((int)floor(fx + 0.5f), 0, lowWidth - 1), vn = clamp((int)floor(fy + 0.5f), 0, lowHeight - 1);
  float3 e = wsum > 0.0f ? sum / wsum : lowIrradiance[(size_t)vn * lowWidth + un].xyz;
  out[i] = (float4)(albedo[i].xyz * (e * GI_INV_PI), 0.0f);
}
