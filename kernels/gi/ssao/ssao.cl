// Screen-space ambient occlusion after Chapman (2011), as seed 003 §3.5.1 used it, and
// screen-space one-bounce colour bleeding (seed 003 eq. 3.5, after Ritschel et al. 2009).
// ALGORITHMS.md §6; host side and choices: src/gi/ssao/ssao_technique.cpp, docs/techniques/ssao.md.
//
// ssao_occlusion, per camera pixel with surface point P (reconstructed from the depth buffer),
// geometric normal n_g, shading normal n:
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

// Adds 1 to the integer lanes of `count` where `mask` holds. A select, not `count -= mask` (a vector
// comparison's true is −1): the subtraction compiles to an add of the mask's zero-extension, which
// Oclgrind 21.10 evaluates to 255 per lane (GI_NOT in common/vector_width.h).
#define SSAO_COUNT(count, mask) (count) = GI_SEL(count, (count) + 1, mask)

#ifndef GI_SSAO_SAMPLES
#define GI_SSAO_SAMPLES 16
#endif
// Occlusion evaluated on every GI_SSAO_DOWN-th camera pixel in x and y (1 or 2; see ssao_depth_planes).
#ifndef GI_SSAO_DOWN
#define GI_SSAO_DOWN 1
#endif
// 1: ssao_occlusion also sums the eq. 3.5 bleeding irradiance. A build option rather than an
// argument: without it the sample loop carries no bleeding state (registers the AVX-512 build
// otherwise spills; ≈ 10 % of the occlusion's CPU time).
#ifndef GI_SSAO_BLEEDING
#define GI_SSAO_BLEEDING 0
#endif

// How (PERFORMANCE_FACTS.md): one work-item handles GI_VW adjacent pixels of a row as lanes of
// floatV (16 on CPU devices, 1 on GPUs); every per-pixel branch of the formulas above is a lane
// mask, the sample loop has a constant trip count and is unrolled, and the surfaces seen at the
// projected samples are gathered — one 4-byte depth-plane record each (ssao_depth_planes), in
// camera space, so that a sample costs one division to project and one 32-bit hardware gather on
// AVX2/AVX-512 (SSAO_GATHER_RECORDS), and the 0.9 MB of records at 640×360 stay in a 1 MB L2 cache
// (8-byte records took 1.7× the CPU time on the 2-core EPYC, docs/PERFORMANCE.md). A group cut by
// the right image border reads its last pixel repeatedly and stores only its valid lanes.

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
  intV idx = min((intV)(GI_LANES), (intV)(valid - 1));
  return GI_GATHER(floatV, plane + i, idx);
}

inline void ssao_store1(global float* plane, int i, int valid, floatV v) { GI_STORE_LANES(float, v, plane, i, valid) }

// Camera space here: c = (x_view, y_view, depth) with depth = −z_view (the G-buffer's linear view
// depth); a point projects to the pixel coordinates sx = cx + fx·c.x/c.z, sy = cy − fy·c.y/c.z
// (`projection` = (fx, fy, cx, cy), derived on the host from the camera's matrices).

// What the occlusion test of a sample needs about the surface seen at pixel q, in one 32-bit word
// so that a sample costs one 32-bit gather and the records of the sample window (4 bytes per
// pixel) stay in the L2 cache:
//   A = 1/depth at q's centre and (g_x, g_y), the screen-space gradient of 1/depth over the tangent
//   plane of q's surface (geometric normal n), relative to A.
// 1/depth is affine in screen coordinates over a plane (perspective-correct interpolation), so
//   1/depth of that plane at pixel coordinates s = A·(1 + g·(s − centre of q))   exactly;
// for the plane n·c = w: 1/depth(s) = n·r(s)/w with the ray r(s) = ((sx − cx)/fx, (cy − sy)/fy, 1),
// hence g = (n.x/fx, −n.y/fy)/(n·r(q)).
// Encoding (ssao_encode_record; tests/ssao_test.cpp mirrors it on the host):
//   bits 16–31: A as an unsigned float with a 5-bit exponent and 11 mantissa bits, rounded to
//     nearest (relative error ≤ 2⁻¹²), i.e. the top 16 bits of A's float bits with the exponent
//     field offset by the frame's base b = ssao_inv_depth_base(znear): the 32 exponents cover
//     depths from ≈ znear/2 to ≈ 2²⁹·znear (beyond: clamped); code 0 (the background) decodes to
//     the smallest A, a plane ≈ 2²⁹·znear away that fails every test below;
//   bits 0–15: the gradient with a shared exponent E (bits 12–15) and two 6-bit two's complement
//     mantissas m_x (bits 6–11), m_y (bits 0–5), g = m·2^(E−15): E is the smallest in 0..15 with
//     |m| ≤ 31 for both, so each component is within 2^(E−16) of the exact one, which is ≤ 1/31.5
//     of the larger component (or ≤ 2⁻¹⁶ when E = 0); |g| is clamped at 31 per pixel (a plane
//     within 1/31 px of edge-on).
// At a sample (at most ½ px from q's centre in x and y) the decoded plane's relative 1/depth is
// therefore within 2⁻¹² + 2^(E−16) of the exact plane's: along the plane's normal that is at most
// 2⁻¹² of the distance to the camera plus depth/(31.5·f) (f: focal length in pixels; a 32nd of a
// pixel's footprint), against the bias of 1 % of R.
inline int ssao_inv_depth_base(float znear) { return 224 - (as_int(znear) >> 23); }

