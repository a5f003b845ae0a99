// One kernel source for CPUs and GPUs (PERFORMANCE_FACTS.md): a work-item handles GI_VW adjacent
// pixels through explicit vector types. GI_VW = 16 on CPU devices (PoCL turns float16 into
// AVX-512 code, while a loop inside a one-pixel work-item stays scalar), 1 on GPUs (one pixel
// per work-item, the GPU way). The host passes GI_VW as a build define.
#pragma once

#ifndef GI_VW
#define GI_VW 1
#endif

#if GI_VW == 16
typedef float16 floatV;
typedef int16 intV;
typedef uint16 uintV;
typedef long16 longV;
typedef ulong16 ulongV;
#define GI_LANES (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)
#define convert_floatV convert_float16
#define convert_intV convert_int16
#define convert_longV convert_long16
#define convert_ulongV convert_ulong16
#define as_uintV as_uint16
#define as_intV as_int16
#define as_floatV as_float16
#define convert_uintV convert_uint16
#define vloadV vload16
#define vstoreV vstore16
#define GI_ANY(m) any(m)
#define GI_ALL(m) all(m)
#define GI_GATHER(V, p, i)                                                                                    \
  ((V)((p)[(i).s0], (p)[(i).s1], (p)[(i).s2], (p)[(i).s3], (p)[(i).s4], (p)[(i).s5], (p)[(i).s6],     \
             (p)[(i).s7], (p)[(i).s8], (p)[(i).s9], (p)[(i).sa], (p)[(i).sb], (p)[(i).sc], (p)[(i).sd],     \
             (p)[(i).se], (p)[(i).sf]))
// GI_VW float4 values (array of structures) <-> four floatV (structure of arrays).
#define GI_AOS4_LOAD(p, X, Y, Z, W)                                                                    \
  {                                                                                                    \
    float16 a_ = vload16(0, p), b_ = vload16(1, p), c_ = vload16(2, p), d_ = vload16(3, p);            \
    X = (float16)(a_.s048c, b_.s048c, c_.s048c, d_.s048c);                                             \
    Y = (float16)(a_.s159d, b_.s159d, c_.s159d, d_.s159d);                                             \
    Z = (float16)(a_.s26ae, b_.s26ae, c_.s26ae, d_.s26ae);                                             \
    W = (float16)(a_.s37bf, b_.s37bf, c_.s37bf, d_.s37bf);                                             \
  }
#define GI_AOS4_STORE(p, X, Y, Z, W)                                                                         \
  {                                                                                                          \
    vstore16((float16)(X.s0, Y.s0, Z.s0, W.s0, X.s1, Y.s1, Z.s1, W.s1, X.s2, Y.s2, Z.s2, W.s2, X.s3, Y.s3,   \
                       Z.s3, W.s3), 0, p);                                                                   \
    vstore16((float16)(X.s4, Y.s4, Z.s4, W.s4, X.s5, Y.s5, Z.s5, W.s5, X.s6, Y.s6, Z.s6, W.s6, X.s7, Y.s7,   \
                       Z.s7, W.s7), 1, p);                                                                   \
    vstore16((float16)(X.s8, Y.s8, Z.s8, W.s8, X.s9, Y.s9, Z.s9, W.s9, X.sa, Y.sa, Z.sa, W.sa, X.sb, Y.sb,   \
                       Z.sb, W.sb), 2, p);                                                                   \
    vstore16((float16)(X.sc, Y.sc, Z.sc, W.sc, X.sd, Y.sd, Z.sd, W.sd, X.se, Y.se, Z.se, W.se, X.sf, Y.sf,   \
                       Z.sf, W.sf), 3, p);                                                                   \
  }
