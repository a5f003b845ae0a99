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
#include "common/vector_width.h"

#ifndef GI_SSAO_SAMPLES
#define GI_SSAO_SAMPLES 16
#endif

// How (PERFORMANCE_FACTS.md): one work-item handles GI_VW adjacent pixels of a row as lanes of
// floatV (16 on CPU devices, 1 on GPUs); every per-pixel branch of the formulas above is a lane
// mask, the sample loop has a constant trip count and is unrolled, and the surfaces seen at the
// projected samples are gathered lane by lane. A group cut by the right image border reads its
// last pixel repeatedly and stores only its valid lanes.

// Loads GI_VW float4 of `plane` starting at pixel i into four floatV (valid lanes, the rest repeat).
#define SSAO_LOAD4(plane, i, valid, X, Y, Z, W)                                   \
  if ((valid) == GI_VW) {                                                         \
    GI_AOS4_LOAD((global const float*)((plane) + (i)), X, Y, Z, W)                \
  } else {                                                                        \
    for (int l_ = 0; l_ < GI_VW; ++l_) vstore4((plane)[(i) + min(l_, (valid) - 1)], l_, tmp); \
    GI_AOS4_LOAD(tmp, X, Y, Z, W)                                                 \
  }
#define SSAO_STORE4(plane, i, valid, X, Y, Z, W)                                  \
  if ((valid) == GI_VW) {                                                         \
    GI_AOS4_STORE((global float*)((plane) + (i)), X, Y, Z, W)                     \
  } else {                                                                        \
    GI_AOS4_STORE(tmp, X, Y, Z, W)                                                \
    for (int l_ = 0; l_ < (valid); ++l_) (plane)[(i) + l_] = vload4(l_, tmp);     \
  }

inline floatV ssao_load1(global const float* plane, int i, int valid) {
  if (valid == GI_VW) return vloadV(0, plane + i);
  intV idx = min((intV)(GI_LANES), valid - 1);
  return GI_GATHER(floatV, plane + i, idx);
}

inline void ssao_store1(global float* plane, int i, int valid, floatV v) {
  if (valid == GI_VW) {
    vstoreV(v, 0, plane + i);
  } else {
    float t[GI_VW];
    vstoreV(v, 0, t);
    for (int l = 0; l < valid; ++l) plane[i + l] = t[l];
  }
}

// What the occlusion test of a sample needs about the surface seen at a pixel, in one float4 so
// that a sample costs one gather: the octahedral coordinates of its geometric normal n (seed 004
// Algorithm 1; decoded exactly enough in float), its tangent plane offset n·Q with the decoded n,
// and its view depth. Background: depth +inf (fails every range check).
inline float2 ssao_oct_encode(float3 v) {
  float2 p = v.xy / (fabs(v.x) + fabs(v.y) + fabs(v.z));
  if (v.z < 0.0f) p = (float2)((1.0f - fabs(p.y)) * (p.x >= 0.0f ? 1.0f : -1.0f), (1.0f - fabs(p.x)) * (p.y >= 0.0f ? 1.0f : -1.0f));
  return p;
}

inline void ssao_oct_decodeV(floatV ox, floatV oy, floatV* nx, floatV* ny, floatV* nz) {
  floatV z = 1.0f - fabs(ox) - fabs(oy);
  floatV one = (floatV)(1.0f), minusOne = (floatV)(-1.0f);
  intV lower = z < 0.0f;
  floatV x = GI_SEL(ox, (1.0f - fabs(oy)) * GI_SEL(minusOne, one, ox >= 0.0f), lower);
  floatV y = GI_SEL(oy, (1.0f - fabs(ox)) * GI_SEL(minusOne, one, oy >= 0.0f), lower);
  floatV inv = 1.0f / sqrt(x * x + y * y + z * z);
  *nx = x * inv;
  *ny = y * inv;
  *nz = z * inv;
}

// One pixel per work-item and no loop: PoCL vectorizes it across work-items.
kernel void ssao_planes(int count, global const float4* position, global const float4* geoNormal,
                        global const float* depth, global float4* planes) {
  int i = get_global_id(0);
  if (i >= count) return;
  float4 p = position[i];
  float2 o = ssao_oct_encode(geoNormal[i].xyz);
  floatV nx, ny, nz;
  ssao_oct_decodeV((floatV)(o.x), (floatV)(o.y), &nx, &ny, &nz);  // the n the samples will see
  float t[3 * GI_VW];
  vstoreV(nx, 0, t);
  vstoreV(ny, 1, t);
  vstoreV(nz, 2, t);
  float3 n = (float3)(t[0], t[GI_VW], t[2 * GI_VW]);
  planes[i] = p.w != 0.0f ? (float4)(o, dot(n, p.xyz), depth[i]) : (float4)(0.0f, 0.0f, 0.0f, INFINITY);
}

