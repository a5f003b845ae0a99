// SH-filtered instant global illumination (Segovia & Wald, seed 001; ALGORITHMS.md §2.5, §3).
//
// Instead of irradiance, each pixel gathers the incoming radiance of its interleaved VPL set as
// 9 real SH coefficients (l <= 2, common/sh.h) per colour channel; the 27 coefficients are
// filtered over the n×m window (tests on depth, geometric normal, instance id — never the
// normal-mapped normal), and only then shaded per pixel with the Lambert zonal coefficients at
// the shading normal and the Phong-lobe ones at the reflected view vector. Normal maps keep their
// detail and glossy surfaces get directional indirect light.
//
//   sh_igi_project   de-interleaved sub-images (InterleavedGather planes: position, GEOMETRIC
//                    normal), GI_VW slots per work-item, VPLs of the slot's set broadcast:
//                      L_lm += Y_lm(ω) · Φ_p · max(0, n_p·(−ω)) / (π · d · max(d², d_min²)) · d · n·m
//                    ω the unit direction receiver -> VPL (incoming direction), i.e. the radiance
//                    a surface facing the VPL receives, as a delta in direction (a Monte-Carlo
//                    estimate of ∫ Y_lm L dω). VPLs behind the receiver's geometric tangent plane
//                    cannot light it and are skipped (a visibility-free bound, exact for a plane).
//                    With `direct` every punctual light is added to every pixel as one more
//                    source, weight 1 (it is not split among the sets): E⊥ · shadow-map
//                    visibility · Y_lm(ω_light). Output: 27 planes [channel][coefficient][slot].
//   sh_igi_prepare   packed coefficients -> camera order, into padded planes together with view
//                    depth, geometric normal and instance id (the filter's inputs).
//   sh_igi_filter_shade   box filter of the 27 coefficients over GI_FX × GI_FY accepting
//                    neighbours by the §3 test (same as kernels/gi/filters/discontinuity.cl),
//                    renormalised; then per pixel
//                      L = ρ/π · max(0, Σ Â_l L_lm Y_lm(n_s)) + F0 · max(0, Σ g_l L_lm Y_lm(r))
//                    Â = (π, 2π/3, π/4), g = (1, (s+1)/(s+2), s/(s+3)), s = 2/α² − 2 ∈ [0, 10⁴],
//                    α = roughness², r the view vector reflected about n_s. F0 is the Phong
//                    lobe's specular albedo (no Fresnel angle dependence).
#include "common/math.h"
#include "common/shared_types.h"
#include "common/lights.h"
#include "common/shadow.h"
#include "common/sh.h"
#include "common/vector_width.h"
#include "gi/vpl/vpl_visibility.h"

#define SH_N 9
#define SH_C 27

// The 9 basis functions (sh.h order) at unit direction (x, y, z), lane-wise.
inline void sh9_basisV(floatV x, floatV y, floatV z, floatV* b) {
  b[0] = (floatV)(GI_SH_Y0);
  b[1] = GI_SH_Y1 * y;
  b[2] = GI_SH_Y1 * z;
  b[3] = GI_SH_Y1 * x;
  b[4] = GI_SH_Y2_PRODUCT * x * y;
  b[5] = GI_SH_Y2_PRODUCT * y * z;
  b[6] = GI_SH_Y20 * (3.0f * z * z - 1.0f);
  b[7] = GI_SH_Y2_PRODUCT * x * z;
  b[8] = GI_SH_Y22 * (x * x - y * y);
}

// Band of coefficient k.
#define SH_BAND(k) ((k) == 0 ? 0 : (k) < 4 ? 1 : 2)

