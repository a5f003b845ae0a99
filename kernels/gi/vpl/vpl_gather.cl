// All-pairs VPL gathering with interleaved sampling (ALGORITHMS.md §2, §2.3). Without visibility
// (the default) every VPL lights every receiver it faces (an over-estimate in occluded regions);
// compiled with GI_VPL_VISIBILITY each pair is tested by a shadow ray (vpl_visibility.h).
//
//   gi_deinterleave   camera pixel (x, y) -> packed slot of sub-image c = (x mod n) + n·(y mod m)
//                     at (x / n, y / m): position and shading normal as six float planes (SoA).
//                     Sub-images are ⌈W/n⌉×⌈H/m⌉ pixels stored with a row pitch of subPitch slots
//                     (⌈W/n⌉ rounded up to 16); slots without a pixel get a zero normal (E = 0).
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

// The copies between camera order and sub-images: one work-item = GI_VW consecutive slots of one
// sub-image row, i.e. GI_VW pixels of camera row y = get_global_id(1) spaced n apart (class
// column cx, slots qx0 … qx0 + GI_VW − 1). The camera side is read or written with one 128-bit
// access per pixel, the sub-image side with whole aligned vectors: scattering single floats into
// n·m·6 planes (one pixel per work-item) cost 2–3 ms at 640×360 for what is a 13 MB copy.
// Dimension 0 = cx + n·segment, so a work-group's neighbouring work-items share camera cache
// lines. Lanes without a pixel (x ≥ width, y ≥ height) read a clamped pixel and are masked.
typedef struct {
  size_t slot;  // first slot of the run (aligned to 16)
  intV pixel;   // per lane: camera pixel index, clamped into the image
  intV valid;   // per lane: the slot holds a pixel
} GiSlotRun;

inline __attribute__((always_inline)) GiSlotRun gi_slot_run(int width, int height, int n, int m, int subPitch, int stride) {
  int g = get_global_id(0), y = get_global_id(1);
  int segment = g / n, cx = g - segment * n;  // one scalar division per GI_VW pixels
  int qy = y / m, cy = y - qy * m;
  int qx0 = segment * GI_VW;
  intV x = cx + n * (qx0 + GI_LANES);
  GiSlotRun r;
  r.slot = (size_t)(cx + n * cy) * stride + (size_t)qy * subPitch + qx0;
  r.pixel = min(y, height - 1) * width + min(x, (intV)(width - 1));
#if GI_VW == 1
  r.valid = x < width && y < height;
#else
  r.valid = x < width & (intV)(y < height ? -1 : 0);
#endif
  return r;
}

// Stores four floatV planes as float4 records at the valid lanes' pixels (p: float4 array as floats).
inline __attribute__((always_inline)) void gi_store_valid_aos4(global float* p, GiSlotRun r, floatV X, floatV Y, floatV Z, floatV W) {
#if GI_VW == 1
  if (r.valid) vstore4((float4)(X, Y, Z, W), r.pixel, p);
#else
  float v[4][GI_VW];
  int px[GI_VW], ok[GI_VW];
  vstoreV(X, 0, v[0]);
  vstoreV(Y, 0, v[1]);
  vstoreV(Z, 0, v[2]);
  vstoreV(W, 0, v[3]);
  vstoreV(r.pixel, 0, px);
  vstoreV(r.valid, 0, ok);
  if (GI_ALL(r.valid)) {
#pragma unroll
    for (int l = 0; l < GI_VW; ++l) vstore4((float4)(v[0][l], v[1][l], v[2][l], v[3][l]), px[l], p);
  } else {
    for (int l = 0; l < GI_VW; ++l)
      if (ok[l]) vstore4((float4)(v[0][l], v[1][l], v[2][l], v[3][l]), px[l], p);
  }
#endif
}

kernel void gi_deinterleave(int width, int height, int n, int m, int subPitch, int stride,
                            global const float* position, global const float* normal, global float* planes) {
  if (get_global_id(1) >= m * (stride / subPitch)) return;  // the launch's rounding: no sub-image row
  GiSlotRun r = gi_slot_run(width, height, n, m, subPitch, stride);
  size_t L = (size_t)n * m * stride;
  floatV px, py, pz, pw, nx, ny, nz, nw;
  GI_GATHER_AOS4(float, position, r.pixel, px, py, pz, pw)
  GI_GATHER_AOS4(float, normal, r.pixel, nx, ny, nz, nw)
  floatV zero = (floatV)(0.0f);
  intV surface = r.valid & (pw > 0.0f);  // background: zero normal, E = 0
  global float* o = planes + r.slot;
  vstoreV(GI_SEL(zero, px, r.valid), 0, o);
  vstoreV(GI_SEL(zero, py, r.valid), 0, o + L);
  vstoreV(GI_SEL(zero, pz, r.valid), 0, o + 2 * L);
  vstoreV(GI_SEL(zero, nx, surface), 0, o + 3 * L);
  vstoreV(GI_SEL(zero, ny, surface), 0, o + 4 * L);
  vstoreV(GI_SEL(zero, nz, surface), 0, o + 5 * L);
}

