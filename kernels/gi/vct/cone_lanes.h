// The cone march of cone.h with GI_VW pixels per work-item (common/vector_width.h;
// PERFORMANCE_FACTS.md points 1-2: a data-dependent loop over one pixel per work-item runs as
// scalar code on PoCL, explicit lanes do not).
//
// Each lane marches its own cone (aperture, angle to its normal, hence its own distances, levels
// and footprint caps); for the diffuse set these are the same in every lane, so the lanes step in
// lockstep. A lane that leaves the grid, passes the maximum distance or saturates is masked from
// then on (vct_cone breaks there); the march ends when every lane is done. Same formulas as
// vct_cone, term for term, with log2/exp2 lane-wise (log2V, pow01V).
#pragma once
#include "common/vector_width.h"
#include "gi/vct/cone.h"

typedef struct {
  floatV r, g, b, a;
} RgbaV;

// The chains of VoxelMips as float arrays (4 floats per record; SH: 12 per voxel).
typedef struct {
  global const float* iso;
  global const float* aniso;
  global const float* sh;
  global const float* shAniso;
  int N, levels, anisotropic;
} VoxelMipsV;

inline VoxelMipsV vox_mips_lanes(VoxelMips m) {
  VoxelMipsV r;
  r.iso = (global const float*)m.iso;
  r.aniso = (global const float*)m.aniso;
  r.sh = (global const float*)m.sh;
  r.shAniso = (global const float*)m.shAniso;
  r.N = m.N;
  r.levels = m.levels;
  r.anisotropic = m.anisotropic;
  return r;
}

// The two x-adjacent records at element offsets i (per lane) of p (records of 4 floats) as eight
// planes R0, G0, B0, A0, R1, G1, B1, A1: one 32-byte load per lane and an 8×8 transposition in the
// three shuffle stages of AVX (unpack within 128-bit halves, pairs of pairs, halves), written so
// that each loaded vector is consumed whole (picking single elements out of the loads made the
// compiler split them into 8-byte loads and element inserts).
#if GI_VW >= 8
// The transposition: L[k] = the pair of lane k (R0 G0 B0 A0 R1 G1 B1 A1) → out = the 8 planes.
__attribute__((always_inline)) inline void vct_transpose_pairs8(float8 L0, float8 L1, float8 L2, float8 L3, float8 L4,
                                                                float8 L5, float8 L6, float8 L7, float8 out[8]) {
  float8 t0 = (float8)(L0.s0, L1.s0, L0.s1, L1.s1, L0.s4, L1.s4, L0.s5, L1.s5);
  float8 t1 = (float8)(L0.s2, L1.s2, L0.s3, L1.s3, L0.s6, L1.s6, L0.s7, L1.s7);
  float8 t2 = (float8)(L2.s0, L3.s0, L2.s1, L3.s1, L2.s4, L3.s4, L2.s5, L3.s5);
  float8 t3 = (float8)(L2.s2, L3.s2, L2.s3, L3.s3, L2.s6, L3.s6, L2.s7, L3.s7);
  float8 t4 = (float8)(L4.s0, L5.s0, L4.s1, L5.s1, L4.s4, L5.s4, L4.s5, L5.s5);
  float8 t5 = (float8)(L4.s2, L5.s2, L4.s3, L5.s3, L4.s6, L5.s6, L4.s7, L5.s7);
  float8 t6 = (float8)(L6.s0, L7.s0, L6.s1, L7.s1, L6.s4, L7.s4, L6.s5, L7.s5);
  float8 t7 = (float8)(L6.s2, L7.s2, L6.s3, L7.s3, L6.s6, L7.s6, L6.s7, L7.s7);
  // u0..u3: R, G, B, A of lanes 0-3 (first record | second record); u4..u7: lanes 4-7.
  float8 u0 = (float8)(t0.s01, t2.s01, t0.s45, t2.s45), u1 = (float8)(t0.s23, t2.s23, t0.s67, t2.s67);
  float8 u2 = (float8)(t1.s01, t3.s01, t1.s45, t3.s45), u3 = (float8)(t1.s23, t3.s23, t1.s67, t3.s67);
  float8 u4 = (float8)(t4.s01, t6.s01, t4.s45, t6.s45), u5 = (float8)(t4.s23, t6.s23, t4.s67, t6.s67);
  float8 u6 = (float8)(t5.s01, t7.s01, t5.s45, t7.s45), u7 = (float8)(t5.s23, t7.s23, t5.s67, t7.s67);
  out[0] = (float8)(u0.lo, u4.lo);
  out[1] = (float8)(u1.lo, u5.lo);
  out[2] = (float8)(u2.lo, u6.lo);
  out[3] = (float8)(u3.lo, u7.lo);
  out[4] = (float8)(u0.hi, u4.hi);
  out[5] = (float8)(u1.hi, u5.hi);
  out[6] = (float8)(u2.hi, u6.hi);
  out[7] = (float8)(u3.hi, u7.hi);
}

__attribute__((always_inline)) inline void vct_pair_planes8(global const float* p, int8 i, float8 out[8]) {
  vct_transpose_pairs8(vload8(0, p + i.s0), vload8(0, p + i.s1), vload8(0, p + i.s2), vload8(0, p + i.s3),
                       vload8(0, p + i.s4), vload8(0, p + i.s5), vload8(0, p + i.s6), vload8(0, p + i.s7), out);
}

// The planes of the blend w0·pair(px + i0) + w1·pair(py + i1) + w2·pair(pz + i2) per lane: three
// volumes with the same stencil combined before the one transposition. The volumes' bases go into
// px, py, pz where they are the same in every lane (the lanes' directions face the same way along
// each axis, the common case) and i0 = i1 = i2: then one offset is taken out of the lane vector per
// lane instead of three; else px = py = pz and the bases are in the offsets. The offsets are
// non-negative: zero-extended into the address (no sign extension per lane).
#define VCT_BLEND3_LANE(k) (w0.s##k * vload8(0, px + u0.s##k) + w1.s##k * vload8(0, py + u1.s##k) + w2.s##k * vload8(0, pz + u2.s##k))
__attribute__((always_inline)) inline void vct_pair_planes8_blend3(global const float* px, global const float* py,
                                                                   global const float* pz, int8 i0, int8 i1, int8 i2,
                                                                   float8 w0, float8 w1, float8 w2, float8 out[8]) {
  uint8 u0 = as_uint8(i0), u1 = as_uint8(i1), u2 = as_uint8(i2);
  vct_transpose_pairs8(VCT_BLEND3_LANE(0), VCT_BLEND3_LANE(1), VCT_BLEND3_LANE(2), VCT_BLEND3_LANE(3),
                       VCT_BLEND3_LANE(4), VCT_BLEND3_LANE(5), VCT_BLEND3_LANE(6), VCT_BLEND3_LANE(7), out);
}
#undef VCT_BLEND3_LANE
#endif

// The 8 planes (R0 G0 B0 A0 R1 G1 B1 A1) of a tap pair, unpacked from what the per-width gathers
// return: two float8[8] halves at 16 lanes, one float8[8] at 8 lanes, one float8 at 1 lane.
#define VCT_UNPACK_HALVES(lo_, hi_, R0, G0, B0, A0, R1, G1, B1, A1) \
  R0 = (float16)(lo_[0], hi_[0]);                                 \
  G0 = (float16)(lo_[1], hi_[1]);                                 \
  B0 = (float16)(lo_[2], hi_[2]);                                 \
  A0 = (float16)(lo_[3], hi_[3]);                                 \
  R1 = (float16)(lo_[4], hi_[4]);                                 \
  G1 = (float16)(lo_[5], hi_[5]);                                 \
  B1 = (float16)(lo_[6], hi_[6]);                                 \
  A1 = (float16)(lo_[7], hi_[7]);
#define VCT_UNPACK_PLANES(t_, R0, G0, B0, A0, R1, G1, B1, A1) \
  R0 = t_[0];                                                 \
  G0 = t_[1];                                                 \
  B0 = t_[2];                                                 \
  A0 = t_[3];                                                 \
  R1 = t_[4];                                                 \
  G1 = t_[5];                                                 \
  B1 = t_[6];                                                 \
  A1 = t_[7];