kernel void sh_igi_project(global const float* planes, int sets, int stride, global const float4* vpls, int count,
                           int direct, global const GiLight* lights, int lightCount,
                           global const GiView* shadowViews, global const uint* shadowOffsets,
                           global const float* shadowDepths, global float* coeffs GI_VPL_VISIBILITY_PARAMS) {
  GI_VPL_VISIBILITY_BEGIN
  size_t g = get_global_id(0);
  size_t L = (size_t)sets * stride;
  if (g * GI_VW >= L) return;
  int set = (int)(g * GI_VW / (size_t)stride);
  floatV px = vloadV(g, planes), py = vloadV(g, planes + L), pz = vloadV(g, planes + 2 * L);
  floatV nx = vloadV(g, planes + 3 * L), ny = vloadV(g, planes + 4 * L), nz = vloadV(g, planes + 5 * L);
  floatV c[SH_C];
#pragma unroll
  for (int k = 0; k < SH_C; ++k) c[k] = (floatV)(0.0f);
  for (int k = set; k < count; k += sets) {
    float4 a = vpls[3 * k], b = vpls[3 * k + 1], f = vpls[3 * k + 2];
    floatV vx = a.x - px, vy = a.y - py, vz = a.z - pz;  // receiver -> VPL
    floatV d2 = vx * vx + vy * vy + vz * vz;
    floatV invD = rsqrt(fmax(d2, 1e-20f));
    floatV cp = -(b.x * vx + b.y * vy + b.z * vz);  // n_p·(x − x_p) = d · n_p·(−ω)
    floatV front = nx * vx + ny * vy + nz * vz;     // > 0: the VPL is above the geometric tangent plane
    floatV w = GI_SEL((floatV)(0.0f), fmax(cp, 0.0f) * invD / fmax(d2, a.w), front > 0.0f);
    w = GI_VPL_VISIBLE(px, py, pz, a.xyz, w);
    floatV y[SH_N];
    sh9_basisV(vx * invD, vy * invD, vz * invD, y);
#pragma unroll
    for (int i = 0; i < SH_N; ++i) {
      floatV wy = w * y[i];
      c[i] += f.x * wy;
      c[SH_N + i] += f.y * wy;
      c[2 * SH_N + i] += f.z * wy;
    }
  }
  float s = (float)sets * GI_INV_PI;
#pragma unroll
  for (int k = 0; k < SH_C; ++k) c[k] *= s;
  if (direct) {
    // The punctual lights themselves, per lane (scalar light and shadow-map code of common/).
    for (int li = 0; li < lightCount; ++li) {
      global const GiLight* l = &lights[li];
      float er[GI_VW], eg[GI_VW], eb[GI_VW], wx[GI_VW], wy[GI_VW], wz[GI_VW];
      float ax[GI_VW], ay[GI_VW], az[GI_VW], gx[GI_VW], gy[GI_VW], gz[GI_VW];
      vstoreV(px, 0, ax); vstoreV(py, 0, ay); vstoreV(pz, 0, az);
      vstoreV(nx, 0, gx); vstoreV(ny, 0, gy); vstoreV(nz, 0, gz);
      for (int lane = 0; lane < GI_VW; ++lane) {
        float3 x = (float3)(ax[lane], ay[lane], az[lane]), ng = (float3)(gx[lane], gy[lane], gz[lane]);
        float3 wi;
        float dist;
        float3 e = light_incident(l, x, &wi, &dist);
        if (!(dot(ng, wi) > 0.0f) || !(e.x + e.y + e.z > 0.0f)) e = (float3)(0.0f);
        else e *= shadow_visibility(l, shadowViews, shadowOffsets, shadowDepths, x, ng);
        er[lane] = e.x; eg[lane] = e.y; eb[lane] = e.z;
        wx[lane] = wi.x; wy[lane] = wi.y; wz[lane] = wi.z;
      }
      floatV y[SH_N];
      sh9_basisV(vloadV(0, wx), vloadV(0, wy), vloadV(0, wz), y);
      floatV vr = vloadV(0, er), vg = vloadV(0, eg), vb = vloadV(0, eb);
#pragma unroll
      for (int i = 0; i < SH_N; ++i) {
        c[i] += vr * y[i];
        c[SH_N + i] += vg * y[i];
        c[2 * SH_N + i] += vb * y[i];
      }
    }
  }
#pragma unroll
  for (int k = 0; k < SH_C; ++k) vstoreV(c[k], g, coeffs + (size_t)k * L);
}

// Pass 2: one work-item per camera pixel; padded planes of the filter (SH_PAD floats of margin):
// 27 coefficients, view depth, geometric normal x, y, z, instance id (uint bits).
#define SH_PAD 64
#define SH_PLANES 32
kernel void sh_igi_prepare(int width, int height, int n, int m, int subWidth, int stride,
                           global const float* coeffs, global const float* depth, global const float4* geoNormal,
                           global const uint* instance, global float* planes) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  size_t i = (size_t)y * width + x;
  size_t P = (size_t)width * height + 2 * SH_PAD;
  size_t Lp = (size_t)n * m * stride;
  size_t o = (size_t)((x % n) + n * (y % m)) * stride + (size_t)(y / m) * subWidth + (size_t)(x / n);
  global float* out = planes + SH_PAD + i;