// kernelVectors: GI_SSAO_SAMPLES float4 (tangent-space x, y, z along n_g, already scaled by the
// length factor lerp(0.1, 1, (i/N)²)); rotations: 16 float2 (cos, sin) for the 4×4 noise tile;
// planes: ssao_planes().
kernel void ssao_occlusion(int width, int height, GiView camera, global const float4* position,
                           global const float4* geoNormal, global const float4* normal,
                           global const float4* planes, global const float* depth, global const float4* direct,
                           constant float4* kernelVectors, constant float2* rotations, float radius,
                           float bias, int bleeding, global float* occlusionOut,
                           global float4* irradianceOut) {
  int px0 = get_global_id(0) * GI_VW, y = get_global_id(1);
  if (px0 >= width || y >= height) return;
  int i0 = y * width + px0, valid = min(GI_VW, width - px0);
  float tmp[4 * GI_VW];
  floatV Px, Py, Pz, Pw, gx, gy, gz, nx, ny, nz, unused;
  SSAO_LOAD4(position, i0, valid, Px, Py, Pz, Pw)
  SSAO_LOAD4(geoNormal, i0, valid, gx, gy, gz, unused)
  SSAO_LOAD4(normal, i0, valid, nx, ny, nz, unused)
  floatV zP = ssao_load1(depth, i0, valid);
  intV surface = Pw != 0.0f;
  // orthonormal_basis() (Duff et al. 2017) lane-wise.
  floatV s = GI_SEL((floatV)(-1.0f), (floatV)(1.0f), gz >= 0.0f);
  floatV a = -1.0f / (s + gz), c = gx * gy * a;
  floatV t0x = 1.0f + s * gx * gx * a, t0y = s * c, t0z = -s * gx;
  floatV b0x = c, b0y = s + gy * gy * a, b0z = -gy;
  // The pixel's entry of the 4×4 rotation tile.
  intV r = ((y & 3) * 4 + ((px0 + GI_LANES) & 3)) * 2;
  constant float* rf = (constant float*)rotations;
  floatV rc = GI_GATHER(floatV, rf, r), rs = GI_GATHER(floatV, rf, r + 1);
  floatV tx = rc * t0x + rs * b0x, ty = rc * t0y + rs * b0y, tz = rc * t0z + rs * b0z;
  floatV bx = rc * b0x - rs * t0x, by = rc * b0y - rs * t0y, bz = rc * b0z - rs * t0z;
  const float As = GI_PI * radius * radius / (float)GI_SSAO_SAMPLES;
  const float d2min = radius * radius / (float)GI_SSAO_SAMPLES;  // A_s/π
  const float* M = camera.view_proj;
  const float W = (float)width, H = (float)height;
  global const float* pos = (global const float*)position;
  global const float* pl = (global const float*)planes;
  global const float* nrm = (global const float*)normal;
  global const float* dir = (global const float*)direct;
  floatV occluded = (floatV)(0.0f), Ex = (floatV)(0.0f), Ey = (floatV)(0.0f), Ez = (floatV)(0.0f);
#pragma unroll
  for (int i = 0; i < GI_SSAO_SAMPLES; ++i) {
    float4 k = kernelVectors[i];
    floatV Sx = Px + radius * (k.x * tx + k.y * bx + k.z * gx);
    floatV Sy = Py + radius * (k.x * ty + k.y * by + k.z * gy);
    floatV Sz = Pz + radius * (k.x * tz + k.y * bz + k.z * gz);
    floatV cx = M[0] * Sx + M[4] * Sy + M[8] * Sz + M[12];
    floatV cy = M[1] * Sx + M[5] * Sy + M[9] * Sz + M[13];
    floatV cw = M[3] * Sx + M[7] * Sy + M[11] * Sz + M[15];
    floatV sx = (cx / cw * 0.5f + 0.5f) * W, sy = (0.5f - cy / cw * 0.5f) * H;
    // cw <= 0: behind the camera, no information; outside the image likewise.
    intV ok = surface & (cw > 0.0f) & (sx >= 0.0f) & (sx < W) & (sy >= 0.0f) & (sy < H);
    if (!GI_ANY(ok)) continue;
    intV q = GI_SEL((intV)(0), convert_intV(GI_SEL((floatV)(0.0f), sy, ok)) * width +
                                   convert_intV(GI_SEL((floatV)(0.0f), sx, ok)), ok);
    intV q4 = q * 4;
    floatV qx, qy, qz;
    ssao_oct_decodeV(GI_GATHER(floatV, pl, q4), GI_GATHER(floatV, pl, q4 + 1), &qx, &qy, &qz);
    floatV qd = GI_GATHER(floatV, pl, q4 + 2), zq = GI_GATHER(floatV, pl, q4 + 3);
    // Background at q: its depth is infinite and fails the range check.
    floatV behind = Sx * qx + Sy * qy + Sz * qz - qd;  // (S − Q) · n_q
    intV occ = ok & (behind < -bias) & (fabs(zq - zP) < radius);
    occluded += GI_SEL((floatV)(0.0f), (floatV)(1.0f), occ);
    if (bleeding && GI_ANY(occ)) {
      floatV Qx = GI_GATHER(floatV, pos, q4), Qy = GI_GATHER(floatV, pos, q4 + 1), Qz = GI_GATHER(floatV, pos, q4 + 2);
      floatV vx = Qx - Px, vy = Qy - Py, vz = Qz - Pz;
      floatV d2 = vx * vx + vy * vy + vz * vz;
      floatV invD = rsqrt(fmax(d2, 1e-30f));
      floatV cosR = fmax((nx * vx + ny * vy + nz * vz) * invD, 0.0f);
      floatV cosS = fmax(-(GI_GATHER(floatV, nrm, q4) * vx + GI_GATHER(floatV, nrm, q4 + 1) * vy +
                           GI_GATHER(floatV, nrm, q4 + 2) * vz) * invD, 0.0f);
      floatV f = GI_SEL((floatV)(0.0f), As * cosS * cosR / fmax(d2, d2min), occ);
      Ex += GI_GATHER(floatV, dir, q4) * f;
      Ey += GI_GATHER(floatV, dir, q4 + 1) * f;
      Ez += GI_GATHER(floatV, dir, q4 + 2) * f;
    }
  }
  ssao_store1(occlusionOut, i0, valid, occluded / (float)GI_SSAO_SAMPLES);
  floatV zero = (floatV)(0.0f);
  SSAO_STORE4(irradianceOut, i0, valid, Ex, Ey, Ez, zero)
}

