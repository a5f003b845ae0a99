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
//                    visibility · Y_lm(ω_light). Output: the 27 coefficient planes [channel][k] of
//                    the filter's row blocks (SH_PLANES below).
//   sh_igi_keys      view depth, geometric normal and instance id, camera order -> the same
//                    packed planes (the filter's discontinuity keys).
//   sh_igi_filter_shade   in the packed layout, GI_VW slots of one sub-image row per work-item:
//                    box filter of the 27 coefficients over GI_FX × GI_FY camera pixels accepting
//                    neighbours by the §3 test (same as kernels/gi/filters/discontinuity.cl),
//                    renormalised; then per pixel
//                      L = ρ/π · max(0, Σ Â_l L_lm Y_lm(n_s)) + F0 · max(0, Σ g_l L_lm Y_lm(r))
//                    Â = (π, 2π/3, π/4), g = (1, (s+1)/(s+2), s/(s+3)), s = 2/α² − 2 ∈ [0, 10⁴],
//                    α = roughness², r the view vector reflected about n_s. F0 is the Phong
//                    lobe's specular albedo (no Fresnel angle dependence). Written to camera
//                    order: only the shaded RGB is re-interleaved, never the 27 coefficients.
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

// The filter's planes (host: ShIgiPlanes in src/gi/sh_igi/sh_igi_technique.h), in row blocks: the
// slots of row sy of sub-image c (InterleavedGather's packed layout) form block c·subHeight + sy of
// SH_PLANES rows of `pitch` floats, plane k of the row in row k of the block, after a margin of
// `pad` floats (also after the last block) that holds every slot a window offset can reach from
// a slot of the image. Planes 0..26: the coefficients [channel][k]; 27: view depth; 28..30:
// geometric normal; 31: instance id (uint bits). Why blocks rather than 32 whole-image planes: a
// work-item's 16 window offsets × 27 planes then lie in 16 blocks of a few pages, not 432 pages
// (one TLB miss per load made the whole-plane filter 2× slower than the camera-order one).
#define SH_DEPTH SH_C
#define SH_NORMAL (SH_C + 1)
#define SH_ID (SH_C + 4)
#define SH_PLANES 32

// Work-item of the packed-layout passes: GI_VW consecutive slots sx0 … sx0 + GI_VW − 1 of row sy of
// sub-image c, camera pixel of lane l at (n·(sx0 + l) + cx, y). Ids run over c fastest, then the
// column block, then sy: the n·m work-items of one block read the same neighbour rows of every
// sub-image (each coefficient lies in n·m windows), so those lines are reused while in cache —
// with the column block fastest the filter ran 5–10× slower, streaming from L3.
typedef struct {
  int sx0, sy, c, cx, cy, y;
} ShRow;

// A whole vector of plane slots, stored past the caches on an x86 CPU device (non-temporal): every
// line of the planes is written whole, once per frame, and not read again before the filter, so
// an ordinary store only adds a read for ownership of each line (≈ 25 MB of extra DRAM reads per
// frame at 640×360). On Sponza 640×360 this cut the projection's CPU time by ≈ 20 % and the keys'
// by ≈ 20 % (perf samples, docs/PERFORMANCE.md). The address is a multiple of 64 bytes (pitch,
// pad and a work-item's first slot are multiples of 16 floats; PoCL aligns buffers to 128 bytes),
// as the aligned streaming store requires. Other devices store normally.
#if defined(GI_DEVICE_CPU) && GI_VW > 1 && (defined(__x86_64__) || defined(__i386__))
#define SH_STREAM_STORES 1
#else
#define SH_STREAM_STORES 0
#endif

inline void sh_store_stream(floatV v, global float* p) {
#if SH_STREAM_STORES
  __builtin_nontemporal_store(v, (global floatV*)p);
#else
  vstoreV(v, 0, p);
#endif
}

// Streaming stores are weakly ordered: the last work-item of each group fences them (SFENCE; PoCL's
// mem_fence emits no instruction) before the kernel completes. One fence per group: the
// work-items of a group run in order on one thread.
inline void sh_stream_fence(void) {
#if SH_STREAM_STORES
  if (get_local_id(0) == get_local_size(0) - 1) __builtin_ia32_sfence();
#endif
}

inline global float* sh_block(global float* planes, int pad, int pitch, int subHeight, int c, int sy) {
  return planes + pad + ((size_t)c * subHeight + sy) * SH_PLANES * pitch;
}

inline bool sh_row(int id, int columns, int width, int height, int n, int m, ShRow* r) {
  int sets = n * m;
  int block = id / sets;
  r->c = id - block * sets;
  r->sy = block / columns;
  r->sx0 = (block - r->sy * columns) * GI_VW;
  r->cy = r->c / n;
  r->cx = r->c - r->cy * n;
  r->y = r->sy * m + r->cy;
  return r->y < height && r->sx0 * n + r->cx < width;
}

