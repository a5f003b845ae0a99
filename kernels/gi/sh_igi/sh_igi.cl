// SH-filtered instant global illumination (Segovia & Wald, seed 001; ALGORITHMS.md §2.5, §3).
//
// Instead of irradiance, each pixel gathers the incoming radiance of its interleaved VPL set as
// 9 real SH coefficients (l <= 2, common/sh.h) per colour channel; the 27 coefficients are
// filtered over the n×m window (tests on depth, geometric normal, instance id — never the
// normal-mapped normal), and only then shaded per pixel with the Lambert zonal coefficients at
// the shading normal and the Phong-lobe ones at the reflected view vector. Normal maps keep their
// detail and glossy surfaces get directional indirect light.
//
// Everything runs in camera order: no sub-image copies. A work-item takes GI_VW consecutive
// pixels of one camera row; pixel (x, y) belongs to VPL set (x mod n) + n·(y mod m), so the lanes
// of a work-item belong to different sets and each lane reads its own VPL from a per-frame lane
// table (sh_igi_vpl_lanes) — one vector load per VPL attribute, as the broadcast of a sub-image's
// shared VPL was one scalar load.
//
//   sh_igi_vpl_lanes  the VPL lane table: for each lane phase (x0 mod n, y mod m) and iteration k,
//                    the 10 attributes (position, 1/d_min², normal, flux) of VPL set_l + n·m·k of
//                    every lane l as GI_VW-wide vectors; lanes whose set has no k-th VPL get a VPL
//                    of zero flux and normal (weight 0, adds exactly nothing).
//   sh_igi_project   per pixel x, over its VPL set p:
//                      L_lm += Y_lm(ω) · Φ_p · max(0, n_p·(−ω)) / (π · d · max(d², d_min²)) · d · n·m
//                    ω the unit direction receiver -> VPL (incoming direction), i.e. the radiance
//                    a surface facing the VPL receives, as a delta in direction (a Monte-Carlo
//                    estimate of ∫ Y_lm L dω). VPLs behind the receiver's geometric tangent plane
//                    cannot light it and are skipped (a visibility-free bound, exact for a plane).
//                    With `direct` every punctual light is added to every pixel as one more
//                    source, weight 1 (it is not split among the sets): E⊥ · shadow-map
//                    visibility · Y_lm(ω_light). Output: the 27 coefficient planes [channel][k] and
//                    the filter's keys (view depth, geometric normal, instance id) in the row
//                    blocks of SH_PLANES below.
//   sh_igi_filter_shade   GI_VW pixels of one row per work-item: box filter of the 27
//                    coefficients over GI_FX × GI_FY pixels accepting neighbours by the §3 test
//                    (same as kernels/gi/filters/discontinuity.cl), renormalised; then per pixel
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

// The filter's planes (host: ShIgiPlanes in src/gi/sh_igi/sh_igi_technique.h), in row blocks: camera
// row y is block y of SH_PLANES rows of `pitch` floats, plane k of the row in row k of the block,
// pixel x at column x; `pad` floats before the first block. Planes 0..26: the coefficients
// [channel][k]; 27: view depth; 28..30: geometric normal; 31: instance id (uint bits). The pitch
// leaves a margin of at least 16 floats after the row's last whole vector, so a window offset's
// vector load never leaves the buffer (columns outside the image are rejected by the x test).
// Why blocks rather than 32 whole-image planes: a work-item's window then lies in GI_FY blocks of
// a few pages, not 32·GI_FY pages far apart.
#define SH_DEPTH SH_C
#define SH_NORMAL (SH_C + 1)
#define SH_ID (SH_C + 4)
#define SH_PLANES 32
#define SH_VPL_ATTRS 10  // lane table: position x, y, z, 1/d_min², normal x, y, z, flux r, g, b

// A whole vector of plane slots, stored past the caches on an x86 CPU device (non-temporal): every
// line of the planes is written whole, once per frame, and not read again before the filter, so
// an ordinary store only adds a read for ownership of each line (≈ 25 MB of extra DRAM reads per
// frame at 640×360; it cut the projection's CPU time by ≈ 20 %, docs/PERFORMANCE.md). The address
// is a multiple of 64 bytes (pitch, pad and a work-item's first pixel are multiples of 16 floats;
// PoCL aligns buffers to 128 bytes), as the aligned streaming store requires. Other devices store
// normally.
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