#define VCT_UNPACK_RECORD(a_, R0, G0, B0, A0, R1, G1, B1, A1) \
  R0 = a_.s0;                                                 \
  G0 = a_.s1;                                                 \
  B0 = a_.s2;                                                 \
  A0 = a_.s3;                                                 \
  R1 = a_.s4;                                                 \
  G1 = a_.s5;                                                 \
  B1 = a_.s6;                                                 \
  A1 = a_.s7;

#if GI_VW == 16
#define VCT_GATHER_PAIR(p, i, R0, G0, B0, A0, R1, G1, B1, A1) \
  {                                                          \
    float8 lo_[8], hi_[8];                                   \
    vct_pair_planes8(p, (i).lo, lo_);                        \
    vct_pair_planes8(p, (i).hi, hi_);                        \
    VCT_UNPACK_HALVES(lo_, hi_, R0, G0, B0, A0, R1, G1, B1, A1) \
  }
#elif GI_VW == 8
#define VCT_GATHER_PAIR(p, i, R0, G0, B0, A0, R1, G1, B1, A1) \
  {                                                          \
    float8 t_[8];                                            \
    vct_pair_planes8(p, i, t_);                              \
    VCT_UNPACK_PLANES(t_, R0, G0, B0, A0, R1, G1, B1, A1)    \
  }
#elif GI_VW == 1
#define VCT_GATHER_PAIR(p, i, R0, G0, B0, A0, R1, G1, B1, A1) \
  {                                                          \
    float8 a_ = vload8(0, (p) + (i));                        \
    VCT_UNPACK_RECORD(a_, R0, G0, B0, A0, R1, G1, B1, A1)    \
  }
#endif

// Whether every lane of a mask (0 / −1 per lane) is set, without branches: the lanes ANDed in
// halves, then the sign. PoCL's all() on int16 tests the lanes two by two with a branch after
// each pair, which costs mispredictions where the answer is data-dependent (shared stencils).
#if GI_VW == 16 && defined(__AVX512DQ__) && defined(__has_builtin)
#if __has_builtin(__builtin_ia32_cvtd2mask512)
// With AVX-512 (x86 CPU devices): the lanes' signs as a 16-bit mask (one vpmovd2m, which the
// compiler folds into the comparison that made m) against all ones.
#define VCT_MASK_BITS(m) __builtin_ia32_cvtd2mask512(m)
#endif
#endif
#ifdef VCT_MASK_BITS
inline int vct_all(int16 m) { return VCT_MASK_BITS(m) == (ushort)0xffff; }
inline int vct_any(int16 m) { return VCT_MASK_BITS(m) != (ushort)0; }
#elif GI_VW == 16
inline int vct_all(int16 m) {
  int8 a = m.lo & m.hi;
  int4 b = a.lo & a.hi;
  int2 c = b.lo & b.hi;
  return (c.x & c.y) < 0;
}
#elif GI_VW == 8
inline int vct_all(int8 m) {
  int4 b = m.lo & m.hi;
  int2 c = b.lo & b.hi;
  return (c.x & c.y) < 0;
}
#else
inline int vct_all(int m) { return m != 0; }
#endif

// Lane 0's value of a lane vector.
#if GI_VW == 1
#define VCT_LANE0(v) (v)
#else
#define VCT_LANE0(v) ((v).s0)
#endif

// Window lookups (vox_level_sample_uniform_lanes): at 16 lanes on x86 CPUs with AVX-512
// (VCT_MASK_BITS), a lookup whose lanes' stencils lie within a window of 4 records along x
// and 2 rows along y and z per tap row loads the window's rows whole and picks each lane's element
// with a two-source permute (vpermi2ps: 32 candidates, the y row in bit 4 of the index) and a
// masked move (the z row). Same records as the per-lane gather, so the same bits.
#ifdef VCT_MASK_BITS
#if __has_builtin(__builtin_ia32_vpermi2varps512)
#define VCT_WINDOW_LOOKUPS 1
// The window's first index along an axis where lane 0 reads v0: v0 − 1 if some lane reads below
// it, else v0 (then the window fits if every lane reads within 1 of it).
inline int vct_window_start(int16 v, int v0) { return v0 - vct_any(v < (int16)(v0)); }

// Element idx + c (c = 0..7: the tap pair's R0 G0 B0 A0 R1 G1 B1 A1) per lane of the rows at
// p + o00 (y, z), p + o10 (y + 1, z), p + o01 (y, z + 1), p + o11 (y + 1, z + 1), 16 floats each;
// idx = 4·(lane's x − window x) + 16·(lane's row is y + 1); zUpper: the lane's row is z + 1.
__attribute__((always_inline)) inline void vct_window_pick(global const float* p, int o00, int o10, int o01, int o11,
                                                           int16 idx, int16 zUpper, float16 out[8]) {
  float16 r00 = vload16(0, p + o00), r10 = vload16(0, p + o10), r01 = vload16(0, p + o01), r11 = vload16(0, p + o11);
#pragma unroll
  for (int c = 0; c < 8; ++c) {
    float16 lower = __builtin_ia32_vpermi2varps512(r00, idx + c, r10);
    float16 upper = __builtin_ia32_vpermi2varps512(r01, idx + c, r11);
    out[c] = select(lower, upper, zUpper);
  }
}

// vct_window_pick of one axis's directional volume facing each lane's direction: plus where
// `facing`, else minus; both are read only where the lanes face both ways.
__attribute__((always_inline)) inline void vct_window_axis(global const float* plus, global const float* minus,
                                                           int16 facing, int o00, int o10, int o01, int o11,
                                                           int16 idx, int16 zUpper, float16 out[8]) {
  int allPlus = vct_all(facing), allMinus = vct_all(~facing);
  vct_window_pick(allMinus ? minus : plus, o00, o10, o01, o11, idx, zUpper, out);
  if (!allPlus && !allMinus) {
    float16 other[8];
    vct_window_pick(minus, o00, o10, o01, o11, idx, zUpper, other);
#pragma unroll
    for (int c = 0; c < 8; ++c) out[c] = select(other[c], out[c], facing);
  }
}
#endif
#endif

// VCT_GATHER_PAIR of the blend Σ_k w_k·pair(p_k + i_k) of three volumes (vct_pair_planes8_blend3).
#if GI_VW == 16
#define VCT_GATHER_PAIR_BLEND3(px, py, pz, i0, i1, i2, w0, w1, w2, R0, G0, B0, A0, R1, G1, B1, A1)               \
  {                                                                                                          \
    float8 lo_[8], hi_[8];                                                                                   \
    vct_pair_planes8_blend3(px, py, pz, (i0).lo, (i1).lo, (i2).lo, (w0).lo, (w1).lo, (w2).lo, lo_);          \
    vct_pair_planes8_blend3(px, py, pz, (i0).hi, (i1).hi, (i2).hi, (w0).hi, (w1).hi, (w2).hi, hi_);          \
    VCT_UNPACK_HALVES(lo_, hi_, R0, G0, B0, A0, R1, G1, B1, A1)                                              \
  }
#elif GI_VW == 8
#define VCT_GATHER_PAIR_BLEND3(px, py, pz, i0, i1, i2, w0, w1, w2, R0, G0, B0, A0, R1, G1, B1, A1) \
  {                                                                                            \
    float8 t_[8];                                                                              \
    vct_pair_planes8_blend3(px, py, pz, i0, i1, i2, w0, w1, w2, t_);                           \
    VCT_UNPACK_PLANES(t_, R0, G0, B0, A0, R1, G1, B1, A1)                                      \
  }
#elif GI_VW == 1
#define VCT_GATHER_PAIR_BLEND3(px, py, pz, i0, i1, i2, w0, w1, w2, R0, G0, B0, A0, R1, G1, B1, A1)                    \
  {                                                                                                               \
    float8 a_ = (w0) * vload8(0, (px) + (i0)) + (w1) * vload8(0, (py) + (i1)) + (w2) * vload8(0, (pz) + (i2));    \
    VCT_UNPACK_RECORD(a_, R0, G0, B0, A0, R1, G1, B1, A1)                                                       \
  }
#endif