// Band of coefficient k.
#define SH_BAND(k) ((k) == 0 ? 0 : (k) < 4 ? 1 : 2)

kernel void sh_igi_project(int width, int height, int n, int m, int subWidth, int subHeight, int stride, int pitch,
                           int pad, global const float* receivers, global const float4* vpls, int count, int direct,
                           global const GiLight* lights, int lightCount, global const GiView* shadowViews,
                           global const uint* shadowOffsets, global const float* shadowDepths,
                           global float* planes GI_VPL_VISIBILITY_PARAMS) {
  GI_VPL_VISIBILITY_BEGIN
  ShRow r;
  int columns = (subWidth + GI_VW - 1) / GI_VW;
  if (!sh_row(get_global_id(0), columns, width, height, n, m, &r)) {
    sh_stream_fence();
    return;
  }
  int sets = n * m, set = r.c;
  size_t L = (size_t)sets * stride;  // receivers: InterleavedGather's six planes of L slots
  // InterleavedGather's sub-image rows are stride / subHeight slots apart (subWidth rounded up to 16).
  size_t slot = (size_t)r.c * stride + (size_t)r.sy * (stride / subHeight) + r.sx0;
  int lanes = min(GI_VW, subWidth - r.sx0);
  floatV px, py, pz, nx, ny, nz;
  if (lanes == GI_VW) {
    px = vloadV(0, receivers + slot);
    py = vloadV(0, receivers + L + slot);
    pz = vloadV(0, receivers + 2 * L + slot);
    nx = vloadV(0, receivers + 3 * L + slot);
    ny = vloadV(0, receivers + 4 * L + slot);
    nz = vloadV(0, receivers + 5 * L + slot);
  } else {  // the row's last slots: lanes past it repeat its last slot (never stored)
    intV s = (int)slot + min(GI_LANES, lanes - 1);
    px = GI_GATHER(floatV, receivers, s);
    py = GI_GATHER(floatV, receivers + L, s);
    pz = GI_GATHER(floatV, receivers + 2 * L, s);
    nx = GI_GATHER(floatV, receivers + 3 * L, s);
    ny = GI_GATHER(floatV, receivers + 4 * L, s);
    nz = GI_GATHER(floatV, receivers + 5 * L, s);
  }
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
  global float* o = sh_block(planes, pad, pitch, subHeight, r.c, r.sy) + r.sx0;
#pragma unroll
  for (int k = 0; k < SH_C; ++k) {
    if (lanes == GI_VW) {
      sh_store_stream(c[k], o + (size_t)k * pitch);
    } else {
      float t[GI_VW];
      vstoreV(c[k], 0, t);
      for (int l = 0; l < lanes; ++l) o[(size_t)k * pitch + l] = t[l];
    }
  }
  sh_stream_fence();
}

// Pass 2: the filter's keys (view depth, geometric normal, instance id) from camera order into the
// packed planes; lanes without a camera pixel get the invalid id. A row's last vector may hold
// fewer than GI_VW slots of the row: stored lane by lane, never into the next row's slots.
kernel void sh_igi_keys(int width, int height, int n, int m, int subWidth, int subHeight, int pitch, int pad,
                        global const float* depth, global const float4* geoNormal, global const uint* instance,
                        global float* planes) {
  ShRow r;
  int columns = (subWidth + GI_VW - 1) / GI_VW;
  if (!sh_row(get_global_id(0), columns, width, height, n, m, &r)) {
    sh_stream_fence();
    return;
  }
  intV x = (r.sx0 + GI_LANES) * n + r.cx;
  intV inside = x < width;
  intV i = r.y * width + min(x, width - 1);
  floatV z = GI_GATHER(floatV, depth, i), gnx, gny, gnz, gnw;
  uintV id = GI_SEL((uintV)(GI_INVALID_ID), GI_GATHER(uintV, instance, i), inside);
  GI_GATHER_AOS4(float, (global const float*)geoNormal, i, gnx, gny, gnz, gnw);
  floatV zero = (floatV)(0.0f);
  floatV key[5] = {GI_SEL(zero, z, inside), GI_SEL(zero, gnx, inside), GI_SEL(zero, gny, inside),
                   GI_SEL(zero, gnz, inside), as_floatV(id)};
  global float* o = sh_block(planes, pad, pitch, subHeight, r.c, r.sy) + r.sx0;
  int lanes = min(GI_VW, subWidth - r.sx0);
#pragma unroll
  for (int k = 0; k < 5; ++k) {
    global float* plane = o + (size_t)(SH_DEPTH + k) * pitch;
    if (lanes == GI_VW) {
      sh_store_stream(key[k], plane);
    } else {
      float t[GI_VW];
      vstoreV(key[k], 0, t);
      for (int l = 0; l < lanes; ++l) plane[l] = t[l];
    }
  }
  sh_stream_fence();
}