// 1/√x for x > 0. With AVX-512 (16 lanes, one zmm register) the 14-bit hardware estimate and one
// Newton step (relative error ≈ 1e-7): PoCL's rsqrt is a square root and a division, and with
// the distance clamp's division they stalled the projection on the divider (−12 % of its CPU time
// without them, docs/PERFORMANCE.md, sh-igi, "Eighth round"). Elsewhere the library rsqrt.
inline floatV sh_rsqrtV(floatV x) {
#if defined(GI_DEVICE_CPU) && GI_VW == 16 && defined(__AVX512F__)
  floatV y = __builtin_ia32_rsqrt14ps512_mask(x, (floatV)(0.0f), (ushort)0xffff);
  return y * fma(-0.5f * x, y * y, (floatV)(1.5f));
#else
  return rsqrt(x);
#endif
}

// Work-item id -> its first pixel x0 and row y (row-major: the work-items of a row are adjacent).
inline bool sh_pixels(int width, int height, int* x0, int* y) {
  int columns = (width + GI_VW - 1) / GI_VW, id = get_global_id(0);
  *y = id / columns;
  *x0 = (id - *y * columns) * GI_VW;
  return *y < height;
}

// Lane phase of the work-item starting at (x0, y): lane l holds pixel x0 + l of VPL set
// ((phase mod n) + l) mod n + n·(phase / n).
inline int sh_phase(int x0, int y, int n, int m) { return x0 % n + n * (y % m); }

kernel void sh_igi_vpl_lanes(int n, int m, int count, int iterations, global const float4* vpls,
                             global float* table) {
  int sets = n * m, id = get_global_id(0);
  if (id >= sets * iterations) return;
  int phase = id / iterations, k = id - phase * iterations;
  int px = phase % n, cy = phase / n;
  global float* o = table + (size_t)id * SH_VPL_ATTRS * GI_VW;
  for (int l = 0; l < GI_VW; ++l) {
    int v = (px + l) % n + n * cy + sets * k;
    float4 a = (float4)(0.0f, 0.0f, 0.0f, 1.0f), b = (float4)(0.0f), f = (float4)(0.0f);
    if (v < count) {
      a = vpls[3 * v];
      b = vpls[3 * v + 1];
      f = vpls[3 * v + 2];
    }
    // 1/d_min² (+inf for d_min = 0: the clamp never acts), so the projection needs no division.
    float attr[SH_VPL_ATTRS] = {a.x, a.y, a.z, 1.0f / a.w, b.x, b.y, b.z, f.x, f.y, f.z};
    for (int j = 0; j < SH_VPL_ATTRS; ++j) o[j * GI_VW + l] = attr[j];
  }
}