#pragma unroll
  for (int k = 0; k < SH_C; ++k) out[k * P] = coeffs[k * Lp + o];
  float4 gn = geoNormal[i];
  out[SH_C * P] = depth[i];
  out[(SH_C + 1) * P] = gn.x;
  out[(SH_C + 2) * P] = gn.y;
  out[(SH_C + 3) * P] = gn.z;
  ((global uint*)out)[(SH_C + 4) * P] = instance[i];
}

#ifndef GI_FX
#define GI_FX 4
#endif
#ifndef GI_FY
#define GI_FY 4
#endif

// Pass 3: GI_VW adjacent pixels of a row per work-item, one unaligned vector load per plane and
// window offset (the margins keep loads in bounds; lanes outside the image are masked), dy outer,
// dx inner (the host mirror's order). Then the zonal shading.
kernel void sh_igi_filter_shade(int width, int height, global const float* planes, global const float4* gPosition,
                                global const float4* gNormal, global const float4* gAlbedo,
                                global const float4* gSpecular, GiView camera, float tauZ, float cosTauN,
                                int sameInstance, int glossy, global float4* out) {
  int gx = get_global_id(0), y = get_global_id(1);
  int x0 = gx * GI_VW;
  if (x0 >= width || y >= height) return;
  size_t P = (size_t)width * height + 2 * SH_PAD;
  global const float* pz = planes + SH_C * P;
  global const float* pnx = planes + (SH_C + 1) * P;
  global const float* pny = planes + (SH_C + 2) * P;
  global const float* pnz = planes + (SH_C + 3) * P;
  global const uint* pid = (global const uint*)(planes + (SH_C + 4) * P);
  size_t c0 = SH_PAD + (size_t)y * width + x0;
  floatV z = vloadV(0, pz + c0), nx = vloadV(0, pnx + c0), ny = vloadV(0, pny + c0), nz = vloadV(0, pnz + c0);
  uintV id = vloadV(0, pid + c0);
  intV xl = x0 + GI_LANES;
  floatV tz = tauZ * z;
  floatV acc[SH_C];
#pragma unroll
  for (int k = 0; k < SH_C; ++k) acc[k] = (floatV)(0.0f);
  floatV ws = (floatV)(0.0f);
#pragma unroll
  for (int dy = -(GI_FY / 2); dy < GI_FY - GI_FY / 2; ++dy) {
    int qy = y + dy;
    if (qy < 0 || qy >= height) continue;
#pragma unroll
    for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) {
      size_t q = (size_t)((long)SH_PAD + (long)qy * width + x0 + dx);
      intV qx = xl + dx;
      uintV qid = vloadV(0, pid + q);
      floatV dz = fabs(vloadV(0, pz + q) - z);
      floatV dn = vloadV(0, pnx + q) * nx + vloadV(0, pny + q) * ny + vloadV(0, pnz + q) * nz;
#if GI_VW == 1
      float wq = (qx >= 0 && qx < width && qid != GI_INVALID_ID && dz <= tz && dn >= cosTauN &&
                  (sameInstance == 0 || qid == id)) ? 1.0f : 0.0f;
#else
      intV ok = (qx >= 0) & (qx < width) & (qid != GI_INVALID_ID) & (dz <= tz) & (dn >= cosTauN) &
                ((intV)(sameInstance == 0 ? -1 : 0) | (qid == id));
      floatV wq = select((floatV)(0.0f), (floatV)(1.0f), ok);
#endif
      ws += wq;
#pragma unroll
      for (int k = 0; k < SH_C; ++k) acc[k] += wq * vloadV(0, planes + (size_t)k * P + q);
    }
  }
  // The centre pixel always passes its own test unless it is background; ws = 0 only there.
  floatV inv = GI_SEL((floatV)(0.0f), 1.0f / ws, ws > 0.0f);

  // Shading inputs, array of structures -> lanes (a partial group repeats its last pixel).
  size_t i = (size_t)y * width + x0;
  int valid = min(GI_VW, width - x0);
  float tmp[4 * GI_VW];
  float3V x, n, alb, f0;
  floatV pw, unused, roughness;