inline uintV ssao_encode_record(floatV A, floatV gx, floatV gy, int base) {
  intV a = (as_intV(A) + 0x800) >> 12;  // A ≥ 0: rounded to 11 mantissa bits
  uintV wa = as_uintV(clamp(a - (base << 11), (intV)(0), (intV)(0xffff)));
  floatV M = fmax(fabs(gx), fabs(gy));
  intV E = clamp((as_intV(M) >> 23) - 116, (intV)(0), (intV)(15));  // M·2^(15−E) in [16, 32) unless clamped
  floatV up = as_floatV((142 - E) << 23);                              // 2^(15−E), exact
  E = GI_SEL(E, E + 1, (M * up >= 31.5f) & (E < 15));                 // rounding would reach 32
  floatV scale = as_floatV((142 - E) << 23);
  intV mx = clamp(convert_intV(rint(gx * scale)), (intV)(-31), (intV)(31));
  intV my = clamp(convert_intV(rint(gy * scale)), (intV)(-31), (intV)(31));
  return (wa << 16) | as_uintV(E << 12) | as_uintV((mx & 63) << 6) | as_uintV(my & 63);
}

// GI_SSAO_DOWN = 2 (`ssao.downsample=2`): the occlusion is evaluated on a half-resolution grid,
// grid pixel (u, v) standing for camera pixel (2u, 2v); the records are then per grid pixel (the
// plane of the surface seen at that camera pixel, gradients still per camera pixel), and this pass
// also copies the grid pixels' depth and geometric normal into gridDepth and gridNormal so that the
// occlusion reads them contiguously, and for the blur's contiguous row loads the plane as three
// floats: 1/depth A and A·(g_x, g_y), in full precision (the records are rounded).
// With GI_SSAO_DOWN = 1 the grid is the camera image and the grid* planes are not written.
kernel void ssao_depth_planes(int gridWidth, int gridHeight, int width, GiView camera, float4 projection,
                              global const float* depth, global const float4* geoNormal, global uint* records,
                              global float* gridDepth, global float4* gridNormal, global float* gridInvDepth,
                              global float* gridSlopeX, global float* gridSlopeY) {
  int px0 = get_global_id(0) * GI_VW, y = get_global_id(1);
  if (px0 >= gridWidth || y >= gridHeight) return;
  int i0 = y * gridWidth + px0, valid = min(GI_VW, gridWidth - px0);
  float tmp[4 * GI_VW];
  floatV z, wx, wy, wz, unused;
#if GI_SSAO_DOWN == 1
  z = ssao_load1(depth, i0, valid);
  SSAO_LOAD4(geoNormal, i0, valid, wx, wy, wz, unused)
#else
  // Camera pixels (D·u, D·v) of the lanes (the last valid one repeated): gathered.
  intV src = (GI_SSAO_DOWN * y) * width + GI_SSAO_DOWN * min(px0 + GI_LANES, (intV)(gridWidth - 1));
  z = GI_GATHER(floatV, depth, src);
  GI_GATHER_AOS4(float, (global const float*)geoNormal, src, wx, wy, wz, unused)
  ssao_store1(gridDepth, i0, valid, z);
  SSAO_STORE4(gridNormal, i0, valid, wx, wy, wz, unused)
#endif
  const float* V = camera.view;
  floatV nx = V[0] * wx + V[4] * wy + V[8] * wz, ny = V[1] * wx + V[5] * wy + V[9] * wz;
  floatV nz = -(V[2] * wx + V[6] * wy + V[10] * wz);
  const float fx = projection.x, fy = projection.y;
  floatV rx = (GI_SSAO_DOWN * convert_floatV(px0 + GI_LANES) + (0.5f - projection.z)) * (1.0f / fx);
  float ry = (projection.w - (float)(GI_SSAO_DOWN * y) - 0.5f) * (1.0f / fy);
  floatV nr = nx * rx + ny * ry + nz;
  nr = copysign(fmax(fabs(nr), 1e-12f), nr);  // a plane seen edge-on: clamped gradients
  floatV inr = 1.0f / nr;
  floatV gx = nx * inr * (1.0f / fx), gy = -ny * inr * (1.0f / fy);
  intV surface = isfinite(z);
  floatV A = GI_SEL((floatV)(0.0f), 1.0f / z, surface);
  uintV w = GI_SEL((uintV)(0u), ssao_encode_record(A, gx, gy, ssao_inv_depth_base(camera.znear)), surface);
#if GI_SSAO_DOWN != 1
  floatV zero = (floatV)(0.0f);
  ssao_store1(gridInvDepth, i0, valid, A);
  ssao_store1(gridSlopeX, i0, valid, GI_SEL(zero, A * gx, surface));
  ssao_store1(gridSlopeY, i0, valid, GI_SEL(zero, A * gy, surface));
#endif
  GI_STORE_LANES(uint, w, records, i0, valid)
}