kernel void sh_igi_project(int width, int height, int n, int m, int pitch, int pad, global const float* position,
                           global const float* geoNormal, global const float* depth, global const uint* instance,
                           global const float* vplLanes, int iterations, int direct, global const GiLight* lights,
                           int lightCount, global const GiView* shadowViews, global const uint* shadowOffsets,
                           global const float* shadowDepths, global float* planes GI_VPL_VISIBILITY_PARAMS) {
  GI_VPL_VISIBILITY_BEGIN
  int x0, y;
  if (!sh_pixels(width, height, &x0, &y)) {
    sh_stream_fence();
    return;
  }
  intV x = x0 + GI_LANES;
  intV inside = x < width;
  size_t row = (size_t)y * width;
  floatV px, py, pz, pw, nx, ny, nz, nw, z;
  uintV id;
  if (x0 + GI_VW <= width) {
    GI_AOS4_LOAD(position + 4 * (row + x0), px, py, pz, pw)
    GI_AOS4_LOAD(geoNormal + 4 * (row + x0), nx, ny, nz, nw)
    z = vloadV(0, depth + row + x0);
    id = vloadV(0, instance + row + x0);
  } else {  // the row's last pixels: lanes past it repeat its last pixel, with the invalid id
    intV i = (int)row + min(x, (intV)(width - 1));
    GI_GATHER_AOS4(float, position, i, px, py, pz, pw)
    GI_GATHER_AOS4(float, geoNormal, i, nx, ny, nz, nw)
    z = GI_GATHER(floatV, depth, i);
    id = GI_SEL((uintV)(GI_INVALID_ID), GI_GATHER(uintV, instance, i), inside);
  }
  floatV zero = (floatV)(0.0f);
  intV surface = inside & (pw > 0.0f);  // background: zero normal, no VPL faces it
  floatV gx = GI_SEL(zero, nx, surface), gy = GI_SEL(zero, ny, surface), gz = GI_SEL(zero, nz, surface);
  floatV c[SH_C];
#pragma unroll
  for (int k = 0; k < SH_C; ++k) c[k] = zero;
  global const float* t = vplLanes + (size_t)sh_phase(x0, y, n, m) * iterations * SH_VPL_ATTRS * GI_VW;
  for (int k = 0; k < iterations; ++k, t += SH_VPL_ATTRS * GI_VW) {
    floatV vx = vloadV(0, t) - px, vy = vloadV(1, t) - py, vz = vloadV(2, t) - pz;  // receiver -> VPL
    floatV d2 = vx * vx + vy * vy + vz * vz;
    floatV invD = sh_rsqrtV(fmax(d2, 1e-20f));
    floatV cp = -(vloadV(4, t) * vx + vloadV(5, t) * vy + vloadV(6, t) * vz);  // n_p·(x − x_p) = d · n_p·(−ω)
    floatV front = gx * vx + gy * vy + gz * vz;  // > 0: the VPL is above the geometric tangent plane
    // 1/max(d², d_min²) = min(1/d², 1/d_min²)
    floatV w = GI_SEL(zero, fmax(cp, 0.0f) * invD * fmin(invD * invD, vloadV(3, t)), front > 0.0f);
    w = GI_VPL_VISIBLE_LANES(px, py, pz, vloadV(0, t), vloadV(1, t), vloadV(2, t), w);
    // The basis polynomials without their constants (applied once after the loop): 1, y, z, x, xy,
    // yz, z², xz, x² − y² of ω; Y20 = c·(3z² − 1) is formed from the z² and 1 sums.
    floatV ox = vx * invD, oy = vy * invD, oz = vz * invD;
    floatV b[SH_N] = {(floatV)(1.0f), oy, oz, ox, ox * oy, oy * oz, oz * oz, ox * oz, (ox - oy) * (ox + oy)};
    floatV wr = w * vloadV(7, t), wg = w * vloadV(8, t), wb = w * vloadV(9, t);
    c[0] += wr;
    c[SH_N] += wg;
    c[2 * SH_N] += wb;
#pragma unroll
    for (int i = 1; i < SH_N; ++i) {
      c[i] += wr * b[i];
      c[SH_N + i] += wg * b[i];
      c[2 * SH_N + i] += wb * b[i];
    }
  }
  float s = (float)(n * m) * GI_INV_PI;
  const float basisConstant[SH_N] = {GI_SH_Y0, GI_SH_Y1, GI_SH_Y1, GI_SH_Y1, GI_SH_Y2_PRODUCT, GI_SH_Y2_PRODUCT,
                                     3.0f * GI_SH_Y20, GI_SH_Y2_PRODUCT, GI_SH_Y22};
#pragma unroll
  for (int ch = 0; ch < 3; ++ch) {
    floatV* cc = c + ch * SH_N;
    cc[6] -= cc[0] * (1.0f / 3.0f);  // Σ(z² − 1/3) = Σ(3z² − 1) / 3
#pragma unroll
    for (int i = 0; i < SH_N; ++i) cc[i] *= basisConstant[i] * s;
  }
  if (direct) {
    // The punctual lights themselves, per lane (scalar light and shadow-map code of common/).
    for (int li = 0; li < lightCount; ++li) {
      global const GiLight* l = &lights[li];
      float er[GI_VW], eg[GI_VW], eb[GI_VW], wx[GI_VW], wy[GI_VW], wz[GI_VW];
      float ax[GI_VW], ay[GI_VW], az[GI_VW], bx[GI_VW], by[GI_VW], bz[GI_VW];
      vstoreV(px, 0, ax); vstoreV(py, 0, ay); vstoreV(pz, 0, az);
      vstoreV(gx, 0, bx); vstoreV(gy, 0, by); vstoreV(gz, 0, bz);
      for (int lane = 0; lane < GI_VW; ++lane) {
        float3 p = (float3)(ax[lane], ay[lane], az[lane]), ng = (float3)(bx[lane], by[lane], bz[lane]);
        float3 wi;
        float dist;
        float3 e = light_incident(l, p, &wi, &dist);
        if (!(dot(ng, wi) > 0.0f) || !(e.x + e.y + e.z > 0.0f)) e = (float3)(0.0f);
        else e *= shadow_visibility(l, shadowViews, shadowOffsets, shadowDepths, p, ng);
        er[lane] = e.x; eg[lane] = e.y; eb[lane] = e.z;
        wx[lane] = wi.x; wy[lane] = wi.y; wz[lane] = wi.z;
      }
      floatV b[SH_N];
      sh9_basisV(vloadV(0, wx), vloadV(0, wy), vloadV(0, wz), b);
      floatV vr = vloadV(0, er), vg = vloadV(0, eg), vb = vloadV(0, eb);
#pragma unroll
      for (int i = 0; i < SH_N; ++i) {
        c[i] += vr * b[i];
        c[SH_N + i] += vg * b[i];
        c[2 * SH_N + i] += vb * b[i];
      }
    }
  }
  // Whole vectors also past the row's end: those lanes land in the pitch's margin, with the
  // invalid id (the filter rejects them) and finite values.
  global float* o = planes + pad + (size_t)y * SH_PLANES * pitch + x0;
#pragma unroll
  for (int k = 0; k < SH_C; ++k) sh_store_stream(c[k], o + (size_t)k * pitch);
  sh_store_stream(GI_SEL(zero, z, inside), o + (size_t)SH_DEPTH * pitch);
  sh_store_stream(GI_SEL(zero, nx, inside), o + (size_t)SH_NORMAL * pitch);
  sh_store_stream(GI_SEL(zero, ny, inside), o + (size_t)(SH_NORMAL + 1) * pitch);
  sh_store_stream(GI_SEL(zero, nz, inside), o + (size_t)(SH_NORMAL + 2) * pitch);
  sh_store_stream(as_floatV(id), o + (size_t)SH_ID * pitch);
  sh_stream_fence();
}