#define SH_LOAD_PLANE(plane, X, Y, Z, W)                                           \
  if (valid == GI_VW) {                                                            \
    GI_AOS4_LOAD((global const float*)(plane + i), X, Y, Z, W)                     \
  } else {                                                                         \
    for (int l = 0; l < GI_VW; ++l) vstore4(plane[i + min(l, valid - 1)], l, tmp); \
    GI_AOS4_LOAD(tmp, X, Y, Z, W)                                                  \
  }
  SH_LOAD_PLANE(gPosition, x.x, x.y, x.z, pw)
  SH_LOAD_PLANE(gNormal, n.x, n.y, n.z, unused)
  SH_LOAD_PLANE(gAlbedo, alb.x, alb.y, alb.z, unused)
  SH_LOAD_PLANE(gSpecular, f0.x, f0.y, f0.z, roughness)
#undef SH_LOAD_PLANE
  floatV yn[SH_N];
  sh9_basisV(n.x, n.y, n.z, yn);
  floatV er = (floatV)(0.0f), eg = (floatV)(0.0f), eb = (floatV)(0.0f);
  const float lambert[3] = {GI_SH_COSCONV0, GI_SH_COSCONV1, GI_SH_COSCONV2};
#pragma unroll
  for (int k = 0; k < SH_N; ++k) {
    floatV t = lambert[SH_BAND(k)] * yn[k];
    er += t * acc[k];
    eg += t * acc[SH_N + k];
    eb += t * acc[2 * SH_N + k];
  }
  float3V Lo = f3v(alb.x * GI_INV_PI * fmax(er * inv, 0.0f), alb.y * GI_INV_PI * fmax(eg * inv, 0.0f),
                   alb.z * GI_INV_PI * fmax(eb * inv, 0.0f));
  if (glossy) {
    float3V wo;
    if (camera.orthographic) {
      float3 w = -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz);
      wo = f3v((floatV)(w.x), (floatV)(w.y), (floatV)(w.z));
    } else {
      wo = safe_normalizeV(f3v(camera.eye[0] - x.x, camera.eye[1] - x.y, camera.eye[2] - x.z), n);
    }
    floatV nv = dotV(n, wo);
    float3V r = f3v(2.0f * nv * n.x - wo.x, 2.0f * nv * n.y - wo.y, 2.0f * nv * n.z - wo.z);
    floatV alpha = fmax(roughness * roughness, 1e-4f);
    floatV s = clamp(2.0f / (alpha * alpha) - 2.0f, 0.0f, 1e4f);
    floatV g1 = (s + 1.0f) / (s + 2.0f), g2 = s / (s + 3.0f);
    floatV yr[SH_N];
    sh9_basisV(r.x, r.y, r.z, yr);
    floatV sr = (floatV)(0.0f), sg = (floatV)(0.0f), sb = (floatV)(0.0f);
#pragma unroll
    for (int k = 0; k < SH_N; ++k) {
      floatV t = (SH_BAND(k) == 0 ? (floatV)(1.0f) : SH_BAND(k) == 1 ? g1 : g2) * yr[k];
      sr += t * acc[k];
      sg += t * acc[SH_N + k];
      sb += t * acc[2 * SH_N + k];
    }
    Lo.x += f0.x * fmax(sr * inv, 0.0f);
    Lo.y += f0.y * fmax(sg * inv, 0.0f);
    Lo.z += f0.z * fmax(sb * inv, 0.0f);
  }
  intV surface = (id != GI_INVALID_ID) & (pw != 0.0f);
  floatV zero = (floatV)(0.0f);
  floatV rx = GI_SEL(zero, Lo.x, surface), ry = GI_SEL(zero, Lo.y, surface), rz = GI_SEL(zero, Lo.z, surface);
  if (valid == GI_VW) {
    GI_AOS4_STORE((global float*)(out + i), rx, ry, rz, zero)
  } else {
    GI_AOS4_STORE(tmp, rx, ry, rz, zero)
    for (int l = 0; l < valid; ++l) out[i + l] = vload4(l, tmp);
  }
}