// Four consecutive 32-bit words per lane (T = float, int or uint; p a pointer to T; i the lanes'
// element offsets) -> four T##16 planes X, Y, Z, W (word 0..3): one 128-bit load per lane and
// the transposition of GI_AOS4_LOAD, instead of four scalar gathers (64 loads with as many
// element inserts, the cost that dominated the resolve and gather passes).
#define GI_GATHER_SPAN4(T, p, i, X, Y, Z, W)                                                                 \
  {                                                                                                          \
    T##16 a_ = (T##16)(vload4(0, (p) + (i).s0), vload4(0, (p) + (i).s1), vload4(0, (p) + (i).s2),           \
                       vload4(0, (p) + (i).s3));                                                             \
    T##16 b_ = (T##16)(vload4(0, (p) + (i).s4), vload4(0, (p) + (i).s5), vload4(0, (p) + (i).s6),           \
                       vload4(0, (p) + (i).s7));                                                             \
    T##16 c_ = (T##16)(vload4(0, (p) + (i).s8), vload4(0, (p) + (i).s9), vload4(0, (p) + (i).sa),           \
                       vload4(0, (p) + (i).sb));                                                             \
    T##16 d_ = (T##16)(vload4(0, (p) + (i).sc), vload4(0, (p) + (i).sd), vload4(0, (p) + (i).se),           \
                       vload4(0, (p) + (i).sf));                                                             \
    X = (T##16)(a_.s048c, b_.s048c, c_.s048c, d_.s048c);                                                     \
    Y = (T##16)(a_.s159d, b_.s159d, c_.s159d, d_.s159d);                                                     \
    Z = (T##16)(a_.s26ae, b_.s26ae, c_.s26ae, d_.s26ae);                                                     \
    W = (T##16)(a_.s37bf, b_.s37bf, c_.s37bf, d_.s37bf);                                                     \
  }
// Two consecutive words per lane: one 64-bit load per lane.
#define GI_GATHER_SPAN2(T, p, i, X, Y)                                                                       \
  {                                                                                                          \
    T##16 a_ = (T##16)(vload2(0, (p) + (i).s0), vload2(0, (p) + (i).s1), vload2(0, (p) + (i).s2),           \
                       vload2(0, (p) + (i).s3), vload2(0, (p) + (i).s4), vload2(0, (p) + (i).s5),           \
                       vload2(0, (p) + (i).s6), vload2(0, (p) + (i).s7));                                    \
    T##16 b_ = (T##16)(vload2(0, (p) + (i).s8), vload2(0, (p) + (i).s9), vload2(0, (p) + (i).sa),           \
                       vload2(0, (p) + (i).sb), vload2(0, (p) + (i).sc), vload2(0, (p) + (i).sd),           \
                       vload2(0, (p) + (i).se), vload2(0, (p) + (i).sf));                                    \
    X = (T##16)(a_.even, b_.even);                                                                           \
    Y = (T##16)(a_.odd, b_.odd);                                                                             \
  }
#elif GI_VW == 8
typedef float8 floatV;
typedef int8 intV;
typedef uint8 uintV;
typedef long8 longV;
typedef ulong8 ulongV;
#define GI_LANES (int8)(0, 1, 2, 3, 4, 5, 6, 7)
#define convert_floatV convert_float8
#define convert_intV convert_int8
#define convert_longV convert_long8
#define convert_ulongV convert_ulong8
#define as_uintV as_uint8
#define as_intV as_int8
#define as_floatV as_float8
#define convert_uintV convert_uint8
#define vloadV vload8
#define vstoreV vstore8
#define GI_ANY(m) any(m)
#define GI_ALL(m) all(m)
#define GI_GATHER(V, p, i) \
  ((V)((p)[(i).s0], (p)[(i).s1], (p)[(i).s2], (p)[(i).s3], (p)[(i).s4], (p)[(i).s5], (p)[(i).s6], (p)[(i).s7]))
#define GI_AOS4_LOAD(p, X, Y, Z, W)                                  \
  {                                                                  \
    float16 a_ = vload16(0, p), b_ = vload16(1, p);                  \
    X = (float8)(a_.s048c, b_.s048c);                                \
    Y = (float8)(a_.s159d, b_.s159d);                                \
    Z = (float8)(a_.s26ae, b_.s26ae);                                \
    W = (float8)(a_.s37bf, b_.s37bf);                                \
  }
#define GI_AOS4_STORE(p, X, Y, Z, W)                                                                         \
  {                                                                                                          \
    vstore16((float16)(X.s0, Y.s0, Z.s0, W.s0, X.s1, Y.s1, Z.s1, W.s1, X.s2, Y.s2, Z.s2, W.s2, X.s3, Y.s3,   \
                       Z.s3, W.s3), 0, p);                                                                   \
    vstore16((float16)(X.s4, Y.s4, Z.s4, W.s4, X.s5, Y.s5, Z.s5, W.s5, X.s6, Y.s6, Z.s6, W.s6, X.s7, Y.s7,   \
                       Z.s7, W.s7), 1, p);                                                                   \
  }
#define GI_GATHER_SPAN4(T, p, i, X, Y, Z, W)                                                         \
  {                                                                                                  \
    T##16 a_ = (T##16)(vload4(0, (p) + (i).s0), vload4(0, (p) + (i).s1), vload4(0, (p) + (i).s2),   \
                       vload4(0, (p) + (i).s3));                                                     \
    T##16 b_ = (T##16)(vload4(0, (p) + (i).s4), vload4(0, (p) + (i).s5), vload4(0, (p) + (i).s6),   \
                       vload4(0, (p) + (i).s7));                                                     \
    X = (T##8)(a_.s048c, b_.s048c);                                                                  \
    Y = (T##8)(a_.s159d, b_.s159d);                                                                  \
    Z = (T##8)(a_.s26ae, b_.s26ae);                                                                  \
    W = (T##8)(a_.s37bf, b_.s37bf);                                                                  \
  }
#define GI_GATHER_SPAN2(T, p, i, X, Y)                                                               \
  {                                                                                                  \
    T##16 a_ = (T##16)(vload2(0, (p) + (i).s0), vload2(0, (p) + (i).s1), vload2(0, (p) + (i).s2),   \
                       vload2(0, (p) + (i).s3), vload2(0, (p) + (i).s4), vload2(0, (p) + (i).s5),   \
                       vload2(0, (p) + (i).s6), vload2(0, (p) + (i).s7));                            \
    X = a_.even;                                                                                     \
    Y = a_.odd;                                                                                      \
  }
#elif GI_VW == 1
typedef float floatV;
typedef int intV;
typedef uint uintV;
typedef long longV;
typedef ulong ulongV;
#define GI_LANES 0
#define convert_floatV convert_float
#define convert_intV convert_int
#define convert_longV convert_long
#define convert_ulongV convert_ulong
#define as_uintV as_uint
#define as_intV as_int
#define as_floatV as_float
#define convert_uintV convert_uint
#define vloadV(i, p) ((p)[i])
#define vstoreV(v, i, p) ((p)[i] = (v))
#define GI_ANY(m) (m)
#define GI_ALL(m) (m)
#define GI_GATHER(V, p, i) ((V)((p)[i]))
#define GI_AOS4_LOAD(p, X, Y, Z, W) \
  {                                 \
    float4 v_ = vload4(0, p);       \
    X = v_.x;                       \
    Y = v_.y;                       \
    Z = v_.z;                       \
    W = v_.w;                       \
  }
#define GI_AOS4_STORE(p, X, Y, Z, W) \
  { vstore4((float4)(X, Y, Z, W), 0, p); }
#define GI_GATHER_SPAN4(T, p, i, X, Y, Z, W) \
  {                                          \
    T##4 v_ = vload4(0, (p) + (i));          \
    X = v_.x;                                \
    Y = v_.y;                                \
    Z = v_.z;                                \
    W = v_.w;                                \
  }
#define GI_GATHER_SPAN2(T, p, i, X, Y) \
  {                                    \
    T##2 v_ = vload2(0, (p) + (i));    \
    X = v_.x;                          \
    Y = v_.y;                          \
  }
#else
#error "GI_VW must be 1, 8 or 16"
#endif

// Per-lane records of 4 (or 2) words: record i of p (float4/int4/uint4 or float2 arrays viewed
// as T arrays) -> planes X, Y, Z, W (word 0..3).
#define GI_GATHER_AOS4(T, p, i, X, Y, Z, W) GI_GATHER_SPAN4(T, p, ((i) * 4), X, Y, Z, W)
#define GI_GATHER_AOS2(T, p, i, X, Y) GI_GATHER_SPAN2(T, p, ((i) * 2), X, Y)

// Lane-wise helpers (structure of arrays). GI_SEL(a, b, c): b where c is true, else a.
// GI_NOT(m): the lanes where the mask m (an intV of comparisons: 0 / −1 per lane, 0 / 1 at GI_VW 1)
// is false, for a mask that is not one comparison (e.g. a loop's `done`; a comparison is negated
// by writing the opposite one, `a != b`, not `!(a == b)`). Not `!m`, for Oclgrind (README,
// "Development notes"): it keeps a vector comparison's true as the byte 0xff per lane and an i1
// constant's as 1, and clang lowers `!m` (also `m == 0`) to an xor of the <N x i1> mask with a
// `true` vector, which it evaluates to 0xfe / 0x01 (−2 / 1 per lane, both true to a branch).
// select() is a call there, which the optimiser leaves alone. For the same reason no mask is a
// constant (an all-true `(intV)(-1)` mask selected against comparisons: 1 per lane) or one
// comparison of two values that are the same in every lane (evaluated once, broadcast: 1 per
// lane), and masks are counted with GI_SEL(n, n + 1, m), not `n -= m` (an add of the mask's
// zero-extension: 255 per lane). docs/PERFORMANCE.md, "Oclgrind's lane masks".
#if GI_VW == 1
#define GI_SEL(a, b, c) ((c) ? (b) : (a))
#define GI_NOT(m) (!(m))
#else
#define GI_SEL(a, b, c) select(a, b, c)
#define GI_NOT(m) select((intV)(-1), (intV)(0), m)
#endif

// Stores the first `valid` lanes of v (lane type T: float, int or uint) at p[i …]: one vector
// store where all GI_VW lanes are valid, else through a private array (the last work-item of a
// row may hold fewer pixels than lanes).
#define GI_STORE_LANES(T, v, p, i, valid)                               \
  {                                                                     \
    if ((valid) == GI_VW) {                                             \
      vstoreV(v, 0, (p) + (i));                                         \
    } else {                                                            \
      T lanes_[GI_VW];                                                  \
      vstoreV(v, 0, lanes_);                                            \
      for (int l_ = 0; l_ < (valid); ++l_) (p)[(i) + l_] = lanes_[l_]; \
    }                                                                   \
  }

typedef struct {
  floatV x, y, z;
} float3V;

typedef struct {
  floatV x, y, z, w;
} float4V;

// The largest of the lanes' values.
inline int lane_max_int(intV v) {
#if GI_VW == 1
  return v;
#else
  int lv[GI_VW];
  vstoreV(v, 0, lv);
  int m = lv[0];
  for (int l = 1; l < GI_VW; ++l) m = max(m, lv[l]);
  return m;
#endif
}

inline float3V f3v(floatV x, floatV y, floatV z) {
  float3V r;
  r.x = x;
  r.y = y;
  r.z = z;
  return r;
}
inline floatV dotV(float3V a, float3V b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float3V addV(float3V a, float3V b) { return f3v(a.x + b.x, a.y + b.y, a.z + b.z); }
inline float3V subV(float3V a, float3V b) { return f3v(a.x - b.x, a.y - b.y, a.z - b.z); }
inline float3V scaleV(float3V a, floatV s) { return f3v(a.x * s, a.y * s, a.z * s); }
inline float3V negV(float3V a) { return f3v(-a.x, -a.y, -a.z); }
inline float3V crossV(float3V a, float3V b) {
  return f3v(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
inline float3V selV(float3V a, float3V b, intV c) {
  return f3v(GI_SEL(a.x, b.x, c), GI_SEL(a.y, b.y, c), GI_SEL(a.z, b.z, c));
}
// safe_normalize() lane-wise.
inline float3V safe_normalizeV(float3V v, float3V fallback) {
  floatV l2 = dotV(v, v);
  return selV(fallback, scaleV(v, rsqrt(l2)), l2 > 1e-30f);
}