// acc += w0 × first record + w1 × second record of a tap pair (first record's terms first, so the
// sums round as they always have).
__attribute__((always_inline)) inline void vct_add_pair(RgbaV* acc, floatV w0, floatV w1, floatV r0, floatV g0,
                                                        floatV b0, floatV a0, floatV r1, floatV g1, floatV b1,
                                                        floatV a1) {
  acc->r += w0 * r0;
  acc->g += w0 * g0;
  acc->b += w0 * b0;
  acc->a += w0 * a0;
  acc->r += w1 * r1;
  acc->g += w1 * g1;
  acc->b += w1 * b1;
  acc->a += w1 * a1;
}

// The stencil of a trilinear lookup at p (level-0 voxel units) in a volume of n³ voxels, scale =
// n / N, per lane: the tap pair along x of each (y, z) row starts at xs = clamp(ix, 0, n − 2) with
// weights wFirst, wSecond (each tap's weight moved to its place in the pair; a tap outside the
// volume weighs 0, and so does the pair's other record); rows yr, zr clamped into the volume with
// weights wy, wz (0 outside). With GI_VCT_BORDER_EDGE the position is first clamped to the
// outermost voxel centre along each axis on which d heads towards the grid's face
// (vox_trilinear_taps), so no tap lies past a face ahead of the cone.
typedef struct {
  intV xs, yr[2], zr[2];
  floatV wFirst, wSecond, wy[2], wz[2];
} VctStencilV;

__attribute__((always_inline)) inline VctStencilV vct_stencil_lanes(float3V p, float3V d, floatV scale, intV n) {
  VctStencilV st;
  floatV ux = p.x * scale - 0.5f, uy = p.y * scale - 0.5f, uz = p.z * scale - 0.5f;
#if GI_VCT_BORDER_EDGE
  {
    floatV zero = (floatV)(0.0f), last = convert_floatV(n - 1);  // two vectors: see min/max below
    ux = GI_SEL(GI_SEL(ux, fmax(ux, zero), d.x < 0.0f), fmin(ux, last), d.x > 0.0f);
    uy = GI_SEL(GI_SEL(uy, fmax(uy, zero), d.y < 0.0f), fmin(uy, last), d.y > 0.0f);
    uz = GI_SEL(GI_SEL(uz, fmax(uz, zero), d.z < 0.0f), fmin(uz, last), d.z > 0.0f);
  }
#endif
  floatV flx = floor(ux), fly = floor(uy), flz = floor(uz);
  floatV fx = ux - flx, fy = uy - fly, fz = uz - flz;
  intV ix = convert_intV(flx), iy = convert_intV(fly), iz = convert_intV(flz);
  floatV zero = (floatV)(0.0f);
  // Per axis, the weights of taps i and i + 1 (0 outside the volume).
  floatV wx0 = GI_SEL(zero, 1.0f - fx, ix >= 0 && ix < n), wx1 = GI_SEL(zero, fx, ix >= -1 && ix < n - 1);
  st.wy[0] = GI_SEL(zero, 1.0f - fy, iy >= 0 && iy < n);
  st.wy[1] = GI_SEL(zero, fy, iy >= -1 && iy < n - 1);
  st.wz[0] = GI_SEL(zero, 1.0f - fz, iz >= 0 && iz < n);
  st.wz[1] = GI_SEL(zero, fz, iz >= -1 && iz < n - 1);
  intV zeroI = (intV)(0);  // min/max of two vectors (oclgrind mis-evaluates vector-scalar forms)
  st.yr[0] = min(max(iy, zeroI), n - 1);
  st.yr[1] = min(max(iy + 1, zeroI), n - 1);
  st.zr[0] = min(max(iz, zeroI), n - 1);
  st.zr[1] = min(max(iz + 1, zeroI), n - 1);
  st.xs = max(min(ix, n - 2), zeroI);
  intV below = ix < st.xs, above = ix > st.xs;
  st.wFirst = GI_SEL(GI_SEL(wx0, zero, above), wx1, below);
  st.wSecond = GI_SEL(GI_SEL(wx1, wx0, above), zero, below);
  return st;
}

// acc += weight × the trilinear lookup at p of the volume of n³ voxels, n = 2^shift (scale = n / N),
// starting at voxel `base` (all per lane) of `vol` (radiance, α) or, with SH voxels, of `shVol`
// evaluated against basis (Y0, Y1y, Y1z, Y1x) with α from `vol` (vox_trilinear / vox_trilinear_sh).
// Same taps, weights and order of summation as vox_trilinear; the tap pair along x of each (y, z)
// row is read as one pair of adjacent records starting at xs = clamp(ix, 0, n − 2), each tap's weight
// moved to its place in the pair (a tap outside the volume weighs 0, and so does the pair's other
// record). Rows outside the volume are clamped into it and weigh 0. A 1-voxel volume's pair
// reaches one record past it: the chains end with one zero record (VoxelScene).
__attribute__((always_inline)) inline void vox_trilinear_lanes(global const float* vol, global const float* shVol, intV base, intV shift, float3V p, float3V d,
                                floatV scale, floatV weight, floatV Y0, floatV Y1y, floatV Y1z, floatV Y1x, RgbaV* acc) {
  intV n = (intV)(1) << shift;
  VctStencilV st = vct_stencil_lanes(p, d, scale, n);
  intV xs = st.xs, yr[2] = {st.yr[0], st.yr[1]}, zr[2] = {st.zr[0], st.zr[1]};
  floatV wFirst = st.wFirst, wSecond = st.wSecond, wy[2] = {st.wy[0], st.wy[1]}, wz[2] = {st.wz[0], st.wz[1]};
#pragma unroll
  for (int row = 0; row < 4; ++row) {
    int yb = row & 1, zb = row >> 1;
    intV idx = base + ((((zr[zb] << shift) + yr[yb]) << shift) + xs);
    floatV w0 = wFirst * wy[yb] * wz[zb] * weight, w1 = wSecond * wy[yb] * wz[zb] * weight;
#if GI_VCT_SH
    floatV r0, r1, r2, r3, g0, g1, g2, g3, b0, b1, b2, b3;
    GI_GATHER_SPAN4(float, shVol, idx * 12, r0, r1, r2, r3)
    GI_GATHER_SPAN4(float, shVol, idx * 12 + 4, g0, g1, g2, g3)
    GI_GATHER_SPAN4(float, shVol, idx * 12 + 8, b0, b1, b2, b3)
    acc->r += w0 * (r0 * Y0 + r1 * Y1y + r2 * Y1z + r3 * Y1x);
    acc->g += w0 * (g0 * Y0 + g1 * Y1y + g2 * Y1z + g3 * Y1x);
    acc->b += w0 * (b0 * Y0 + b1 * Y1y + b2 * Y1z + b3 * Y1x);
    GI_GATHER_SPAN4(float, shVol, idx * 12 + 12, r0, r1, r2, r3)
    GI_GATHER_SPAN4(float, shVol, idx * 12 + 16, g0, g1, g2, g3)
    GI_GATHER_SPAN4(float, shVol, idx * 12 + 20, b0, b1, b2, b3)
    acc->r += w1 * (r0 * Y0 + r1 * Y1y + r2 * Y1z + r3 * Y1x);
    acc->g += w1 * (g0 * Y0 + g1 * Y1y + g2 * Y1z + g3 * Y1x);
    acc->b += w1 * (b0 * Y0 + b1 * Y1y + b2 * Y1z + b3 * Y1x);
    floatV unused0, unused1, unused2, a0, unused3, unused4, unused5, a1;
    VCT_GATHER_PAIR(vol, idx * 4, unused0, unused1, unused2, a0, unused3, unused4, unused5, a1)
    acc->a += w0 * a0;
    acc->a += w1 * a1;
#else
    floatV r0, g0, b0, a0, r1, g1, b1, a1;
    VCT_GATHER_PAIR(vol, idx * 4, r0, g0, b0, a0, r1, g1, b1, a1)
    vct_add_pair(acc, w0, w1, r0, g0, b0, a0, r1, g1, b1, a1);
#endif
  }
}

