// All-pairs VPL gathering with interleaved sampling (ALGORITHMS.md §2, §2.3). Without visibility
// (the default) every VPL lights every receiver it faces (an over-estimate in occluded regions);
// compiled with GI_VPL_VISIBILITY each pair is tested by a shadow ray (vpl_visibility.h).
//
//   gi_deinterleave   camera pixel (x, y) -> packed slot of sub-image c = (x mod n) + n·(y mod m)
//                     at (x / n, y / m): position and normal (shading, or geometric for sh-igi) as six float planes (SoA).
//                     Sub-images are ⌈W/n⌉×⌈H/m⌉, each padded to a multiple of GI_VW slots; slots
//                     without a pixel keep the zero normal they were cleared with (E = 0).
//                     Pattern 1×1 is the plain row-major copy used by the `vpl` technique.
//   vpl_gather        one work-item = GI_VW adjacent slots of one sub-image (float16 lanes on a
//                     CPU, 1 on a GPU); loops over the sub-image's VPL set k = c, c + n·m, …, each
//                     VPL broadcast to all lanes:
//                       E = Σ_p Φ_p · max(0, n_p·ω) · max(0, −n·ω) / (π · max(d², d_min²)) · n·m
//                     written as three irradiance planes (W/m²).
//   gi_reinterleave_radiance   packed E -> camera order, L = ρ/π · E (float4, indirect output);
//   gi_reinterleave_irradiance packed E -> camera order E (float4), for the discontinuity filter.
#include "common/math.h"
#include "common/shared_types.h"
#include "common/vector_width.h"
#include "gi/vpl/vpl_visibility.h"

// x / n and y / m without integer divisions (PoCL turns a division by a run-time value into one
// scalar idiv per lane, which made these copies cost 2-3 ms at 640x360): (x + 0.5) / n is at
// least 0.5 / n >= 1/16 away from an integer, and for x < 16384 (the largest image size) the
// float error of (x + 0.5) · fl(1/n) stays below 0.01, so the truncation is exact.
inline size_t gi_packed_index(int x, int y, int n, int m, int subWidth, int stride) {
  int qx = (int)(((float)x + 0.5f) * (1.0f / (float)n)), qy = (int)(((float)y + 0.5f) * (1.0f / (float)m));
  int c = (x - qx * n) + n * (y - qy * m);
  return (size_t)c * stride + (size_t)qy * subWidth + (size_t)qx;
}

kernel void gi_deinterleave(int width, int height, int n, int m, int subWidth, int stride,
                            global const float4* position, global const float4* normal, global float* planes) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  size_t i = (size_t)y * width + x;
  size_t L = (size_t)n * m * stride;
  size_t o = gi_packed_index(x, y, n, m, subWidth, stride);
  float4 p = position[i];
  float3 nn = p.w > 0.0f ? normal[i].xyz : (float3)(0.0f);  // background: zero normal, E = 0
  planes[o] = p.x;
  planes[L + o] = p.y;
  planes[2 * L + o] = p.z;
  planes[3 * L + o] = nn.x;
  planes[4 * L + o] = nn.y;
  planes[5 * L + o] = nn.z;
}

kernel void vpl_gather(global const float* planes, int sets, int stride, global const float4* vpls, int count,
                       global float* irradiance GI_VPL_VISIBILITY_PARAMS) {
  GI_VPL_VISIBILITY_BEGIN
  size_t g = get_global_id(0);
  size_t L = (size_t)sets * stride;
  if (g * GI_VW >= L) return;
  int set = (int)(g * GI_VW / (size_t)stride);
  floatV px = vloadV(g, planes), py = vloadV(g, planes + L), pz = vloadV(g, planes + 2 * L);
  floatV nx = vloadV(g, planes + 3 * L), ny = vloadV(g, planes + 4 * L), nz = vloadV(g, planes + 5 * L);
  floatV er = (floatV)(0.0f), eg = (floatV)(0.0f), eb = (floatV)(0.0f);
  for (int k = set; k < count; k += sets) {
    float4 a = vpls[3 * k], b = vpls[3 * k + 1], f = vpls[3 * k + 2];
    floatV vx = a.x - px, vy = a.y - py, vz = a.z - pz;  // receiver -> VPL
    floatV d2 = vx * vx + vy * vy + vz * vz;
    floatV cp = -(b.x * vx + b.y * vy + b.z * vz);  // n_p·(x − x_p)
    floatV cr = nx * vx + ny * vy + nz * vz;        // −n·(x − x_p)
    floatV gterm = max(cp, 0.0f) * max(cr, 0.0f) / (max(d2, 1e-20f) * max(d2, a.w));
    gterm = GI_VPL_VISIBLE(px, py, pz, a.xyz, gterm);
    er += f.x * gterm;
    eg += f.y * gterm;
    eb += f.z * gterm;
  }
  float s = (float)sets * GI_INV_PI;
  vstoreV(er * s, g, irradiance);
  vstoreV(eg * s, g, irradiance + L);
  vstoreV(eb * s, g, irradiance + 2 * L);
}

kernel void gi_reinterleave_radiance(int width, int height, int n, int m, int subWidth, int stride,
                                     global const float* irradiance, global const float4* albedo,
                                     global float4* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  size_t i = (size_t)y * width + x;
  size_t L = (size_t)n * m * stride;
  size_t o = gi_packed_index(x, y, n, m, subWidth, stride);
  float3 e = (float3)(irradiance[o], irradiance[L + o], irradiance[2 * L + o]);
  out[i] = (float4)(albedo[i].xyz * (e * GI_INV_PI), 0.0f);
}

kernel void gi_reinterleave_irradiance(int width, int height, int n, int m, int subWidth, int stride,
                                       global const float* irradiance, global float4* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  size_t i = (size_t)y * width + x;
  size_t L = (size_t)n * m * stride;
  size_t o = gi_packed_index(x, y, n, m, subWidth, stride);
  out[i] = (float4)(irradiance[o], irradiance[L + o], irradiance[2 * L + o], 0.0f);
}