#ifndef GI_FX
#define GI_FX 4
#endif
#ifndef GI_FY
#define GI_FY 4
#endif
// Output rows per work-item of both filters: the row sums (box) or the row pass (separable) of
// the SH_FILTER_ROWS + GI_FY − 1 rows their windows cover are kept in private memory (19 KB at 16
// lanes and GI_FY = 4; with 16 rows the 33 KB no longer fit L1 and it was slower).
#define SH_FILTER_ROWS 8  // host: kShIgiFilterRows

// Software prefetch on x86 CPU devices (a no-op elsewhere; never faults, so addresses past a
// buffer are harmless). The filters read 27 coefficient lines and 5 key lines per plane row and
// 4 G-buffer streams in each of their rows: far more streams than the hardware prefetchers follow,
// so without it the first touch of every line waited for memory (box filter −18 %, separable
// −32 % CPU time with it, docs/PERFORMANCE.md, sh-igi, "Eighth round"). Into L2 (prefetcht1):
// −10 % more for the box filter than into L1, whose few fill buffers the prefetches then held.
inline __attribute__((always_inline)) void sh_prefetch(global const float* p) {
#if defined(GI_DEVICE_CPU) && (defined(__x86_64__) || defined(__i386__))
  __builtin_prefetch((const void*)(size_t)p, 0, 2);
#endif
}

// The planes of a row block, SH_PREFETCH_AHEAD floats right of a work-item's first pixel: the line
// the work-item two further along the row reads first (2·GI_VW + 16 measured 3 % better than 32 at
// 16 lanes; 32 at 8).
#define SH_PREFETCH_AHEAD (2 * GI_VW + 16)
inline __attribute__((always_inline)) void sh_prefetch_block(global const float* base, int pitch) {
#pragma unroll
  for (int k = 0; k < SH_PLANES; ++k) sh_prefetch(base + (size_t)k * pitch + SH_PREFETCH_AHEAD);
}

// The three G-buffer runs (float4 per pixel) that sh_shading reads for GI_VW pixels from (x0, y).
inline __attribute__((always_inline)) void sh_prefetch_gbuffer(int width, int x0, int y, global const float* gNormal,
                                                               global const float* gAlbedo, global const float* gSpecular) {
  size_t at = 4 * ((size_t)y * width + x0);
  for (int i = 0; i < 4 * GI_VW; i += 16) {
    sh_prefetch(gNormal + at + i);
    sh_prefetch(gAlbedo + at + i);
    sh_prefetch(gSpecular + at + i);
  }
}

// The filters' helpers are always inlined: PoCL left sh_shading a call (its ShShading through
// memory), ≈ 30 % of the filters' CPU time in a symbol of its own.
// The filter's keys of GI_VW consecutive pixels: `q` is plane 0 of their row block at their first pixel.
typedef struct {
  floatV z, tz, nx, ny, nz;
  uintV id;
} ShKeys;

inline __attribute__((always_inline)) ShKeys sh_keys(global const float* q, int pitch, float tauZ) {
  ShKeys k;
  k.z = vloadV(0, q + (size_t)SH_DEPTH * pitch);
  k.nx = vloadV(0, q + (size_t)SH_NORMAL * pitch);
  k.ny = vloadV(0, q + (size_t)(SH_NORMAL + 1) * pitch);
  k.nz = vloadV(0, q + (size_t)(SH_NORMAL + 2) * pitch);
  k.id = vloadV(0, (global const uint*)(q + (size_t)SH_ID * pitch));
  k.tz = tauZ * k.z;
  return k;
}