// The records at the lanes' indices q, with the CPU's 32-bit-index hardware gather where it has
// one. The builtins take a flat pointer: x86 OpenCL CPU devices have one address space (only they
// define __AVX512F__ / __AVX2__).
// - AVX-512 (GI_VW 16): one vpgatherdd. GI_GATHER compiles to two vpgatherqd on 64-bit indices
//   (each index sign-extended, the halves split and joined); the one gather took 5–11 % less CPU
//   time of planes + occlusion on the 2-core AMD EPYC with AVX-512 (docs/PERFORMANCE.md).
// - AVX2 without AVX-512 (GI_VW 8 there, or 16 when forced): one vpgatherdd per 8 lanes. GI_GATHER
//   compiles to a load and an element insert per lane there; the gathers took 4–14 % less CPU time
//   (median of 50 calls) of planes + occlusion on the 2-core AMD EPYC with AVX2 (docs/PERFORMANCE.md, "On the AVX2
//   machine of 3 Dec").
#if defined(__has_builtin) && GI_VW == 16 && defined(__AVX512F__)
#if __has_builtin(__builtin_ia32_gathersiv16si)
#define SSAO_GATHER_RECORDS(records, q) \
  as_uint16(__builtin_ia32_gathersiv16si((int16)(0), (const void*)(size_t)(records), (q), (ushort)0xffff, 4))
#endif
#elif defined(__has_builtin) && (GI_VW == 8 || GI_VW == 16) && defined(__AVX2__)
#if __has_builtin(__builtin_ia32_gatherd_d256)
#define SSAO_GATHER8_AVX2(records, q8) \
  __builtin_ia32_gatherd_d256((int8)(0), (const int*)(size_t)(records), (q8), (int8)(-1), 4)
#if GI_VW == 16
#define SSAO_GATHER_RECORDS(records, q) \
  as_uint16((int16)(SSAO_GATHER8_AVX2(records, (q).lo), SSAO_GATHER8_AVX2(records, (q).hi)))
#else
#define SSAO_GATHER_RECORDS(records, q) as_uint8(SSAO_GATHER8_AVX2(records, q))
#endif
#endif
#endif
#ifndef SSAO_GATHER_RECORDS
#define SSAO_GATHER_RECORDS(records, q) GI_GATHER(uintV, records, q)
#endif

// t + 1 clamped to [0, n + 1], NaN -> 0, as two selects that compile to one vmaxps and one vminps
// each (fmin/fmax with their NaN rules took three instructions each).
inline floatV ssao_clamp_index(floatV t, float n) {
  floatV u = t + 1.0f;
  u = GI_SEL((floatV)(0.0f), u, u > 0.0f);
  return GI_SEL((floatV)(n + 1.0f), u, u < n + 1.0f);
}