// acc += weight × Σ_k b_k·trilinear(volume k) of the three volumes of n³ voxels, n = 2^shift, that
// start at voxels base0, base1, base2 of `vol` (radiance, α): a lookup is linear in the records, so
// the blend of the three lookups is the lookup of the blended records, each tap pair blended per
// lane before one transposition (VCT_GATHER_PAIR_BLEND3) instead of three. Same taps and weights as
// three vox_trilinear_lanes; the sums are associated differently (not bit-identical to them).
__attribute__((always_inline)) inline void vox_trilinear_blend3_lanes(global const float* vol, intV base0, intV base1,
                                                                      intV base2, floatV b0, floatV b1, floatV b2,
                                                                      intV shift, float3V p, float3V d, floatV scale,
                                                                      floatV weight, RgbaV* acc) {
  intV n = (intV)(1) << shift;
  VctStencilV st = vct_stencil_lanes(p, d, scale, n);
#pragma unroll
  for (int row = 0; row < 4; ++row) {
    int yb = row & 1, zb = row >> 1;
    intV idx = (((st.zr[zb] << shift) + st.yr[yb]) << shift) + st.xs;
    floatV wRow = st.wy[yb] * st.wz[zb] * weight;
    floatV r0, g0, b0_, a0, r1, g1, b1_, a1;
    VCT_GATHER_PAIR_BLEND3(vol, vol, vol, 4 * (base0 + idx), 4 * (base1 + idx), 4 * (base2 + idx), b0, b1, b2, r0, g0,
                           b0_, a0, r1, g1, b1_, a1)
    vct_add_pair(acc, st.wFirst * wRow, st.wSecond * wRow, r0, g0, b0_, a0, r1, g1, b1_, a1);
  }
}

// acc += weight × level `level` (per lane) seen along d (vox_level_sample). Level offsets in closed
// form: Σ_{l<L} (N >> l)³ = 8·n³·(8^L − 1)/7 with n = N >> L, and (8^L − 1)/7 = octal 1…1 (L ones).
__attribute__((always_inline)) inline void vox_level_sample_lanes(VoxelMipsV m, intV level, float3V p, float3V d, floatV weight, RgbaV* acc) {
  int logN = 31 - clz(m.N);
  intV shift = logN - level;
  floatV scale = as_floatV(convert_uintV(127 - level) << 23);  // 2^−level
  intV n3Shift = 3 * shift;
  intV offset = ((intV)(0x09249249) & (((intV)(1) << (3 * level)) - 1)) << (n3Shift + 3);
  int N3 = m.N * m.N * m.N;
  intV n3 = (intV)(1) << n3Shift;
  // Light arriving at the apex travels along −d: the SH basis at −d.
  floatV Y0 = (floatV)(GI_SH_Y0), Y1y = -GI_SH_Y1 * d.y, Y1z = -GI_SH_Y1 * d.z, Y1x = -GI_SH_Y1 * d.x;
  // level < the first directional level (every level with isotropic mips), as the sign of the
  // difference: not a constant all-true mask for isotropic mips, and not a comparison, which the
  // compiler evaluates once and broadcasts where the level is the same in every lane (the SH
  // voxels' vox_level_sample_uniform_lanes): Oclgrind gets both wrong (GI_NOT, vector_width.h).
  // 0 / −1 at every width (GI_SEL, GI_ANY and GI_ALL take any nonzero as true at GI_VW 1).
  intV isoLanes = (level - (m.anisotropic ? GI_VCT_FIRST_DIRECTIONAL_LEVEL : INT_MAX)) >> 31;
  // Lanes masked out of a volume (weight 0) read its first voxels only (n = 1, base 0): the
  // isotropic levels ≥ 1 are not built with anisotropic mips, and level 0 has no directional
  // volumes unless GI_VCT_DIRECTIONAL; unwritten memory could hold NaN, and NaN·0 is NaN.
  if (GI_ANY(isoLanes))
    vox_trilinear_lanes(m.iso, m.sh, GI_SEL((intV)(0), offset, isoLanes), GI_SEL((intV)(0), shift, isoLanes), p, d, scale,
                        GI_SEL((floatV)(0.0f), weight, isoLanes), Y0, Y1y, Y1z, Y1x, acc);
  if (!m.anisotropic || GI_ALL(isoLanes)) return;
  floatV da[3] = {d.x, d.y, d.z};
  intV shiftDirectional = GI_SEL(shift, (intV)(0), isoLanes);
  // Directional volume 2·axis (+) or 2·axis + 1 (−) of the level (vox_aniso_offset), per axis.
  intV base[3];
  for (int axis = 0; axis < 3; ++axis)
    base[axis] = GI_SEL(6 * (offset - GI_VCT_FIRST_DIRECTIONAL_LEVEL * N3) + (2 * axis + GI_SEL((intV)(1), (intV)(0), da[axis] >= 0.0f)) * n3,
                        (intV)(0), isoLanes);
#if GI_VCT_SH
  for (int axis = 0; axis < 3; ++axis)
    vox_trilinear_lanes(m.aniso, m.shAniso, base[axis], shiftDirectional, p, d, scale,
                        GI_SEL(weight * da[axis] * da[axis], (floatV)(0.0f), isoLanes), Y0, Y1y, Y1z, Y1x, acc);
#else
  // The three volumes share the stencil: blended per tap pair before one transposition
  // (vox_trilinear_blend3_lanes), as the level-aligned march does.
  vox_trilinear_blend3_lanes(m.aniso, base[0], base[1], base[2], d.x * d.x, d.y * d.y, d.z * d.z, shiftDirectional, p,
                             d, scale, GI_SEL(weight, (floatV)(0.0f), isoLanes), acc);
#endif
}