// Weight 1 or 0 of neighbours q (plane 0 of their row block at their first pixel; columns qx) for
// pixels with keys c: the §3 test — inside the image, a surface, |Δz| ≤ τ_z·z, geometric normals
// within τ_n, and, when asked, the same instance id.
inline __attribute__((always_inline)) floatV sh_weight(global const float* q, int pitch, ShKeys c, intV qx, int width, float cosTauN,
                        int sameInstance) {
  uintV qid = vloadV(0, (global const uint*)(q + (size_t)SH_ID * pitch));
  floatV dz = fabs(vloadV(0, q + (size_t)SH_DEPTH * pitch) - c.z);
  floatV dn = vloadV(0, q + (size_t)SH_NORMAL * pitch) * c.nx + vloadV(0, q + (size_t)(SH_NORMAL + 1) * pitch) * c.ny +
              vloadV(0, q + (size_t)(SH_NORMAL + 2) * pitch) * c.nz;
#if GI_VW == 1
  return (qx >= 0 && qx < width && qid != GI_INVALID_ID && dz <= c.tz && dn >= cosTauN &&
          (sameInstance == 0 || qid == c.id)) ? 1.0f : 0.0f;
#else
  intV ok = (qx >= 0) & (qx < width) & (qid != GI_INVALID_ID) & (dz <= c.tz) & (dn >= cosTauN) &
            ((intV)(sameInstance == 0 ? -1 : 0) | (qid == c.id));
  return select((floatV)(0.0f), (floatV)(1.0f), ok);
#endif
}

// What the shading of GI_VW pixels of row y from x0 needs besides the filtered coefficients: the
// zonal weights of each coefficient (Lambert at the shading normal, Phong lobe at r), albedo, F0
// and which lanes are surface pixels (lanes past the image repeat the row's last pixel).
typedef struct {
  floatV tn[SH_N], tr[SH_N];
  float3V alb, f0;
  intV surface;
} ShShading;

#define SH_BAND(k) ((k) == 0 ? 0 : (k) < 4 ? 1 : 2)

inline __attribute__((always_inline)) void sh_shading(int width, int x0, int y, uintV id, global const float* gNormal,
                       global const float* gAlbedo, global const float* gSpecular, GiView camera, int glossy,
                       ShShading* s) {
  intV x = x0 + GI_LANES;
  intV inside = x < width;
  size_t row = (size_t)y * width;
  float3V nrm;
  floatV unused, roughness;
  if (x0 + GI_VW <= width) {
    GI_AOS4_LOAD(gNormal + 4 * (row + x0), nrm.x, nrm.y, nrm.z, unused)
    GI_AOS4_LOAD(gAlbedo + 4 * (row + x0), s->alb.x, s->alb.y, s->alb.z, unused)
    GI_AOS4_LOAD(gSpecular + 4 * (row + x0), s->f0.x, s->f0.y, s->f0.z, roughness)
  } else {
    intV i = (int)row + min(x, (intV)(width - 1));
    GI_GATHER_AOS4(float, gNormal, i, nrm.x, nrm.y, nrm.z, unused)
    GI_GATHER_AOS4(float, gAlbedo, i, s->alb.x, s->alb.y, s->alb.z, unused)
    GI_GATHER_AOS4(float, gSpecular, i, s->f0.x, s->f0.y, s->f0.z, roughness)
  }
  s->surface = (id != GI_INVALID_ID) & inside;
  sh9_basisV(nrm.x, nrm.y, nrm.z, s->tn);
  const float lambert[3] = {GI_SH_COSCONV0, GI_SH_COSCONV1, GI_SH_COSCONV2};
#pragma unroll
  for (int k = 0; k < SH_N; ++k) s->tn[k] = lambert[SH_BAND(k)] * s->tn[k];
  if (glossy) {
    float3V wo;
    if (camera.orthographic) {
      float3 v = -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz);
      wo = f3v((floatV)(v.x), (floatV)(v.y), (floatV)(v.z));
    } else {
      // The G-buffer's position is eye + t·d on the ray through the pixel centre (raster/gbuffer.cl),
      // so the view vector is −d: from the camera, without reading the position run.
      floatV ndcX = (convert_floatV(x) + 0.5f) / (float)camera.width * 2.0f - 1.0f;
      float ndcY = 1.0f - ((float)y + 0.5f) / (float)camera.height * 2.0f;
      const float* M = camera.inv_view_proj;
#define SH_UNPROJECT(r, zs) (M[r] * ndcX + (M[4 + r] * ndcY + M[8 + r] * (zs) + M[12 + r]))
      floatV invNear = 1.0f / SH_UNPROJECT(3, -1.0f), invFar = 1.0f / SH_UNPROJECT(3, 1.0f);
      float3V d = f3v(SH_UNPROJECT(0, 1.0f) * invFar - SH_UNPROJECT(0, -1.0f) * invNear,
                      SH_UNPROJECT(1, 1.0f) * invFar - SH_UNPROJECT(1, -1.0f) * invNear,
                      SH_UNPROJECT(2, 1.0f) * invFar - SH_UNPROJECT(2, -1.0f) * invNear);
#undef SH_UNPROJECT
      wo = safe_normalizeV(f3v(-d.x, -d.y, -d.z), nrm);
    }
    floatV nv = dotV(nrm, wo);
    float3V rv = f3v(2.0f * nv * nrm.x - wo.x, 2.0f * nv * nrm.y - wo.y, 2.0f * nv * nrm.z - wo.z);
    floatV alpha = fmax(roughness * roughness, 1e-4f);
    floatV sp = clamp(2.0f / (alpha * alpha) - 2.0f, 0.0f, 1e4f);
    floatV g1 = (sp + 1.0f) / (sp + 2.0f), g2 = sp / (sp + 3.0f);
    sh9_basisV(rv.x, rv.y, rv.z, s->tr);
#pragma unroll
    for (int k = 1; k < SH_N; ++k) s->tr[k] *= SH_BAND(k) == 1 ? g1 : g2;
  } else {
#pragma unroll
    for (int k = 0; k < SH_N; ++k) s->tr[k] = (floatV)(0.0f);
  }
}

