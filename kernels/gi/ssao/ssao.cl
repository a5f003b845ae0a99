// Screen-space ambient occlusion after Chapman (2011), as seed 003 §3.5.1 used it, and
// screen-space one-bounce colour bleeding (seed 003 eq. 3.5, after Ritschel et al. 2009).
// ALGORITHMS.md §6; host side and choices: src/gi/ssao/ssao_technique.cpp, docs/techniques/ssao.md.
//
// ssao_occlusion, per camera pixel with surface point P, geometric normal n_g, shading normal n:
//   GI_SSAO_SAMPLES points S_i = P + R·(rotated tangent-space kernel vector k_i) in the hemisphere
//   around n_g. S_i is projected to pixel q; the surface seen there (position Q, geometric normal
//   n_q facing the camera) occludes S_i when S_i lies behind the tangent plane of Q by more than
//   the bias (a first-order reconstruction of "behind the depth buffer" that is exact for planes,
//   so a flat floor is never self-occluded by depth quantisation) and passes the range check
//   |z_Q − z_P| < R (Chapman's hard check: distant foreground does not darken).
//   occlusion = (occluded samples)/N.
//   Colour bleeding (eq. 3.5): every occluding pixel q is a small sender of area A_s = πR²/N
//   emitting the direct radiance L_q seen in the camera image:
//     E(P) = Σ_occluded L_q · A_s · max(cos θ_s, 0) · max(cos θ_r, 0) / max(d², A_s/π),
//   θ_s between n_q and P − Q, θ_r between n and Q − P, d = |Q − P|; the clamp keeps the solid
//   angle of a sender at most that of a disc of area A_s seen from its rim distance (eq. 3.5 is
//   singular at d → 0). E is irradiance (W/m²); the outgoing radiance ρ/π·E is formed after the blur.
// ssao_blur_compose: a 4×4 box (offsets −2..1: every window holds each of the 16 noise rotations
//   once) over occlusion and E that skips neighbours whose view depth differs by more than
//   tau·z from the centre's (never across depth discontinuities), then
//     indirect = (1 − occlusion)·indirect_upstream + bleeding·ρ/π·E.
#include "common/math.h"
#include "common/shared_types.h"

#ifndef GI_SSAO_SAMPLES
#define GI_SSAO_SAMPLES 16
#endif

// kernelVectors: GI_SSAO_SAMPLES float4 (tangent-space x, y, z along n_g, already scaled by the
// length factor lerp(0.1, 1, (i/N)²)); rotations: 16 float2 (cos, sin) for the 4×4 noise tile.
kernel void ssao_occlusion(int width, int height, GiView camera, global const float4* position,
                           global const float4* geoNormal, global const float4* normal,
                           global const float* depth, global const float4* direct,
                           constant float4* kernelVectors, constant float2* rotations, float radius,
                           float bias, int bleeding, global float* occlusionOut,
                           global float4* irradianceOut) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  int pix = y * width + x;
  float4 p4 = position[pix];
  if (p4.w == 0.0f) {  // background: nothing to occlude
    occlusionOut[pix] = 0.0f;
    irradianceOut[pix] = (float4)(0.0f);
    return;
  }
  float3 P = p4.xyz, ng = geoNormal[pix].xyz, n = normal[pix].xyz;
  float zP = depth[pix];
  float3 t0, b0;
  orthonormal_basis(ng, &t0, &b0);
  float2 rot = rotations[(y & 3) * 4 + (x & 3)];
  float3 t = rot.x * t0 + rot.y * b0, b = rot.x * b0 - rot.y * t0;
  const float As = GI_PI * radius * radius / (float)GI_SSAO_SAMPLES;
  const float d2min = radius * radius / (float)GI_SSAO_SAMPLES;  // A_s/π
  const float* M = camera.view_proj;
  int occluded = 0;
  float3 E = (float3)(0.0f);
#pragma unroll
  for (int i = 0; i < GI_SSAO_SAMPLES; ++i) {
    float4 k = kernelVectors[i];
    float3 S = P + radius * (k.x * t + k.y * b + k.z * ng);
    float cx = M[0] * S.x + M[4] * S.y + M[8] * S.z + M[12];
    float cy = M[1] * S.x + M[5] * S.y + M[9] * S.z + M[13];
    float cw = M[3] * S.x + M[7] * S.y + M[11] * S.z + M[15];
    if (cw <= 0.0f) continue;  // behind the camera: no information
    float sx = (cx / cw * 0.5f + 0.5f) * (float)width, sy = (0.5f - cy / cw * 0.5f) * (float)height;
    if (!(sx >= 0.0f && sx < (float)width && sy >= 0.0f && sy < (float)height)) continue;
    int q = (int)sy * width + (int)sx;
    float4 Q4 = position[q];
    if (Q4.w == 0.0f) continue;
    float3 Q = Q4.xyz, nq = geoNormal[q].xyz;
    if (!(dot(S - Q, nq) < -bias)) continue;
    if (!(fabs(depth[q] - zP) < radius)) continue;
    ++occluded;
    if (bleeding) {
      float3 v = Q - P;
      float d2 = dot(v, v);
      float invD = rsqrt(fmax(d2, 1e-30f));
      float cosR = fmax(dot(n, v) * invD, 0.0f);
      float cosS = fmax(-dot(normal[q].xyz, v) * invD, 0.0f);
      E += direct[q].xyz * (As * cosS * cosR / fmax(d2, d2min));
    }
  }
  occlusionOut[pix] = (float)occluded / (float)GI_SSAO_SAMPLES;
  irradianceOut[pix] = (float4)(E, 0.0f);
}

// Depth-aware 4×4 blur of occlusion and E, then composition into the indirect buffer.
// upstream = 0: no technique before this one in the chain (the indirect input counts as zero).
kernel void ssao_blur_compose(int width, int height, global const float* depth, global const float4* albedo,
                              global const float* occlusionIn, global const float4* irradianceIn, float tau,
                              int upstream, int bleeding, global float* occlusionOut, global float4* indirect) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  int pix = y * width + x;
  float z = depth[pix];
  float4 in = upstream ? indirect[pix] : (float4)(0.0f);
  if (!isfinite(z)) {  // background
    occlusionOut[pix] = 0.0f;
    indirect[pix] = in;
    return;
  }
  float tol = tau * z, occ = 0.0f, count = 0.0f;
  float3 E = (float3)(0.0f);
  for (int dy = -2; dy <= 1; ++dy) {
    int yy = y + dy;
    if (yy < 0 || yy >= height) continue;
    for (int dx = -2; dx <= 1; ++dx) {
      int xx = x + dx;
      if (xx < 0 || xx >= width) continue;
      int q = yy * width + xx;
      if (!(fabs(depth[q] - z) <= tol)) continue;
      occ += occlusionIn[q];
      E += irradianceIn[q].xyz;
      count += 1.0f;
    }
  }
  occ /= count;  // count >= 1: the centre always passes
  E /= count;
  occlusionOut[pix] = occ;
  float3 out = (1.0f - occ) * in.xyz;
  if (bleeding) out += albedo[pix].xyz * GI_INV_PI * E;
  indirect[pix] = (float4)(out, in.w);
}