// kernelVectors: GI_SSAO_SAMPLES float4 (tangent-space x, y, z along n_g, already scaled by the
// length factor lerp(0.1, 1, (i/N)²)); rotations: 16 float2 (cos, sin) for the 4×4 noise tile;
// records: ssao_depth_planes(). position, normal and direct are read only with GI_SSAO_BLEEDING.
// The grid (gridWidth × gridHeight) is the camera image or, with GI_SSAO_DOWN = 2, the
// half-resolution grid of ssao_depth_planes (depth, geoNormal and records per grid pixel; position,
// normal and direct stay camera images of the given width). Outputs per grid pixel; irradianceOut
// only with GI_SSAO_BLEEDING (left as it was otherwise).
kernel void ssao_occlusion(int gridWidth, int gridHeight, int width, GiView camera, float4 projection,
                           global const float* depth, global const float4* geoNormal, global const uint* records,
                           constant float4* kernelVectors, constant float2* rotations, float radius, float bias,
                           global const float4* position, global const float4* normal,
                           global const float4* direct, global float* occlusionOut, global float4* irradianceOut) {
  int px0 = get_global_id(0) * GI_VW, y = get_global_id(1);
  if (px0 >= gridWidth || y >= gridHeight) return;
  int i0 = y * gridWidth + px0, valid = min(GI_VW, gridWidth - px0);
  float tmp[4 * GI_VW];
  const float fx = projection.x, fy = projection.y, cx = projection.z, cy = projection.w;
  floatV zP = ssao_load1(depth, i0, valid);
  intV surface = isfinite(zP);
  zP = GI_SEL((floatV)(0.0f), zP, surface);  // background lanes: finite arithmetic, masked below
  // The geometric normal in camera space.
  floatV wx, wy, wz, unused;
  SSAO_LOAD4(geoNormal, i0, valid, wx, wy, wz, unused)
  const float* V = camera.view;
  floatV gx = V[0] * wx + V[4] * wy + V[8] * wz, gy = V[1] * wx + V[5] * wy + V[9] * wz;
  floatV gz = -(V[2] * wx + V[6] * wy + V[10] * wz);
  // orthonormal_basis() (Duff et al. 2017) lane-wise, rotated by the pixel's entry of the 4×4 tile.
  floatV s = GI_SEL((floatV)(-1.0f), (floatV)(1.0f), gz >= 0.0f);
  floatV a = -1.0f / (s + gz), c = gx * gy * a;
  floatV t0x = 1.0f + s * gx * gx * a, t0y = s * c, t0z = -s * gx;
  floatV b0x = c, b0y = s + gy * gy * a, b0z = -gy;
  intV r = ((y & 3) * 4 + ((px0 + GI_LANES) & 3)) * 2;
  constant float* rf = (constant float*)rotations;
  floatV rc = GI_GATHER(floatV, rf, r), rs = GI_GATHER(floatV, rf, r + 1);
  // Everything below in scaled camera coordinates (x·fx, −y·fy, depth), so that a point projects
  // to s = (cx, cy) + (x', y')/depth, with the radius folded into the frame vectors.
  const float kx = fx * radius, ky = -fy * radius;
  floatV Tx = kx * (rc * t0x + rs * b0x), Ty = ky * (rc * t0y + rs * b0y), Tz = radius * (rc * t0z + rs * b0z);
  floatV Bx = kx * (rc * b0x - rs * t0x), By = ky * (rc * b0y - rs * t0y), Bz = radius * (rc * b0z - rs * t0z);
  floatV Nx = kx * gx, Ny = ky * gy, Nz = radius * gz;
  const float D = (float)GI_SSAO_DOWN;  // camera pixels per grid pixel
  floatV Px = zP * (D * convert_floatV(px0 + GI_LANES) + (0.5f - cx)), Py = zP * (D * (float)y + 0.5f - cy), Pz = zP;
  const float W = (float)gridWidth, H = (float)gridHeight;
  const uint baseBits = (uint)ssao_inv_depth_base(camera.znear) << 23;
  const float bias2 = bias * bias;
#if GI_SSAO_BLEEDING
  // Bleeding (eq. 3.5) in world space, from the G-buffer.
  floatV Pwx, Pwy, Pwz, nx, ny, nz;
#if GI_SSAO_DOWN == 1
  SSAO_LOAD4(position, i0, valid, Pwx, Pwy, Pwz, unused)
  SSAO_LOAD4(normal, i0, valid, nx, ny, nz, unused)
#else
  intV own = (GI_SSAO_DOWN * y) * width + GI_SSAO_DOWN * min(px0 + GI_LANES, (intV)(gridWidth - 1));
  GI_GATHER_AOS4(float, (global const float*)position, own, Pwx, Pwy, Pwz, unused)
  GI_GATHER_AOS4(float, (global const float*)normal, own, nx, ny, nz, unused)
#endif
  const float As = GI_PI * radius * radius / (float)GI_SSAO_SAMPLES;
  const float d2min = radius * radius / (float)GI_SSAO_SAMPLES;  // A_s/π
  global const float* pos = (global const float*)position;
  global const float* nrm = (global const float*)normal;
  global const float* dir = (global const float*)direct;
  floatV Ex = (floatV)(0.0f), Ey = (floatV)(0.0f), Ez = (floatV)(0.0f);
#endif
  intV occluded = (intV)(0);  // samples occluded
  // Unrolled by 4, not fully: the fully unrolled 16 samples kept ≈ 300 vector spills and reloads in
  // the AVX-512 build (all gathers hoisted, their results parked on the stack); by 4 planes +
  // occlusion take ≈ 17 % less CPU time (by 2 and by 8 more than by 4; docs/PERFORMANCE.md).
#pragma unroll 4
  for (int i = 0; i < GI_SSAO_SAMPLES; ++i) {
    float4 k = kernelVectors[i];
    floatV Sx = Px + k.x * Tx + k.y * Bx + k.z * Nx;
    floatV Sy = Py + k.x * Ty + k.y * By + k.z * Ny;
    floatV Sz = Pz + k.x * Tz + k.y * Bz + k.z * Nz;
    floatV inv = 1.0f / Sz;
    floatV sx = cx + Sx * inv, sy = cy + Sy * inv;
    // The sample's grid pixel (ix, iy) = floor(t) for t > −1 (truncation of t + 1, minus 1, the
    // float clamped first so that the conversion is defined; NaN -> −1), t = s on the camera image,
    // t = (s − ½)/2 + ½ on the half-resolution grid (the grid pixel whose camera pixel centre is
    // nearest); off the grid or at depth <= 0 (behind the camera): no information, not occluded.
#if GI_SSAO_DOWN == 1
    floatV tx = sx, ty = sy;
#else
    floatV tx = sx * (1.0f / D) + (0.5f - 0.5f / D), ty = sy * (1.0f / D) + (0.5f - 0.5f / D);
#endif
    intV ix = convert_intV(ssao_clamp_index(tx, W)) - 1, iy = convert_intV(ssao_clamp_index(ty, H)) - 1;
    intV ok = (Sz > 0.0f) & (as_uintV(ix) < (uint)gridWidth) & (as_uintV(iy) < (uint)gridHeight);
    intV q = GI_SEL((intV)(0), iy * gridWidth + ix, ok);
    uintV w = SSAO_GATHER_RECORDS(records, q);
    // q's record describes the plane at camera pixel (D·ix, D·iy); decoded as ssao_encode_record:
    // A, and A·g = m·A·2^(E−15) (the exponent fields added: exact).
    uintV aField = (w >> 4) & 0x0ffff000u;
    floatV A = as_floatV(aField + baseBits);
    floatV Ag = as_floatV(aField + ((w << 11) & 0x07800000u) + (baseBits - (15u << 23)));
    floatV Agx = convert_floatV(as_intV(w << 20) >> 26) * Ag, Agy = convert_floatV(as_intV(w << 26) >> 26) * Ag;
    floatV ux = D * convert_floatV(ix) + (0.5f - cx), uy = D * convert_floatV(iy) + (0.5f - cy);  // q's centre
    // The plane 1/depth(s) = A·(1 + g·(s − q's centre)) is n'·S = 1 in these coordinates, with
    // n' = (A·g_x, A·g_y, A·(1 − g·u)), u = q's centre relative to the principal point; S lies
    // e = n'·S − 1 = depth_S·(1/depth of the plane on S's ray) − 1 (relative) behind it, which is a
    // distance e/|n'_m| along the plane's normal, n'_m = (A·g_x·fx, A·g_y·fy, n'_z) being n' in
    // metric camera coordinates. Occluded: more than the bias behind, e > bias·|n'_m| (squared: no
    // square root), and the range check |depth_q − depth_P| < R multiplied by A > 0.
    floatV Anz = A - Agx * ux - Agy * uy;  // n'_z (nz is P's shading normal)
    floatV e = Agx * Sx + Agy * Sy + Anz * Sz - 1.0f;
    floatV mx = Agx * fx, my = Agy * fy;
    intV occ = ok & (e > 0.0f) & (e * e > bias2 * (mx * mx + my * my + Anz * Anz)) &
               (fabs(1.0f - zP * A) < radius * A);
    SSAO_COUNT(occluded, occ);
#if GI_SSAO_BLEEDING
    if (GI_ANY(occ)) {
#if GI_SSAO_DOWN == 1
      intV q4 = q * 4;
#else
      intV q4 = GI_SEL((intV)(0), (GI_SSAO_DOWN * iy) * width + GI_SSAO_DOWN * ix, ok) * 4;
#endif
      floatV Qx = GI_GATHER(floatV, pos, q4), Qy = GI_GATHER(floatV, pos, q4 + 1), Qz = GI_GATHER(floatV, pos, q4 + 2);
      floatV vx = Qx - Pwx, vy = Qy - Pwy, vz = Qz - Pwz;
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
#endif
  }
  // Background lanes ran with depth 0 (their samples may pass the tests): no occlusion, no light.
  ssao_store1(occlusionOut, i0, valid,
              GI_SEL((floatV)(0.0f), convert_floatV(occluded) / (float)GI_SSAO_SAMPLES, surface));
  // E only with bleeding on: the blur reads it only then, and 16 bytes per pixel written for
  // nothing would also push the sampled records out of the L2 cache.
#if GI_SSAO_BLEEDING
  floatV zero = (floatV)(0.0f);
  Ex = GI_SEL(zero, Ex, surface);
  Ey = GI_SEL(zero, Ey, surface);
  Ez = GI_SEL(zero, Ez, surface);
  SSAO_STORE4(irradianceOut, i0, valid, Ex, Ey, Ez, zero)
#endif
}

// indirect = keep·indirect_upstream (xyz; w kept) for the GI_VW pixels from i0, in place: each
// 16-float row (four pixels) times (keep_p, keep_p, keep_p, 1) of its pixels (one permutation of
// keep; w·1 = w exactly), instead of transposing GI_VW float4 into four floatV and back, which
// compiled to ≈ 100 loads and shuffles and took half of the blur's time. The same products.
#if GI_VW == 16
#define SSAO_KEEP_ROW(keep, one, c)                                                                          \
  shuffle2(keep, one, (uint16)(4 * (c), 4 * (c), 4 * (c), 16, 4 * (c) + 1, 4 * (c) + 1, 4 * (c) + 1, 16,     \
                               4 * (c) + 2, 4 * (c) + 2, 4 * (c) + 2, 16, 4 * (c) + 3, 4 * (c) + 3, 4 * (c) + 3, 16))
#elif GI_VW == 8
#define SSAO_KEEP_ROW(keep, one, c)                                                                          \
  shuffle2(keep, one, (uint16)(4 * (c), 4 * (c), 4 * (c), 8, 4 * (c) + 1, 4 * (c) + 1, 4 * (c) + 1, 8,       \
                               4 * (c) + 2, 4 * (c) + 2, 4 * (c) + 2, 8, 4 * (c) + 3, 4 * (c) + 3, 4 * (c) + 3, 8))
#endif
inline void ssao_scale_indirect(global float4* indirect, int i0, int valid, floatV keep) {
#if GI_VW == 1
  float4 v = indirect[i0];
  indirect[i0] = (float4)(v.xyz * keep, v.w);
#else
  if (valid == GI_VW) {
    global float* row = (global float*)(indirect + i0);
    floatV one = (floatV)(1.0f);
#pragma unroll
    for (int c = 0; c < GI_VW / 4; ++c) vstore16(vload16(c, row) * SSAO_KEEP_ROW(keep, one, c), c, row);
  } else {
    float k[GI_VW];
    vstoreV(keep, 0, k);
    for (int l = 0; l < valid; ++l) {
      float4 v = indirect[i0 + l];
      indirect[i0 + l] = (float4)(v.xyz * k[l], v.w);
    }
  }
#endif
}

// The composition of GI_VW pixels from pixel i0 (valid of them in the image): stores the blurred
// occlusion occ and indirect = (1 − occ)·indirect_upstream + albedo·k·E, k = the E normalisation
// over π (0 off surfaces).
// Without bleeding only the upstream term is scaled (ssao_scale_indirect).
inline void ssao_compose(int i0, int valid, floatV occ, floatV k, floatV Ex, floatV Ey, floatV Ez, int upstream,
                         int bleeding, global const float4* albedo, global float* occlusionOut,
                         global float4* indirect) {
  float tmp[4 * GI_VW];
  floatV zero = (floatV)(0.0f);
  ssao_store1(occlusionOut, i0, valid, occ);
  if (upstream && !bleeding) {
    ssao_scale_indirect(indirect, i0, valid, 1.0f - occ);
    return;
  }
  floatV ix = zero, iy = zero, iz = zero, iw = zero;
  if (upstream) SSAO_LOAD4(indirect, i0, valid, ix, iy, iz, iw)
  floatV keep = 1.0f - occ;
  floatV ox = keep * ix, oy = keep * iy, oz = keep * iz;
  if (bleeding) {
    floatV ax, ay, az, aw;
    SSAO_LOAD4(albedo, i0, valid, ax, ay, az, aw)
    ox += ax * k * Ex;
    oy += ay * k * Ey;
    oz += az * k * Ez;
  }
  SSAO_STORE4(indirect, i0, valid, ox, oy, oz, iw)
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
  floatV tol = tau * z, occ = zero, Ex = zero, Ey = zero, Ez = zero;
  intV count = (intV)(0);  // taps taken
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
        intV xc = row + clamp(xx, (intV)(0), (intV)(width - 1));
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
      SSAO_COUNT(count, take);
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
  floatV inv = GI_SEL(zero, one / fmax(convert_floatV(count), one), surface);
  ssao_compose(i0, valid, occ * inv, GI_SEL(zero, GI_INV_PI * inv, surface), Ex, Ey, Ez, upstream, bleeding, albedo,
               occlusionOut, indirect);
}

// ssao.downsample = 2: the blur of ssao_blur_compose over the half-resolution grid, evaluated per
// camera pixel, then the same composition. Camera pixel (x, y) averages the 4×4 grid pixels
// (u, v) = (⌊(x+1)/2⌋ − 2 + i, ⌊(y+1)/2⌋ − 2 + j), i, j = 0..3 (any 4×4 block of the grid holds each
// noise rotation once), skipping those whose surface does not pass through the pixel's: the depth
// of grid pixel q's tangent plane on the pixel's view ray, from q's depth-plane record, must be
// within tau·z of the pixel's depth z — never across depth discontinuities (the full-resolution
// blur compares depths directly; over two camera pixels a plane seen at a grazing angle changes
// its depth by more than tau, so the plane is extrapolated instead). A pixel with no grid pixel of
// its surface in the window (a feature under two pixels wide) gets no occlusion and no bleeding.
// Lanes: a work-item takes the 2·GI_VW camera pixels from x0 (even) as two floatV, the even pixels
// x0 + 2l and the odd pixels x0 + 2l + 1. Their windows start at grid columns c0 + l and c0 + l + 1
// (c0 = x0/2 − 2), so inside the grid each row of windows is five contiguous loads (columns
// c0 + k + l, k = 0..4: taps k of the even and k − 1 of the odd pixels) and no lane shuffles; the
// pixels lie 4 − 2k (even) and 5 − 2k (odd) camera pixels right of the centre of grid column
// c0 + k + l. The results are interleaved back into pixel order once, for the composition.
#if GI_VW == 16
#define SSAO_EVEN(a, b) ((float16)((a).even, (b).even))
#define SSAO_ODD(a, b) ((float16)((a).odd, (b).odd))
#define SSAO_INTERLEAVE_LO(e, o) shuffle2(e, o, (uint16)(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23))
#define SSAO_INTERLEAVE_HI(e, o) shuffle2(e, o, (uint16)(8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15, 31))
#elif GI_VW == 8
#define SSAO_EVEN(a, b) ((float8)((a).even, (b).even))
#define SSAO_ODD(a, b) ((float8)((a).odd, (b).odd))
#define SSAO_INTERLEAVE_LO(e, o) shuffle2(e, o, (uint8)(0, 8, 1, 9, 2, 10, 3, 11))
#define SSAO_INTERLEAVE_HI(e, o) shuffle2(e, o, (uint8)(4, 12, 5, 13, 6, 14, 7, 15))
#else
#define SSAO_EVEN(a, b) (a)
#define SSAO_ODD(a, b) (b)
#define SSAO_INTERLEAVE_LO(e, o) (e)
#define SSAO_INTERLEAVE_HI(e, o) (o)
#endif
// One tap: accumulate grid pixel (plane P + Q·offsetX at the pixel, NaN where it is not usable;
// occlusion oq, E) into a pixel of depth z when its plane passes within tau·z.
#define SSAO_UP_TAP(z, offsetX, occ, count, Ex, Ey, Ez)                  \
  {                                                                      \
    floatV e_ = (z) * (P + Q * (offsetX)) - 1.0f;                        \
    intV take_ = fabs(e_) <= tau;                                        \
    occ += GI_SEL(zero, oq, take_);                                      \
    SSAO_COUNT(count, take_);                                            \
    if (bleeding) {                                                      \
      Ex += GI_SEL(zero, ex, take_);                                     \
      Ey += GI_SEL(zero, ey, take_);                                     \
      Ez += GI_SEL(zero, ez, take_);                                     \
    }                                                                    \
  }
kernel void ssao_upsample_blur_compose(int width, int height, int gridWidth, int gridHeight,
                                       global const float* depth, global const float4* albedo,
                                       global const float* gridInvDepth, global const float* gridSlopeX,
                                       global const float* gridSlopeY,
                                       global const float* occlusionIn, global const float4* irradianceIn, float tau,
                                       int upstream, int bleeding, global float* occlusionOut,
                                       global float4* indirect) {
  int x0 = get_global_id(0) * 2 * GI_VW, y = get_global_id(1);
  if (x0 >= width || y >= height) return;
  size_t row0 = (size_t)y * width;
  intV lanes = (intV)(GI_LANES);
  floatV zE, zO;  // depths of the even and the odd pixels
  if (x0 + 2 * GI_VW <= width) {
    floatV a = vloadV(0, depth + row0 + x0), b = vloadV(0, depth + row0 + x0 + GI_VW);
    zE = SSAO_EVEN(a, b);
    zO = SSAO_ODD(a, b);
  } else {  // pixels past the border repeat the last one (not stored)
    zE = GI_GATHER(floatV, depth + row0, min(x0 + 2 * lanes, (intV)(width - 1)));
    zO = GI_GATHER(floatV, depth + row0, min(x0 + 2 * lanes + 1, (intV)(width - 1)));
  }
  floatV zero = (floatV)(0.0f), one = (floatV)(1.0f);
  floatV occE = zero, ExE = zero, EyE = zero, EzE = zero;
  floatV occO = zero, ExO = zero, EyO = zero, EzO = zero;
  intV cntE = (intV)(0), cntO = (intV)(0);  // taps taken
  global const float* irr = (global const float*)irradianceIn;
  int c0 = x0 / 2 - 2, v0 = (y + 1) / 2 - 2;
  bool interior = c0 >= 0 && c0 + 4 + GI_VW <= gridWidth;
#pragma unroll
  for (int dy = 0; dy < 4; ++dy) {
    int vv = v0 + dy;
    if (vv < 0 || vv >= gridHeight) continue;
    int row = vv * gridWidth;
    float offsetY = (float)(y - 2 * vv);  // camera pixels below the grid row's pixel centres
#pragma unroll
    for (int k = 0; k < 5; ++k) {
      floatV A, Q, slopeY, oq, ex = zero, ey = zero, ez = zero, unused;
      intV inside;
      if (interior) {
        int c = row + c0 + k;
        inside = lanes >= 0;  // all lanes
        A = vloadV(0, gridInvDepth + c);
        Q = vloadV(0, gridSlopeX + c);
        slopeY = vloadV(0, gridSlopeY + c);
        oq = vloadV(0, occlusionIn + c);
        if (bleeding) GI_AOS4_LOAD(irr + (size_t)c * 4, ex, ey, ez, unused)
      } else {
        intV u = c0 + k + lanes;
        inside = (u >= 0) & (u < gridWidth);
        intV uc = row + clamp(u, (intV)(0), (intV)(gridWidth - 1));
        A = GI_GATHER(floatV, gridInvDepth, uc);
        Q = GI_GATHER(floatV, gridSlopeX, uc);
        slopeY = GI_GATHER(floatV, gridSlopeY, uc);
        oq = GI_GATHER(floatV, occlusionIn, uc);
        if (bleeding) GI_GATHER_AOS4(float, irr, uc, ex, ey, ez, unused)
      }
      // 1/depth of the grid pixel's plane at camera-pixel offset (dx, offsetY) from its centre:
      // P + Q·dx (ssao_depth_planes); P = NaN (no tap passes) outside the grid and on the
      // background (A = 0).
      floatV P = GI_SEL((floatV)(NAN), A + slopeY * offsetY, inside & (A > 0.0f));
      if (k < 4) SSAO_UP_TAP(zE, (float)(4 - 2 * k), occE, cntE, ExE, EyE, EzE)
      if (k > 0) SSAO_UP_TAP(zO, (float)(5 - 2 * k), occO, cntO, ExO, EyO, EzO)
    }
  }
  // No grid pixel accepted (or the background): no occlusion, no bleeding, the upstream value kept.
  intV surfE = isfinite(zE) & (cntE > 0), surfO = isfinite(zO) & (cntO > 0);
  floatV invE = GI_SEL(zero, one / fmax(convert_floatV(cntE), one), surfE);
  floatV invO = GI_SEL(zero, one / fmax(convert_floatV(cntO), one), surfO);
  occE *= invE;
  occO *= invO;
  floatV kE = GI_INV_PI * invE, kO = GI_INV_PI * invO;
  int i0 = (int)row0 + x0;
  ssao_compose(i0, min(GI_VW, width - x0), SSAO_INTERLEAVE_LO(occE, occO), SSAO_INTERLEAVE_LO(kE, kO),
               SSAO_INTERLEAVE_LO(ExE, ExO), SSAO_INTERLEAVE_LO(EyE, EyO), SSAO_INTERLEAVE_LO(EzE, EzO), upstream,
               bleeding, albedo, occlusionOut, indirect);
  if (x0 + GI_VW < width)
    ssao_compose(i0 + GI_VW, min(GI_VW, width - x0 - GI_VW), SSAO_INTERLEAVE_HI(occE, occO),
                 SSAO_INTERLEAVE_HI(kE, kO), SSAO_INTERLEAVE_HI(ExE, ExO), SSAO_INTERLEAVE_HI(EyE, EyO),
                 SSAO_INTERLEAVE_HI(EzE, EzO), upstream, bleeding, albedo, occlusionOut, indirect);
}