// The zonal sums of one channel's 9 filtered (not yet renormalised) coefficients.
inline __attribute__((always_inline)) void sh_fold(const ShShading* s, const floatV* acc, floatV* diffuse, floatV* specular) {
  floatV e = (floatV)(0.0f), sp = (floatV)(0.0f);
#pragma unroll
  for (int k = 0; k < SH_N; ++k) {
    e += s->tn[k] * acc[k];
    sp += s->tr[k] * acc[k];
  }
  *diffuse = e;
  *specular = sp;
}

// L = ρ/π · max(0, inv · diffuse) + F0 · max(0, inv · specular) per channel, written to camera order.
inline __attribute__((always_inline)) void sh_write(const ShShading* s, const floatV* diffuse, const floatV* specular, floatV inv, int glossy,
                     int width, int x0, int y, global float* out) {
  floatV zero = (floatV)(0.0f);
  floatV res[3];
#pragma unroll
  for (int ch = 0; ch < 3; ++ch) {
    floatV a = ch == 0 ? s->alb.x : ch == 1 ? s->alb.y : s->alb.z, f = ch == 0 ? s->f0.x : ch == 1 ? s->f0.y : s->f0.z;
    floatV L = a * GI_INV_PI * fmax(diffuse[ch] * inv, 0.0f);
    if (glossy) L += f * fmax(specular[ch] * inv, 0.0f);
    res[ch] = GI_SEL(zero, L, s->surface);
  }
  size_t row = (size_t)y * width;
  if (x0 + GI_VW <= width) {
    GI_AOS4_STORE(out + 4 * (row + x0), res[0], res[1], res[2], zero)
  } else {
    float t[4 * GI_VW];
    GI_AOS4_STORE(t, res[0], res[1], res[2], zero)
    for (int l = 0; x0 + l < width; ++l) vstore4(vload4(l, t), row + x0 + l, out);
  }
}