// ⌊t / d⌋ for |t| ≤ 64, 1 ≤ d ≤ 8 without an integer division (one scalar idiv per window offset
// was a visible share of the filter): (t + ½)/d is at least 1/16 away from an integer and the float
// error is far below that, so the floor is exact.
inline int floor_div_small(int t, int d) { return (int)floor(((float)t + 0.5f) * (1.0f / (float)d)); }

#ifndef GI_FX
#define GI_FX 4
#endif
#ifndef GI_FY
#define GI_FY 4
#endif

// Pass 3, in the packed layout (no re-interleave of the 27 coefficients): the window offset
// (dx, dy) of the pixel in sub-image c = (cx, cy), slot (sx, sy), is the pixel of sub-image
// ((cx + dx) mod n, (cy + dy) mod m) at slot (sx + ⌊(cx + dx)/n⌋, sy + ⌊(cy + dy)/m⌋): the shift
// depends on (c, dx, dy) only, never on the lane, so every window offset is one contiguous vector
// load per plane. Weights (§3 test, dy outer, dx inner: the host mirror's order) first, then the
// coefficients channel by channel — 9 accumulators live instead of 27 — folded into the zonal
// shading sums of the centre pixel. Shading inputs are gathered from camera order and the
// result is written there.
kernel void sh_igi_filter_shade(int width, int height, int n, int m, int subWidth, int subHeight, int pitch, int pad,
                                global const float* planes, global const float4* gPosition,
                                global const float4* gNormal, global const float4* gAlbedo,
                                global const float4* gSpecular, GiView camera, float tauZ, float cosTauN,
                                int sameInstance, int glossy, global float4* out) {
  ShRow r;
  int columns = (subWidth + GI_VW - 1) / GI_VW;
  if (!sh_row(get_global_id(0), columns, width, height, n, m, &r)) return;
  intV x = (r.sx0 + GI_LANES) * n + r.cx;
  size_t blockSize = (size_t)SH_PLANES * pitch;
  global const float* base = planes + pad + ((size_t)r.c * subHeight + r.sy) * blockSize + r.sx0;
  global const float* pz = base + (size_t)SH_DEPTH * pitch;
  global const float* pnx = base + (size_t)SH_NORMAL * pitch;
  global const float* pny = pnx + pitch;
  global const float* pnz = pny + pitch;
  global const uint* pid = (global const uint*)(base + (size_t)SH_ID * pitch);
  floatV z = vloadV(0, pz), nx = vloadV(0, pnx), ny = vloadV(0, pny), nz = vloadV(0, pnz);
  uintV id = vloadV(0, pid);
  floatV tz = tauZ * z;

  floatV w[GI_FX * GI_FY];
  long off[GI_FX * GI_FY];  // window offset q relative to this work-item's first slot, in floats
  floatV ws = (floatV)(0.0f);
#pragma unroll
  for (int dy = -(GI_FY / 2); dy < GI_FY - GI_FY / 2; ++dy) {
    int ty = r.cy + dy, shy = floor_div_small(ty, m);
    int qy = r.y + dy;
#pragma unroll
    for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) {
      int q = (dy + GI_FY / 2) * GI_FX + dx + GI_FX / 2;
      int tx = r.cx + dx, shx = floor_div_small(tx, n);
      int cq = (ty - shy * m) * n + (tx - shx * n);
      off[q] = ((long)(cq - r.c) * subHeight + shy) * (long)blockSize + shx;
      w[q] = (floatV)(0.0f);
      if (qy < 0 || qy >= height) continue;
      long s = off[q];
      intV qx = x + dx;
      uintV qid = vloadV(0, pid + s);
      floatV dz = fabs(vloadV(0, pz + s) - z);
      floatV dn = vloadV(0, pnx + s) * nx + vloadV(0, pny + s) * ny + vloadV(0, pnz + s) * nz;
#if GI_VW == 1
      w[q] = (qx >= 0 && qx < width && qid != GI_INVALID_ID && dz <= tz && dn >= cosTauN &&
              (sameInstance == 0 || qid == id)) ? 1.0f : 0.0f;
#else
      intV ok = (qx >= 0) & (qx < width) & (qid != GI_INVALID_ID) & (dz <= tz) & (dn >= cosTauN) &
                ((intV)(sameInstance == 0 ? -1 : 0) | (qid == id));
      w[q] = select((floatV)(0.0f), (floatV)(1.0f), ok);
#endif
      ws += w[q];
    }
  }
  // The centre pixel always passes its own test unless it is background; ws = 0 only there.
  floatV inv = GI_SEL((floatV)(0.0f), 1.0f / ws, ws > 0.0f);

  // Shading inputs gathered from camera order (lanes past the image repeat the row's last pixel).
  intV inside = x < width;
  intV i = r.y * width + min(x, width - 1);
  float3V p, nrm, alb, f0;
  floatV pw, unused, roughness;
  GI_GATHER_AOS4(float, (global const float*)gPosition, i, p.x, p.y, p.z, pw);
  GI_GATHER_AOS4(float, (global const float*)gNormal, i, nrm.x, nrm.y, nrm.z, unused);
  GI_GATHER_AOS4(float, (global const float*)gAlbedo, i, alb.x, alb.y, alb.z, unused);
  GI_GATHER_AOS4(float, (global const float*)gSpecular, i, f0.x, f0.y, f0.z, roughness);
  // Zonal weights of each coefficient: Lambert at the shading normal, Phong lobe at r.
  floatV tn[SH_N], tr[SH_N];
  sh9_basisV(nrm.x, nrm.y, nrm.z, tn);
  const float lambert[3] = {GI_SH_COSCONV0, GI_SH_COSCONV1, GI_SH_COSCONV2};