#ifdef VCT_WINDOW_LOOKUPS
// The rows of vox_level_sample_uniform_lanes by window lookups (VCT_WINDOW_LOOKUPS above), if
// every lane's stencil fits the window (n ≥ 4: the 4 records from x fit in a row); returns whether
// it did. chain + 4·(level6 + k·n3): directional volume k (directional), else the isotropic level
// at chain + bx0.
__attribute__((always_inline)) inline int vct_window_lookup(global const float* chain, int directional, int level6,
                                                            int n3, int shift, int n, float3V d, floatV dx2,
                                                            floatV dy2, floatV dz2, int bx0, const VctStencilV* st,
                                                            RgbaV* acc) {
  int x = clamp(vct_window_start(st->xs, st->xs.s0), 0, n - 4);
  int y[2] = {vct_window_start(st->yr[0], st->yr[0].s0), vct_window_start(st->yr[1], st->yr[1].s0)};
  int z[2] = {vct_window_start(st->zr[0], st->zr[0].s0), vct_window_start(st->zr[1], st->zr[1].s0)};
  intV one = (intV)(1), dx = st->xs - x;
  intV dy[2] = {st->yr[0] - y[0], st->yr[1] - y[1]}, dz[2] = {st->zr[0] - z[0], st->zr[1] - z[1]};
  // (Unsigned: a lane below the window start wraps to a large value.)
  if (!vct_all(as_uint16(dx) <= (uint16)(2) && as_uint16(dy[0]) <= (uint16)(1) && as_uint16(dy[1]) <= (uint16)(1) &&
               as_uint16(dz[0]) <= (uint16)(1) && as_uint16(dz[1]) <= (uint16)(1)))
    return 0;
  intV ox4 = 4 * dx;
#pragma unroll
  for (int row = 0; row < 4; ++row) {
    int yb = row & 1, zb = row >> 1;
    int ya = y[yb], yc = min(ya + 1, n - 1), za = z[zb], zc = min(za + 1, n - 1);
    int o00 = 4 * ((((za << shift) + ya) << shift) + x), o10 = 4 * ((((za << shift) + yc) << shift) + x);
    int o01 = 4 * ((((zc << shift) + ya) << shift) + x), o11 = 4 * ((((zc << shift) + yc) << shift) + x);
    intV idx = ox4 + (dy[yb] << 4), zUpper = dz[zb] == one;
    floatV v[8];
    if (directional) {
      floatV vx[8], vy[8], vz[8];
      global const float* p = chain + 4 * level6;
      int minus = 4 * n3;
      vct_window_axis(p, p + minus, d.x >= 0.0f, o00, o10, o01, o11, idx, zUpper, vx);
      vct_window_axis(p + 2 * minus, p + 3 * minus, d.y >= 0.0f, o00, o10, o01, o11, idx, zUpper, vy);
      vct_window_axis(p + 4 * minus, p + 5 * minus, d.z >= 0.0f, o00, o10, o01, o11, idx, zUpper, vz);
#pragma unroll
      for (int c = 0; c < 8; ++c) v[c] = dx2 * vx[c] + dy2 * vy[c] + dz2 * vz[c];
    } else {
      vct_window_pick(chain + bx0, o00, o10, o01, o11, idx, zUpper, v);
    }
    floatV w0 = st->wFirst * st->wy[yb] * st->wz[zb], w1 = st->wSecond * st->wy[yb] * st->wz[zb];
    vct_add_pair(acc, w0, w1, v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
  }
  return 1;
}
#endif

// acc += level `level` (the same in every lane) seen along d, for the level-aligned march
// (vct_cone_levels_lanes). Radiance voxels at an anisotropic level: the three directional volumes
// facing d share one stencil, and a lookup is linear in the records, so Σ_axis d_axis²·trilinear(V_axis)
// = trilinear(Σ_axis d_axis²·V_axis): each tap pair is blended from the three volumes per lane
// before one transposition (one third of the shuffles of three lookups). Same taps and weights as
// vox_level_sample_lanes; the sums are associated differently (not bit-identical to it).
__attribute__((always_inline)) inline void vox_level_sample_uniform_lanes(VoxelMipsV m, int level, float3V p, float3V d,
                                                                          RgbaV* acc) {
#if GI_VCT_SH
  vox_level_sample_lanes(m, (intV)(level), p, d, (floatV)(1.0f), acc);
#else
  int directional = m.anisotropic && level >= GI_VCT_FIRST_DIRECTIONAL_LEVEL;
  int shift = (31 - clz(m.N)) - level, n = 1 << shift;
  float scale = as_float((uint)(127 - level) << 23);  // 2^−level
  int n3 = 1 << (3 * shift), N3 = m.N * m.N * m.N;
  int offset = (0x09249249 & ((1 << (3 * level)) - 1)) << (3 * shift + 3);  // vox_level_sample_lanes
  int level6 = 6 * (offset - GI_VCT_FIRST_DIRECTIONAL_LEVEL * N3);  // vox_aniso_offset
  // The volumes read, in float-element offsets: the isotropic level (bx only, weight 1), or the
  // directional volume 2·axis (+) or 2·axis + 1 (−) of each axis facing d, weights d_axis².
  global const float* chain = directional ? m.aniso : m.iso;
  intV bx = (intV)(4 * offset), by = bx, bz = bx;
  floatV dx2 = (floatV)(1.0f), dy2 = (floatV)(0.0f), dz2 = dy2;
  if (directional) {
    bx = 4 * (level6 + (0 + GI_SEL((intV)(1), (intV)(0), d.x >= 0.0f)) * n3);
    by = 4 * (level6 + (2 + GI_SEL((intV)(1), (intV)(0), d.y >= 0.0f)) * n3);
    bz = 4 * (level6 + (4 + GI_SEL((intV)(1), (intV)(0), d.z >= 0.0f)) * n3);
    dx2 = d.x * d.x;
    dy2 = d.y * d.y;
    dz2 = d.z * d.z;
  }
  VctStencilV st = vct_stencil_lanes(p, d, (floatV)(scale), (intV)(n));
  intV xs = st.xs, yr[2] = {st.yr[0], st.yr[1]}, zr[2] = {st.zr[0], st.zr[1]};
  floatV wFirst = st.wFirst, wSecond = st.wSecond, wy[2] = {st.wy[0], st.wy[1]}, wz[2] = {st.wz[0], st.wz[1]};
  // At the coarse levels the lanes (neighbouring pixels, same cone of the set) mostly read the
  // same cells of the same volumes: then each row's pairs are loaded once and blended per lane,
  // with no per-lane loads or transposition.
  int x0 = VCT_LANE0(xs), y0 = VCT_LANE0(yr[0]), y1 = VCT_LANE0(yr[1]), z0 = VCT_LANE0(zr[0]), z1 = VCT_LANE0(zr[1]);
  int bx0 = VCT_LANE0(bx), by0 = VCT_LANE0(by), bz0 = VCT_LANE0(bz);
  // (Level 0 is left out: its 1-voxel cells are rarely shared, and the test costs more than it saves.)
  int sameBases = vct_all(bx == bx0 && by == by0 && bz == bz0);
  int sameStencil = level > 0 && vct_all(xs == x0 && yr[0] == y0 && yr[1] == y1 && zr[0] == z0 && zr[1] == z1);
  int shared = sameStencil && sameBases;
  // Lanes with the same stencil whose directions face opposite ways along some axis (an axis
  // nearly in the surface's plane, whose sign the normal map flips from pixel to pixel: ≈ 1/6 of
  // the lookups of levels ≥ 1 on Sponza) read both volumes of every axis once and pick per lane.
  int sharedFacing = directional && sameStencil && !sameBases;
  // One loop over the 4 rows per kind of lookup (not one test per row): the per-lane values only
  // the gather needs are then prepared in its branch alone.
#define VCT_ROWS(...)                                                       \
  _Pragma("unroll") for (int row = 0; row < 4; ++row) {                     \
    int yb = row & 1, zb = row >> 1;                                        \
    floatV w0 = wFirst * wy[yb] * wz[zb], w1 = wSecond * wy[yb] * wz[zb];   \
    floatV r0, g0, b0, a0, r1, g1, b1, a1;                                  \
    int idx0 = 4 * (((((zb ? z1 : z0) << shift) + (yb ? y1 : y0)) << shift) + x0); \
    intV idx = 4 * ((((zr[zb] << shift) + yr[yb]) << shift) + xs);         \
    __VA_ARGS__                                                             \
    vct_add_pair(acc, w0, w1, r0, g0, b0, a0, r1, g1, b1, a1);              \
  }
  if (shared && directional) {
    // Scalar loads (not one vload8 per volume): each value then enters its multiply as a
    // broadcast memory operand, with no shuffle to spread an element of a loaded vector.
    VCT_ROWS(global const float *px = chain + bx0 + idx0, *py = chain + by0 + idx0, *pz = chain + bz0 + idx0;
             r0 = dx2 * px[0] + dy2 * py[0] + dz2 * pz[0]; g0 = dx2 * px[1] + dy2 * py[1] + dz2 * pz[1];
             b0 = dx2 * px[2] + dy2 * py[2] + dz2 * pz[2]; a0 = dx2 * px[3] + dy2 * py[3] + dz2 * pz[3];
             r1 = dx2 * px[4] + dy2 * py[4] + dz2 * pz[4]; g1 = dx2 * px[5] + dy2 * py[5] + dz2 * pz[5];
             b1 = dx2 * px[6] + dy2 * py[6] + dz2 * pz[6]; a1 = dx2 * px[7] + dy2 * py[7] + dz2 * pz[7];)
  } else if (shared) {
    VCT_ROWS(global const float* px = chain + bx0 + idx0; r0 = (floatV)(px[0]); g0 = (floatV)(px[1]);
             b0 = (floatV)(px[2]); a0 = (floatV)(px[3]); r1 = (floatV)(px[4]); g1 = (floatV)(px[5]);
             b1 = (floatV)(px[6]); a1 = (floatV)(px[7]);)
  } else if (sharedFacing) {
    // Volume 2·axis (+) at q, 2·axis + 1 (−) at q + 4·n3: each lane's value is the one the gather
    // would load, blended in the same order (same bits).
    intV facingX = d.x >= 0.0f, facingY = d.y >= 0.0f, facingZ = d.z >= 0.0f;
    int minus = 4 * n3;
#define VCT_FACING(q, k, facing) GI_SEL((floatV)((q)[minus + (k)]), (floatV)((q)[k]), facing)
#define VCT_BLEND_FACING(k) \
  (dx2 * VCT_FACING(qx, k, facingX) + dy2 * VCT_FACING(qy, k, facingY) + dz2 * VCT_FACING(qz, k, facingZ))
    VCT_ROWS(global const float *qx = chain + 4 * level6 + idx0, *qy = qx + 8 * n3, *qz = qy + 8 * n3;
             r0 = VCT_BLEND_FACING(0); g0 = VCT_BLEND_FACING(1); b0 = VCT_BLEND_FACING(2);
             a0 = VCT_BLEND_FACING(3); r1 = VCT_BLEND_FACING(4); g1 = VCT_BLEND_FACING(5);
             b1 = VCT_BLEND_FACING(6); a1 = VCT_BLEND_FACING(7);)
#undef VCT_BLEND_FACING
#undef VCT_FACING
#ifdef VCT_WINDOW_LOOKUPS
  } else if (n >= 4 && vct_window_lookup(chain, directional, level6, n3, shift, n, d, dx2, dy2, dz2, bx0, &st, acc)) {
#endif
  } else if (directional && sameBases) {
    VCT_ROWS(VCT_GATHER_PAIR_BLEND3(chain + bx0, chain + by0, chain + bz0, idx, idx, idx, dx2, dy2, dz2, r0, g0, b0,
                                    a0, r1, g1, b1, a1))
  } else if (directional) {
    VCT_ROWS(VCT_GATHER_PAIR_BLEND3(chain, chain, chain, bx + idx, by + idx, bz + idx, dx2, dy2, dz2, r0, g0, b0, a0,
                                    r1, g1, b1, a1))
  } else {
    VCT_ROWS(VCT_GATHER_PAIR(chain, bx + idx, r0, g0, b0, a0, r1, g1, b1, a1))
  }
#undef VCT_ROWS
#endif
}

// SH voxels: a lookup's radiance clamped at 0 (the l ≤ 1 reconstruction can go negative).
__attribute__((always_inline)) inline void vct_clamp_sh_lanes(RgbaV* c) {
#if GI_VCT_SH
  c->r = fmax(c->r, 0.0f);
  c->g = fmax(c->g, 0.0f);
  c->b = fmax(c->b, 0.0f);
#endif
}

// vox_sample for the lanes: quadrilinear at a fractional level per lane.
inline RgbaV vox_sample_lanes(VoxelMipsV m, float3V p, float3V d, floatV level) {
  level = clamp(level, 0.0f, (float)(m.levels - 1));
  floatV fl = floor(level);
  intV l0 = convert_intV(fl);
  floatV f = level - fl;
  intV second = f > 0.0f && l0 + 1 < m.levels;
  floatV w1 = GI_SEL((floatV)(0.0f), f, second);
  RgbaV c;
  c.r = c.g = c.b = c.a = (floatV)(0.0f);
  vox_level_sample_lanes(m, l0, p, d, 1.0f - w1, &c);
  if (GI_ANY(second)) vox_level_sample_lanes(m, min(l0 + 1, (intV)(m.levels - 1)), p, d, w1, &c);
  vct_clamp_sh_lanes(&c);
  return c;
}

// log2(x) for positive normal x, lane-wise without library calls (PERFORMANCE_FACTS point 4):
// the exponent bits plus the atanh series of the mantissa scaled into [√½, √2); absolute error
// below 1e-7.
inline floatV log2V(floatV x) {
  uintV bits = as_uintV(x);
  intV e = convert_intV(bits >> 23) - 127;
  floatV m = as_floatV((bits & 0x007fffffu) | 0x3f800000u);  // [1, 2)
  intV high = m > 1.41421356f;
  m = GI_SEL(m, 0.5f * m, high);
  e = GI_SEL(e, e + 1, high);
  floatV s = (m - 1.0f) / (m + 1.0f), s2 = s * s;
  return convert_floatV(e) + 2.88539008f * s * (1.0f + s2 * (1.0f / 3.0f + s2 * (0.2f + s2 * (1.0f / 7.0f))));
}

// x^r for x in [0, 1] and r > 0 lane-wise: exp2(r·log2V(x)), exp2 from the exponent bits and a
// Taylor polynomial on [−½, ½]; relative error below 1e-6 (x = 0 gives 2^(−127·r), not 0).
inline floatV pow01V(floatV x, floatV r) {
  floatV y = fmax(r * log2V(x), -126.0f);
  floatV i = floor(y + 0.5f);
  floatV f = (y - i) * 0.693147181f;
  floatV p = 1.0f + f * (1.0f + f * (0.5f + f * (1.0f / 6.0f + f * (1.0f / 24.0f + f * (1.0f / 120.0f + f * (1.0f / 720.0f))))));
  return p * as_floatV(convert_uintV(convert_intV(i) + 127) << 23);
}

// The opacity of sample s corrected for the step, 1 − (1 − α)^(Δt/D) (stepOverDiameter = Δt/D),
// and its ratio to s.a, the factor of the sample's premultiplied radiance: the part of a
// compositing step that does not depend on what is in front (vct_composite_corrected_lanes).
__attribute__((always_inline)) inline void vct_corrected_lanes(RgbaV s, floatV stepOverDiameter, floatV* corrected,
                                                              floatV* perAlpha) {
  floatV alpha = fmin(s.a, 1.0f);
  *corrected = 1.0f - pow01V(1.0f - alpha, stepOverDiameter);
  *perAlpha = *corrected / s.a;
}

// The rest of the compositing step of the lanes where `sampled` (vct_composite_lanes).
__attribute__((always_inline)) inline void vct_composite_corrected_lanes(RgbaV s, intV sampled, floatV corrected,
                                                                        floatV perAlpha, floatV aoFalloff, RgbaV* c,
                                                                        floatV* occ) {
  intV live = sampled && s.a > 1e-6f;
  floatV k = GI_SEL((floatV)(0.0f), (1.0f - c->a) * perAlpha, live);
  c->r += k * s.r;
  c->g += k * s.g;
  c->b += k * s.b;
  *occ += GI_SEL((floatV)(0.0f), (1.0f - *occ) * corrected * aoFalloff, live);
  c->a += GI_SEL((floatV)(0.0f), (1.0f - c->a) * corrected, live);
}

// One front-to-back compositing step of the lanes where `sampled` (vct_cone's): the sample s with
// its opacity corrected for the step, 1 − (1 − α)^(Δt/D) (stepOverDiameter = Δt/D), and the AO
// occlusion weighted by aoFalloff = 1/(1 + λt).
__attribute__((always_inline)) inline void vct_composite_lanes(RgbaV s, intV sampled, floatV stepOverDiameter,
                                                               floatV aoFalloff, RgbaV* c, floatV* occ) {
  floatV corrected, perAlpha;
  vct_corrected_lanes(s, stepOverDiameter, &corrected, &perAlpha);
  vct_composite_corrected_lanes(s, sampled, corrected, perAlpha, aoFalloff, c, occ);
}

// vct_footprint lane-wise; the largest power of two ≤ the bound by clearing its mantissa.
inline floatV vct_footprint_lanes(floatV tanHalf, floatV t, float h0, floatV cosN) {
  floatV bound = (h0 + t * cosN - 1.0f) * (1.0f / 1.5f);
  floatV cap = GI_SEL((floatV)(1.0f), as_floatV(as_uintV(bound) & 0xff800000u), bound >= 1.0f);
  return fmax(1.0f, fmin(2.0f * tanHalf * t, cap));
}

#if GI_VW == 16
#define VCT_UCHARV uchar16
#elif GI_VW == 8
#define VCT_UCHARV uchar8
#else
#define VCT_UCHARV uchar
#endif

// Whether the lookup vox_sample_lanes(m, p, d, log2V(diameter)) reads only exactly empty cells, per
// lane, by the empty-space map (voxel_light.cl, vct_empty_space). The trilinear taps of a level lie
// inside those of the next coarser one (taps i0, i0 + 1 of level l with i0 = ⌊u − ½⌋, u = p/2^l, lie
// in the cells 2·i1 … 2·i1 + 3 of level l, i1 = ⌊u/2 − ½⌋), so the map at the first tap of a level at
// least as coarse as the lookup's coarser level decides: ⌈log2 D⌉ from the float's bits (log2V never
// rounds above it), clamped to the chain as the lookup's level is. Taps outside the volume weigh 0
// (a first tap < 0 or ≥ n is clamped into the volume, which can only find more cells occupied).
// Where it says empty, the lookup's α is exactly 0 and vct_composite_lanes changes nothing.
__attribute__((always_inline)) inline intV vct_lookup_empty_lanes(VoxelMipsV m, global const uchar* emptySpace,
                                                                  float3V p, floatV diameter) {
  uintV bits = as_uintV(diameter);  // ≥ 1
  intV top = convert_intV(bits >> 23) - 127 + GI_SEL((intV)(0), (intV)(1), (bits & 0x007fffffu) != 0u);
  top = min(top, (intV)(m.levels - 1));
  intV shift = (31 - clz(m.N)) - top;
  floatV scale = as_floatV(convert_uintV(127 - top) << 23);  // 2^−top
  intV zero = (intV)(0), last = ((intV)(1) << shift) - 1;
  intV ix = min(max(convert_intV(floor(p.x * scale - 0.5f)), zero), last);
  intV iy = min(max(convert_intV(floor(p.y * scale - 0.5f)), zero), last);
  intV iz = min(max(convert_intV(floor(p.z * scale - 0.5f)), zero), last);
  intV offset = ((intV)(0x09249249) & (((intV)(1) << (3 * top)) - 1)) << (3 * shift + 3);  // vox_level_sample_lanes
  intV cell = offset + ((((iz << shift) + iy) << shift) + ix);
  return convert_intV(GI_GATHER(VCT_UCHARV, emptySpace, cell)) == 0;
}

// vct_cone for GI_VW cones from o along d, of half-angle tan tanHalf, whose axes make cosine cosN
// with their surfaces' normals: radiance (r, g, b) and opacity a arriving along them, and the AO
// occlusion. A lane whose step needs no lookup — below the footprint-in-front height, or (with an
// empty-space map; 0: none) a lookup of only empty cells, whose α = 0 composites nothing — takes
// its next steps at once, until every lane is done or at a step to sample: each lane's steps,
// samples and sums are those of vct_cone, only the lookups of empty space are left out.
inline RgbaV vct_cone_lanes(VoxelMipsV m, global const uchar* emptySpace, float3V o, float3V d, floatV tanHalf,
                            float maxDistance, float stepFactor, float aoLambda, float h0, floatV cosN,
                            floatV* occlusion) {
  RgbaV c;
  c.r = c.g = c.b = c.a = (floatV)(0.0f);
  floatV occ = (floatV)(0.0f);
  intV done = (intV)(0);
  floatV t = (floatV)(0.0f), step = t;
  floatV diameter = vct_footprint_lanes(tanHalf, t, h0, cosN);  // at t (vct_cone_advance's first footprint)
  float3V p;
  intV sampled;
  float limit = (float)m.N;
  for (;;) {
    for (intV advance = GI_NOT(done);;) {
      // vct_cone_advance of the lanes in `advance`; the others keep their t (and so their p,
      // diameter and state).
      floatV stepNext = fmax(0.5f, stepFactor * diameter);
      step = GI_SEL(step, stepNext, advance);
      t = GI_SEL(t, t + stepNext, advance);
      diameter = vct_footprint_lanes(tanHalf, t, h0, cosN);
      floatV margin = 0.5f * diameter;
      p = addV(o, scaleV(d, t));
      done = done || t > maxDistance || p.x < -margin || p.y < -margin || p.z < -margin || p.x > limit + margin ||
             p.y > limit + margin || p.z > limit + margin;
      // Footprint in front: nothing sampled below h = 2.5 voxels.
      sampled = GI_NOT(done) && h0 + t * cosN - 1.0f >= 1.5f;
      advance = GI_NOT(done || sampled);
      if (emptySpace) advance = advance || (sampled && vct_lookup_empty_lanes(m, emptySpace, p, diameter));
      if (!GI_ANY(advance)) break;
    }
    if (GI_ALL(done)) break;
    RgbaV s = vox_sample_lanes(m, p, d, log2V(diameter));
    vct_composite_lanes(s, sampled, step / diameter, 1.0f / (1.0f + aoLambda * t), &c, &occ);
    done = done || c.a >= 0.99f;
  }
  *occlusion = occ;
  return c;
}

// vct_cone_levels for GI_VW cones of one half-angle (the diffuse set): every lane has the same
// distances, levels and steps, so the schedule is scalar and each step is one trilinear lookup per
// lane (one level, uniform across the lanes).
// The steps run in chunks of VCT_LEVEL_CHUNK: first the chunk's lookups back to back (a lookup does
// not depend on the compositing, only on the position), then their compositing. Compositing one
// step right after its lookup put the long dependent chain of (1 − α)^(Δt/D) (log2, exp2, two
// divisions) between every two lookups; grouped, the chains of the chunk's steps overlap. Same
// operations per lane as stepping one at a time (same bits): a lane that left the grid is masked
// from that step on, and one saturated in a chunk's compositing is masked from there on (the
// chunk's remaining lookups are wasted for it; the march still ends when every lane is done).
#define VCT_LEVEL_CHUNK 4
inline RgbaV vct_cone_levels_lanes(VoxelMipsV m, float3V o, float3V d, float tanHalf, float maxDistance,
                                   float aoLambda, floatV* occlusion) {
  RgbaV c;
  c.r = c.g = c.b = c.a = (floatV)(0.0f);
  floatV occ = (floatV)(0.0f);
  intV done = (intV)(0);
  float tPrevious = 0.0f, limit = (float)m.N;
  float diameter = 1.0f;
  int level = 0, more = 1;
  while (more) {
    RgbaV s[VCT_LEVEL_CHUNK];
    intV doneAt[VCT_LEVEL_CHUNK];
    float stepOverDiameter[VCT_LEVEL_CHUNK], aoFalloff[VCT_LEVEL_CHUNK];
    int count = 0;
    intV left = done;  // lanes done before each lookup (left the grid, or saturated in an earlier chunk)
    for (; count < VCT_LEVEL_CHUNK; ++count, ++level, diameter *= 2.0f) {
      float t = diameter * (0.5f / tanHalf);
      if (t > maxDistance) {
        more = 0;
        break;
      }
      float step = t - tPrevious;
      tPrevious = t;
      float margin = 0.5f * diameter;
      float3V p = addV(o, scaleV(d, (floatV)(t)));
      left = left || p.x < -margin || p.y < -margin || p.z < -margin || p.x > limit + margin ||
             p.y > limit + margin || p.z > limit + margin;
      if (vct_all(left)) {
        more = 0;
        break;
      }
      s[count].r = s[count].g = s[count].b = s[count].a = (floatV)(0.0f);
      vox_level_sample_uniform_lanes(m, min(level, m.levels - 1), p, d, &s[count]);
      vct_clamp_sh_lanes(&s[count]);
      doneAt[count] = left;
      stepOverDiameter[count] = step / diameter;
      aoFalloff[count] = 1.0f / (1.0f + aoLambda * t);
    }
    // The corrected opacities of the chunk's samples first (independent of each other: their
    // long chains of log2, exp2 and divisions overlap), then the dependent compositing.
    floatV corrected[VCT_LEVEL_CHUNK], perAlpha[VCT_LEVEL_CHUNK];
    for (int k = 0; k < count; ++k)
      vct_corrected_lanes(s[k], (floatV)(stepOverDiameter[k]), &corrected[k], &perAlpha[k]);
    for (int k = 0; k < count; ++k) {
      done = done || doneAt[k];
      vct_composite_corrected_lanes(s[k], GI_NOT(done), corrected[k], perAlpha[k], (floatV)(aoFalloff[k]), &c, &occ);
      done = done || c.a >= 0.99f;
    }
    if (vct_all(done)) break;
  }
  *occlusion = occ;
  return c;
}

// The largest lane of v.
#if GI_VW == 16
inline int vct_max_lanes(int16 v) {
  int8 a = max(v.lo, v.hi);
  int4 b = max(a.lo, a.hi);
  int2 c = max(b.lo, b.hi);
  return max(c.x, c.y);
}
#elif GI_VW == 8
inline int vct_max_lanes(int8 v) {
  int4 b = max(v.lo, v.hi);
  int2 c = max(b.lo, b.hi);
  return max(c.x, c.y);
}
#else
inline int vct_max_lanes(int v) { return v; }
#endif

// Composites a chunk's `count` samples in order: s[k] where sampled[k] and the lane is not yet
// saturated, which is noted in *saturated (a ≥ 0.99).
__attribute__((always_inline)) inline void vct_composite_chunk_lanes(RgbaV* s, intV* sampled, floatV* stepOverDiameter,
                                                                     floatV* aoFalloff, int count, RgbaV* c,
                                                                     floatV* occ, intV* saturated) {
  for (int k = 0; k < count; ++k) {
    vct_composite_lanes(s[k], sampled[k] && GI_NOT(*saturated), stepOverDiameter[k], aoFalloff[k], c, occ);
    *saturated = *saturated || c->a >= 0.99f;
  }
}

// vct_cone_levels (cone.h: each sample reads one level, the cone's diameter rounded up to a power
// of two, in sub-steps of at most max(½, stepFactor·2^l) voxels) for GI_VW cones of their own
// half-angles (the specular cones, vct.specular_steps=levels). Each lane walks its own sequence of
// levels and sub-steps; a lookup reads one level per lane (vox_level_sample_lanes; lanes at level 0
// read the isotropic level 0 (unless the voxels are directional), the others the directional
// volumes of their levels, so a step whose lanes straddle both does both lookups) instead of the two levels of the
// continuous march's quadrilinear lookups. As in vct_cone_levels_lanes, the lookups run in chunks
// of VCT_LEVEL_CHUNK, then their compositing (a lane saturated in a chunk is masked from there
// on). Each lane's samples and sums are those of vct_cone_levels. No empty-space skip: with
// one-level lookups the map tests and extra stepping passes cost what the skipped lookups saved
// (docs/PERFORMANCE.md, "Level-aligned specular cone").
inline RgbaV vct_cone_levels_varying_lanes(VoxelMipsV m, float3V o, float3V d, floatV tanHalf, float maxDistance, float stepFactor, float aoLambda,
                                           floatV* occlusion) {
  RgbaV c;
  c.r = c.g = c.b = c.a = (floatV)(0.0f);
  floatV occ = (floatV)(0.0f);
  intV left = (intV)(0), saturated = left;  // left: past the maximum distance or out of the grid
  float limit = (float)m.N;
  // Per lane: its level, diameter 2^level, the level's segment (tStart, tEnd], its sub-steps of
  // length delta (the last ends at tEnd exactly), the sub-step j taken last, and its distance t.
  floatV tUnit = 0.5f / tanHalf, diameter = (floatV)(1.0f);
  intV level = (intV)(0);
  floatV tEnd = diameter * tUnit, tStart = (floatV)(0.0f);
  floatV steps = fmax(1.0f, ceil((tEnd - tStart) / fmax(0.5f, stepFactor * diameter)));
  floatV delta = (tEnd - tStart) / steps, j = (floatV)(0.0f), t = (floatV)(0.0f), tPrevious = t;
  float3V p;
  RgbaV s[VCT_LEVEL_CHUNK];
  intV sampledAt[VCT_LEVEL_CHUNK];
  floatV stepOverDiameter[VCT_LEVEL_CHUNK], aoFalloff[VCT_LEVEL_CHUNK];
  int count = 0;
  while (!vct_all(left || saturated)) {
    // The next sample of every lane not done: the next sub-step, or the first of the next level.
    intV advance = GI_NOT(left || saturated);
    intV nextLevel = advance && j + 1.0f > steps;
    if (GI_ANY(nextLevel)) {  // (most steps stay within the lanes' levels: no divisions)
      level = GI_SEL(level, level + 1, nextLevel);
      diameter = GI_SEL(diameter, 2.0f * diameter, nextLevel);
      tEnd = GI_SEL(tEnd, diameter * tUnit, nextLevel);
      tStart = GI_SEL(tStart, 0.5f * tEnd, nextLevel);
      steps = GI_SEL(steps, fmax(1.0f, ceil((tEnd - tStart) / fmax(0.5f, stepFactor * diameter))), nextLevel);
      delta = GI_SEL(delta, (tEnd - tStart) / steps, nextLevel);
    }
    j = GI_SEL(j, GI_SEL(j + 1.0f, (floatV)(1.0f), nextLevel), advance);
    tPrevious = GI_SEL(tPrevious, t, advance);
    t = GI_SEL(t, GI_SEL(tStart + j * delta, tEnd, j == steps), advance);
    p = addV(o, scaleV(d, t));
    floatV margin = 0.5f * diameter;
    left = left || (advance && (t > maxDistance || p.x < -margin || p.y < -margin || p.z < -margin ||
                                p.x > limit + margin || p.y > limit + margin || p.z > limit + margin));
    intV sampled = GI_NOT(left || saturated);
    if (!GI_ANY(sampled)) break;
    // Lanes that are done look up the highest level of a sampled lane (weight irrelevant: masked in
    // the compositing), so that they add no lookup of a level no sampled lane needs.
    intV lookupLevel = min(GI_SEL((intV)(vct_max_lanes(GI_SEL((intV)(0), level, sampled))), level, sampled),
                           (intV)(m.levels - 1));
    s[count].r = s[count].g = s[count].b = s[count].a = (floatV)(0.0f);
    vox_level_sample_lanes(m, lookupLevel, p, d, (floatV)(1.0f), &s[count]);
    vct_clamp_sh_lanes(&s[count]);
    sampledAt[count] = sampled;
    stepOverDiameter[count] = (t - tPrevious) / diameter;
    aoFalloff[count] = 1.0f / (1.0f + aoLambda * t);
    if (++count == VCT_LEVEL_CHUNK) {
      vct_composite_chunk_lanes(s, sampledAt, stepOverDiameter, aoFalloff, count, &c, &occ, &saturated);
      count = 0;
    }
  }
  vct_composite_chunk_lanes(s, sampledAt, stepOverDiameter, aoFalloff, count, &c, &occ, &saturated);
  *occlusion = occ;
  return c;
}

#ifdef VCT_CONE_COUNT
// vct_diffuse_irradiance for GI_VW surface points p with normals n: irradiance (r, g, b) and, in
// a, the AO visibility.
inline RgbaV vct_diffuse_irradiance_lanes(VoxelMipsV m, float3V p, float3V n, float startOffset, float maxDistance,
                                          float stepFactor, float aoLambda, int footprintInFront, int levelSteps) {
  // orthonormal_basis (common/math.h) lane-wise.
  floatV s = GI_SEL((floatV)(-1.0f), (floatV)(1.0f), n.z >= 0.0f);
  floatV a = -1.0f / (s + n.z);
  floatV c = n.x * n.y * a;
  float3V t = f3v(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
  float3V b = f3v(c, s + n.y * n.y * a, -n.y);
  float3V o = addV(p, scaleV(n, (floatV)(startOffset)));
  RgbaV E;
  E.r = E.g = E.b = (floatV)(0.0f);
  floatV occlusion = (floatV)(0.0f);
  for (int i = 0; i < VCT_CONE_COUNT; ++i) {
    float4 cone = VCT_CONES[i];
    float3V d = addV(addV(scaleV(t, (floatV)(cone.x)), scaleV(b, (floatV)(cone.y))), scaleV(n, (floatV)(cone.z)));
    d = scaleV(d, rsqrt(dotV(d, d)));
    floatV occ;
    RgbaV r = levelSteps && !footprintInFront
                  ? vct_cone_levels_lanes(m, o, d, VCT_DIFFUSE_TAN_HALF, maxDistance, aoLambda, &occ)
                  : vct_cone_lanes(m, 0, o, d, (floatV)(VCT_DIFFUSE_TAN_HALF), maxDistance, stepFactor, aoLambda,
                                   footprintInFront ? startOffset : INFINITY, (floatV)(cone.z), &occ);
    E.r += cone.w * r.r;
    E.g += cone.w * r.g;
    E.b += cone.w * r.b;
    occlusion += cone.w * GI_INV_PI * occ;
  }
  E.a = 1.0f - occlusion;
  return E;
}
#endif