// Box filter + shade (`sh-igi.filter=box`). A work-item takes GI_VW pixels of SH_FILTER_ROWS rows.
// Window offset (dx, dy) of its pixels is one (unaligned) vector load per plane at a fixed
// offset from their first pixel. The weights (§3 test, dy outer, dx inner: the host mirror's
// order) come first; then, per window row, a row whose GI_FX offsets every lane accepts adds the
// row's plain sum of the GI_FX columns — computed once per work-item for every row its windows
// cover, shared by the GI_FY output rows that read it — and any other row adds its accepted
// offsets one by one (a row no lane accepts adds nothing). The same box, in a different summation
// order for the clean rows (a rounding difference); GI_FY row sums instead of GI_FX · GI_FY
// offsets where no test rejects. Channel by channel, 9 accumulators live, folded into the zonal
// shading sums.
kernel void sh_igi_filter_shade(int width, int height, int pitch, int pad, global const float* planes,
                                global const float* gNormal,
                                global const float* gAlbedo, global const float* gSpecular, GiView camera,
                                float tauZ, float cosTauN, int sameInstance, int glossy, global float* out) {
  int columns = (width + GI_VW - 1) / GI_VW, id = get_global_id(0);
  int y0 = id / columns * SH_FILTER_ROWS, x0 = (id - id / columns * columns) * GI_VW;
  if (y0 >= height) return;
  intV x = x0 + GI_LANES;
  size_t blockSize = (size_t)SH_PLANES * pitch;
  float rowSum[SH_FILTER_ROWS + GI_FY - 1][SH_C][GI_VW];
  // 1, but not a constant LLVM can see: with plain adds of the overlapping unaligned loads it built
  // a sliding-window sum out of 64-bit pieces (vmovsd + vaddps xmm), half of the kernel's time;
  // fma(1, v, s) is v + s exactly and keeps whole-vector loads (box filter −28 % CPU time).
  floatV unit = (floatV)(pitch > 0 ? 1.0f : 0.0f);
  for (int r = 0; r < SH_FILTER_ROWS + GI_FY - 1; ++r) {
    int qy = y0 - GI_FY / 2 + r;
    if (qy < 0 || qy >= height) continue;  // never read: no lane accepts a row outside the image
    global const float* base = planes + pad + (size_t)qy * blockSize + x0;
    sh_prefetch_block(base, pitch);
#pragma unroll
    for (int k = 0; k < SH_C; ++k) {
      global const float* plane = base + (size_t)k * pitch;
      floatV sum = vloadV(0, plane - GI_FX / 2);
#pragma unroll
      for (int dx = 1 - GI_FX / 2; dx < GI_FX - GI_FX / 2; ++dx) sum = fma(unit, vloadV(0, plane + dx), sum);
      vstoreV(sum, 0, rowSum[r][k]);
    }
  }
  for (int r = 0; r < SH_FILTER_ROWS; ++r) {
    int y = y0 + r;
    if (y >= height) break;
    global const float* base = planes + pad + (size_t)y * blockSize + x0;
    ShKeys c = sh_keys(base, pitch, tauZ);
    // what the next row (after the last: the next work-item's first) will shade
    sh_prefetch_gbuffer(width, r + 1 < SH_FILTER_ROWS ? x0 : x0 + GI_VW, r + 1 < SH_FILTER_ROWS ? y + 1 : y0,
                        gNormal, gAlbedo, gSpecular);
    floatV w[GI_FX * GI_FY];
    long off[GI_FX * GI_FY];  // window offset q relative to the work-item's first pixel in row y, in floats
    bool clean[GI_FY], empty[GI_FY];  // window row dy: every lane accepts every offset / none accepts any
    floatV ws = (floatV)(0.0f);
#pragma unroll
    for (int dy = -(GI_FY / 2); dy < GI_FY - GI_FY / 2; ++dy) {
      int j = dy + GI_FY / 2;
      bool rowInside = y + dy >= 0 && y + dy < height;
      floatV rowWeight = (floatV)(0.0f), rowAll = (floatV)(1.0f);
#pragma unroll
      for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) {
        int q = j * GI_FX + dx + GI_FX / 2;
        off[q] = (long)dy * (long)blockSize + dx;
        w[q] = rowInside ? sh_weight(base + off[q], pitch, c, x + dx, width, cosTauN, sameInstance) : (floatV)(0.0f);
        ws += w[q];
        rowWeight += w[q];
        rowAll = fmin(rowAll, w[q]);
      }
      clean[j] = GI_ALL(rowAll > 0.0f);
      empty[j] = !GI_ANY(rowWeight > 0.0f);
    }
    // The centre pixel always passes its own test unless it is background; ws = 0 only there.
    floatV inv = GI_SEL((floatV)(0.0f), 1.0f / ws, ws > 0.0f);
    ShShading s;
    sh_shading(width, x0, y, c.id, gNormal, gAlbedo, gSpecular, camera, glossy, &s);
    floatV diffuse[3], specular[3];
    for (int ch = 0; ch < 3; ++ch) {
      global const float* channel = base + (size_t)ch * SH_N * pitch;
      floatV acc[SH_N];
#pragma unroll
      for (int k = 0; k < SH_N; ++k) acc[k] = (floatV)(0.0f);
#pragma unroll
      for (int j = 0; j < GI_FY; ++j) {
        if (clean[j]) {
#pragma unroll
          for (int k = 0; k < SH_N; ++k) acc[k] += vloadV(0, rowSum[r + j][ch * SH_N + k]);
        } else if (!empty[j]) {
#pragma unroll
          for (int i = 0; i < GI_FX; ++i) {
            int q = j * GI_FX + i;
            floatV wq = w[q];
            global const float* src = channel + off[q];
#pragma unroll
            for (int k = 0; k < SH_N; ++k) acc[k] += wq * vloadV(0, src + (size_t)k * pitch);
          }
        }
      }
      sh_fold(&s, acc, &diffuse[ch], &specular[ch]);
    }
    sh_write(&s, diffuse, specular, inv, glossy, width, x0, y, out);
  }
}