#pragma unroll
  for (int k = 0; k < SH_N; ++k) tn[k] = lambert[SH_BAND(k)] * tn[k];
  if (glossy) {
    float3V wo;
    if (camera.orthographic) {
      float3 v = -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz);
      wo = f3v((floatV)(v.x), (floatV)(v.y), (floatV)(v.z));
    } else {
      wo = safe_normalizeV(f3v(camera.eye[0] - p.x, camera.eye[1] - p.y, camera.eye[2] - p.z), nrm);
    }
    floatV nv = dotV(nrm, wo);
    float3V rv = f3v(2.0f * nv * nrm.x - wo.x, 2.0f * nv * nrm.y - wo.y, 2.0f * nv * nrm.z - wo.z);
    floatV alpha = fmax(roughness * roughness, 1e-4f);
    floatV s = clamp(2.0f / (alpha * alpha) - 2.0f, 0.0f, 1e4f);
    floatV g1 = (s + 1.0f) / (s + 2.0f), g2 = s / (s + 3.0f);
    sh9_basisV(rv.x, rv.y, rv.z, tr);
#pragma unroll
    for (int k = 1; k < SH_N; ++k) tr[k] *= SH_BAND(k) == 1 ? g1 : g2;
  } else {
#pragma unroll
    for (int k = 0; k < SH_N; ++k) tr[k] = (floatV)(0.0f);
  }

  // Filter the 9 coefficient planes of each channel over the window (window offset outer: one
  // weight and 9 accumulators live), then fold them into the shading sums.
  floatV diffuse[3], specular[3];
  for (int ch = 0; ch < 3; ++ch) {
    global const float* channel = base + (size_t)ch * SH_N * pitch;
    floatV acc[SH_N];
#pragma unroll
    for (int k = 0; k < SH_N; ++k) acc[k] = (floatV)(0.0f);
#pragma unroll
    for (int q = 0; q < GI_FX * GI_FY; ++q) {
      floatV wq = w[q];
      global const float* src = channel + off[q];
#pragma unroll
      for (int k = 0; k < SH_N; ++k) acc[k] += wq * vloadV(0, src + (size_t)k * pitch);
    }
    floatV e = (floatV)(0.0f), sp = (floatV)(0.0f);
#pragma unroll
    for (int k = 0; k < SH_N; ++k) {
      e += tn[k] * acc[k];
      sp += tr[k] * acc[k];
    }
    diffuse[ch] = e;
    specular[ch] = sp;
  }
  floatV zero = (floatV)(0.0f);
  intV surface = (id != GI_INVALID_ID) & (pw != 0.0f) & inside;
  floatV res[3];
#pragma unroll
  for (int ch = 0; ch < 3; ++ch) {
    floatV a = ch == 0 ? alb.x : ch == 1 ? alb.y : alb.z, f = ch == 0 ? f0.x : ch == 1 ? f0.y : f0.z;
    floatV L = a * GI_INV_PI * fmax(diffuse[ch] * inv, 0.0f);
    if (glossy) L += f * fmax(specular[ch] * inv, 0.0f);
    res[ch] = GI_SEL(zero, L, surface);
  }
  float t[4 * GI_VW];
  GI_AOS4_STORE(t, res[0], res[1], res[2], zero)
  int lanes = min(GI_VW, (width - 1 - r.cx) / n - r.sx0 + 1);  // lanes with a camera pixel
  int row = r.y * width + r.sx0 * n + r.cx;
  for (int l = 0; l < lanes; ++l) out[row + l * n] = vload4(l, t);
}