// Σ over VPL set `set` (k = set, set + sets, …) of Φ_p · max(0, n_p·ω) · max(0, −n·ω) / max(d², d_min²)
// / d² for the receivers (px, py, pz), (nx, ny, nz), into er, eg, eb (one macro for both gathers,
// so that their sums are the same operations in the same order).
#define GI_VPL_SET_SUM(px, py, pz, nx, ny, nz, set, sets, vpls, count, er, eg, eb)                     \
  for (int k = (set); k < (count); k += (sets)) {                                                      \
    float4 a = (vpls)[3 * k], b = (vpls)[3 * k + 1], f = (vpls)[3 * k + 2];                             \
    floatV vx = a.x - (px), vy = a.y - (py), vz = a.z - (pz); /* receiver -> VPL */                     \
    floatV d2 = vx * vx + vy * vy + vz * vz;                                                          \
    floatV cp = -(b.x * vx + b.y * vy + b.z * vz); /* n_p·(x − x_p) */                                 \
    floatV cr = (nx) * vx + (ny) * vy + (nz) * vz; /* −n·(x − x_p) */                                  \
    floatV gterm = max(cp, 0.0f) * max(cr, 0.0f) / (max(d2, 1e-20f) * max(d2, a.w));                 \
    gterm = GI_VPL_VISIBLE(px, py, pz, a.xyz, gterm);                                                 \
    er += f.x * gterm;                                                                                \
    eg += f.y * gterm;                                                                                \
    eb += f.z * gterm;                                                                                \
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
  GI_VPL_SET_SUM(px, py, pz, nx, ny, nz, set, sets, vpls, count, er, eg, eb)
  float s = (float)sets * GI_INV_PI;
  vstoreV(er * s, g, irradiance);
  vstoreV(eg * s, g, irradiance + L);
  vstoreV(eb * s, g, irradiance + 2 * L);
}

// The same gather without the copies (the `vpl` and `igi` techniques): a work-item takes the
// GI_VW receivers of one sub-image row run straight from the camera G-buffer (the pixels the
// de-interleave would have put there, gi_slot_run) and writes their camera-order result: E
// (float4, radiance == 0) or L = ρ/π · E. Same operations as de-interleave + vpl_gather +
// re-interleave, without writing and re-reading 36 bytes per pixel of sub-image planes.
kernel void vpl_gather_camera(int width, int height, int n, int m, int subPitch, int stride,
                              global const float* position, global const float* normal, global const float4* vpls,
                              int count, int radiance, global const float* albedo,
                              global float* out GI_VPL_VISIBILITY_PARAMS) {
  GI_VPL_VISIBILITY_BEGIN
  if (get_global_id(1) >= m * (stride / subPitch)) return;
  GiSlotRun r = gi_slot_run(width, height, n, m, subPitch, stride);
  int sets = n * m, set = (int)(r.slot / (size_t)stride);
  floatV px, py, pz, pw, nx, ny, nz, nw;
  GI_GATHER_AOS4(float, position, r.pixel, px, py, pz, pw)
  GI_GATHER_AOS4(float, normal, r.pixel, nx, ny, nz, nw)
  floatV zero = (floatV)(0.0f);
  intV surface = r.valid & (pw > 0.0f);  // background and empty lanes: zero normal, E = 0
  nx = GI_SEL(zero, nx, surface);
  ny = GI_SEL(zero, ny, surface);
  nz = GI_SEL(zero, nz, surface);
  floatV er = zero, eg = zero, eb = zero;
  GI_VPL_SET_SUM(px, py, pz, nx, ny, nz, set, sets, vpls, count, er, eg, eb)
  float s = (float)sets * GI_INV_PI;
  er *= s;
  eg *= s;
  eb *= s;
  if (radiance) {
    floatV ar, ag, ab, aw;
    GI_GATHER_AOS4(float, albedo, r.pixel, ar, ag, ab, aw)
    er = ar * (er * GI_INV_PI);
    eg = ag * (eg * GI_INV_PI);
    eb = ab * (eb * GI_INV_PI);
  }
  gi_store_valid_aos4(out, r, er, eg, eb, zero);
}

kernel void gi_reinterleave_radiance(int width, int height, int n, int m, int subPitch, int stride,
                                     global const float* irradiance, global const float* albedo,
                                     global float* out) {
  if (get_global_id(1) >= m * (stride / subPitch)) return;  // the launch's rounding: no sub-image row
  GiSlotRun r = gi_slot_run(width, height, n, m, subPitch, stride);
  size_t L = (size_t)n * m * stride;
  global const float* e = irradiance + r.slot;
  floatV ar, ag, ab, aw;
  GI_GATHER_AOS4(float, albedo, r.pixel, ar, ag, ab, aw)
  floatV lr = ar * (vloadV(0, e) * GI_INV_PI), lg = ag * (vloadV(0, e + L) * GI_INV_PI),
         lb = ab * (vloadV(0, e + 2 * L) * GI_INV_PI);
  gi_store_valid_aos4(out, r, lr, lg, lb, (floatV)(0.0f));
}

kernel void gi_reinterleave_irradiance(int width, int height, int n, int m, int subPitch, int stride,
                                       global const float* irradiance, global float* out) {
  if (get_global_id(1) >= m * (stride / subPitch)) return;  // the launch's rounding: no sub-image row
  GiSlotRun r = gi_slot_run(width, height, n, m, subPitch, stride);
  size_t L = (size_t)n * m * stride;
  global const float* e = irradiance + r.slot;
  gi_store_valid_aos4(out, r, vloadV(0, e), vloadV(0, e + L), vloadV(0, e + 2 * L), (floatV)(0.0f));
}