// Separable filter + shade (`sh-igi.filter=separable`, the thesis's separable blur as for igi):
// a GI_FX × 1 pass, then a 1 × GI_FY pass over its result, each renormalised by its own accepted
// weights and testing against its own centre pixel. Without discontinuities it is the box (the
// same mean, up to rounding); at discontinuities a pixel can receive light through an
// intermediate that passed both tests (a path the 2D window would reject). GI_FX + GI_FY taps
// instead of GI_FX · GI_FY. A work-item takes GI_VW pixels of SH_FILTER_ROWS rows: the row pass
// covers the SH_FILTER_ROWS + GI_FY − 1 rows its column passes read and keeps them in private
// memory.
kernel void sh_igi_filter_shade_separable(int width, int height, int pitch, int pad, global const float* planes,
                                          global const float* gNormal,
                                          global const float* gAlbedo, global const float* gSpecular,
                                          GiView camera, float tauZ, float cosTauN, int sameInstance, int glossy,
                                          global float* out) {
  int columns = (width + GI_VW - 1) / GI_VW, id = get_global_id(0);
  int y0 = id / columns * SH_FILTER_ROWS, x0 = (id - id / columns * columns) * GI_VW;
  if (y0 >= height) return;
  intV x = x0 + GI_LANES;
  size_t blockSize = (size_t)SH_PLANES * pitch;
  float rowPass[SH_FILTER_ROWS + GI_FY - 1][SH_C][GI_VW];
  for (int r = 0; r < SH_FILTER_ROWS + GI_FY - 1; ++r) {
    int qy = y0 - GI_FY / 2 + r;
    if (qy < 0 || qy >= height) {  // zeros: the column pass gives these rows weight 0
#pragma unroll
      for (int k = 0; k < SH_C; ++k) vstoreV((floatV)(0.0f), 0, rowPass[r][k]);
      continue;
    }
    global const float* base = planes + pad + (size_t)qy * blockSize + x0;
    // sh_prefetch_block written out: through the helper LLVM allocated this kernel's registers
    // differently and it took 1.2× the CPU time (8 lanes, AVX-512; the box filter is indifferent).
#pragma unroll
    for (int k = 0; k < SH_PLANES; ++k) sh_prefetch(base + (size_t)k * pitch + SH_PREFETCH_AHEAD);
    ShKeys c = sh_keys(base, pitch, tauZ);
    floatV w[GI_FX];
    floatV ws = (floatV)(0.0f);
#pragma unroll
    for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) {
      w[dx + GI_FX / 2] = sh_weight(base + dx, pitch, c, x + dx, width, cosTauN, sameInstance);
      ws += w[dx + GI_FX / 2];
    }
    floatV inv = GI_SEL((floatV)(0.0f), 1.0f / ws, ws > 0.0f);  // 0 only where no surface
#pragma unroll
    for (int k = 0; k < SH_C; ++k) {
      global const float* plane = base + (size_t)k * pitch;
      floatV sum = (floatV)(0.0f);
#pragma unroll
      for (int dx = -(GI_FX / 2); dx < GI_FX - GI_FX / 2; ++dx) sum += w[dx + GI_FX / 2] * vloadV(0, plane + dx);
      vstoreV(sum * inv, 0, rowPass[r][k]);
    }
  }
  for (int r = 0; r < SH_FILTER_ROWS; ++r) {
    int y = y0 + r;
    if (y >= height) break;
    global const float* base = planes + pad + (size_t)y * blockSize + x0;
    ShKeys c = sh_keys(base, pitch, tauZ);
    // what the next row (after the last: the next work-item's first) will shade
    sh_prefetch_gbuffer(width, r + 1 < SH_FILTER_ROWS ? x0 : x0 + GI_VW, r + 1 < SH_FILTER_ROWS ? y + 1 : y0,
                        gNormal, gAlbedo, gSpecular);
    floatV w[GI_FY];
    floatV ws = (floatV)(0.0f);
#pragma unroll
    for (int dy = -(GI_FY / 2); dy < GI_FY - GI_FY / 2; ++dy) {
      bool rowInside = y + dy >= 0 && y + dy < height;
      w[dy + GI_FY / 2] = rowInside ? sh_weight(base + (long)dy * (long)blockSize, pitch, c, x, width, cosTauN,
                                                sameInstance)
                                    : (floatV)(0.0f);
      ws += w[dy + GI_FY / 2];
    }
    floatV inv = GI_SEL((floatV)(0.0f), 1.0f / ws, ws > 0.0f);
    ShShading s;
    sh_shading(width, x0, y, c.id, gNormal, gAlbedo, gSpecular, camera, glossy, &s);
    floatV diffuse[3], specular[3];
    for (int ch = 0; ch < 3; ++ch) {
      floatV acc[SH_N];
#pragma unroll
      for (int k = 0; k < SH_N; ++k) acc[k] = (floatV)(0.0f);
#pragma unroll
      for (int dy = 0; dy < GI_FY; ++dy) {
        floatV wq = w[dy];
#pragma unroll
        for (int k = 0; k < SH_N; ++k) acc[k] += wq * vloadV(0, rowPass[r + dy][ch * SH_N + k]);
      }
      sh_fold(&s, acc, &diffuse[ch], &specular[ch]);
    }
    sh_write(&s, diffuse, specular, inv, glossy, width, x0, y, out);
  }
}