// Depth-aware 4×4 blur of occlusion and E, then composition into the indirect buffer.
// upstream = 0: no technique before this one in the chain (the indirect input counts as zero).
// Rows of taps are contiguous vector loads inside the image; near the left and right borders the
// taps are gathered with clamped indices and masked.
kernel void ssao_blur_compose(int width, int height, global const float* depth, global const float4* albedo,
                              global const float* occlusionIn, global const float4* irradianceIn, float tau,
                              int upstream, int bleeding, global float* occlusionOut, global float4* indirect) {
  int px0 = get_global_id(0) * GI_VW, y = get_global_id(1);
  if (px0 >= width || y >= height) return;
  int i0 = y * width + px0, valid = min(GI_VW, width - px0);
  float tmp[4 * GI_VW];
  floatV z = ssao_load1(depth, i0, valid);
  floatV zero = (floatV)(0.0f), one = (floatV)(1.0f);
  floatV tol = tau * z, occ = zero, count = zero, Ex = zero, Ey = zero, Ez = zero;
  intV lanes = (intV)(GI_LANES);
  global const float* irr = (global const float*)irradianceIn;
#pragma unroll
  for (int dy = -2; dy <= 1; ++dy) {
    int yy = y + dy;
    if (yy < 0 || yy >= height) continue;
    int row = yy * width;
#pragma unroll
    for (int dx = -2; dx <= 1; ++dx) {
      int x0 = px0 + dx;
      floatV zq, oq, ex = zero, ey = zero, ez = zero, unused;
      intV inside;
      if (x0 >= 0 && x0 + GI_VW <= width) {
        inside = lanes >= 0;  // all lanes
        zq = vloadV(0, depth + row + x0);
        oq = vloadV(0, occlusionIn + row + x0);
        if (bleeding) GI_AOS4_LOAD(irr + (size_t)(row + x0) * 4, ex, ey, ez, unused)
      } else {
        intV xx = x0 + lanes;
        inside = (xx >= 0) & (xx < width);
        intV xc = row + clamp(xx, 0, width - 1);
        zq = GI_GATHER(floatV, depth, xc);
        oq = GI_GATHER(floatV, occlusionIn, xc);
        if (bleeding) {
          intV x4 = xc * 4;
          ex = GI_GATHER(floatV, irr, x4);
          ey = GI_GATHER(floatV, irr, x4 + 1);
          ez = GI_GATHER(floatV, irr, x4 + 2);
        }
      }
      intV take = inside & (fabs(zq - z) <= tol);
      occ += GI_SEL(zero, oq, take);
      count += GI_SEL(zero, one, take);
      if (bleeding) {
        Ex += GI_SEL(zero, ex, take);
        Ey += GI_SEL(zero, ey, take);
        Ez += GI_SEL(zero, ez, take);
      }
    }
  }
  // count >= 1 on surfaces (the centre always passes); background lanes (infinite depth) take
  // nothing and keep the upstream value.
  intV surface = isfinite(z);
  floatV inv = GI_SEL(zero, one / fmax(count, one), surface);
  occ *= inv;
  ssao_store1(occlusionOut, i0, valid, occ);
  floatV ix = zero, iy = zero, iz = zero, iw = zero;
  if (upstream) SSAO_LOAD4(indirect, i0, valid, ix, iy, iz, iw)
  floatV keep = 1.0f - occ;
  floatV ox = keep * ix, oy = keep * iy, oz = keep * iz;
  if (bleeding) {
    floatV ax, ay, az, aw;
    SSAO_LOAD4(albedo, i0, valid, ax, ay, az, aw)
    floatV k = GI_SEL(zero, GI_INV_PI * inv, surface);
    ox += ax * k * Ex;
    oy += ay * k * Ey;
    oz += az * k * Ez;
  }
  SSAO_STORE4(indirect, i0, valid, ox, oy, oz, iw)
}
