// Reading a light-field probe grid (McGuire et al. 2017, "Real-time global illumination using
// precomputed light field probes", as seed 004 §4 implemented its "irradiance with filtered
// visibility"; ALGORITHMS.md §6): octahedral mapping, bilinear map lookups, and the irradiance at
// a surface point blended from its 8 surrounding probes with
//   - a backface term of cosθ = n · (p_probe − x)/|p_probe − x|: DDGI's smooth weight
//     ((cosθ + 1)/2)² + 0.2 (Majercik et al. 2019) with GI_PROBE_BACKFACE_SMOOTH = 1, else seed
//     004's eq. 7, max(0, cosθ), but at least grid.backface_floor (else a point facing away from
//     all 8 probes, e.g. a wall between the outermost probes and the bounds, would get no light),
//   - Chebyshev visibility from the probe's filtered distance (mean μ, mean² of the distance):
//     with r the distance from the probe to the (biased) point, r ≤ μ is visible, else
//     σ² / (σ² + (r − μ)²), σ² = |mean² − μ²|, raised to GI_PROBE_CHEBYSHEV_POWER (DDGI's
//     sharpening; 0 = no visibility),
//   - with GI_PROBE_CRUSH = 1, DDGI's crush of the product w = backface × visibility: w below
//     t = GI_PROBE_CRUSH_THRESHOLD becomes w³/t² (Chebyshev's soft tail, the per cent or so it
//     lets through a thin wall, is cut further), w first at least 1e-6 (a pixel whose probes are
//     all hidden still blends them by position),
//   - trilinear weights over the probe cell (after the crush: the crush judges visibility alone),
//   - the probe's state (probe_types.h): 0 for a probe classified as inside geometry;
// and the weights renormalised. With GI_PROBE_PERCEPTUAL_BLEND = 1 the probes' irradiance is
// blended as √E (DDGI's blending "in a more perceptual space": the maps read hold √E; the sum is
// squared). The GI_PROBE_* switches are build defines (probes.chebyshev_power,
// probes.backface, probes.crush, probes.perceptual_blend; read at setup): no run-time branch in
// the shading's per-probe arithmetic (as run-time switches they cost 3–5 % of the shading).
// The backface and visibility terms look from the probe's relocated position (grid point +
// offset); the trilinear weights use the grid cell. Layouts: probe_types.h.
#pragma once
#include "common/math.h"
#include "gi/probes/probe_types.h"

#ifndef GI_PROBE_CHEBYSHEV_POWER
#define GI_PROBE_CHEBYSHEV_POWER 3  // probes.chebyshev_power
#endif
#ifndef GI_PROBE_BACKFACE_SMOOTH
#define GI_PROBE_BACKFACE_SMOOTH 1  // probes.backface: 1 smooth (DDGI), 0 eq7 (seed 004)
#endif
#ifndef GI_PROBE_CRUSH
#define GI_PROBE_CRUSH 1                // probes.crush > 0
#define GI_PROBE_CRUSH_THRESHOLD 0.2f  // probes.crush
#endif
#ifndef GI_PROBE_PERCEPTUAL_BLEND
#define GI_PROBE_PERCEPTUAL_BLEND 0  // probes.perceptual_blend
#endif

inline float probe_sign_not_zero(float v) { return v >= 0.0f ? 1.0f : -1.0f; }

// Seed 004 Algorithm 1: unit direction -> octahedral coordinates in [-1, 1]².
inline float2 probe_oct_encode(float3 v) {
  float l1 = fabs(v.x) + fabs(v.y) + fabs(v.z);
  float2 p = (float2)(v.x, v.y) / l1;
  if (v.z < 0.0f)
    p = (float2)((1.0f - fabs(p.y)) * probe_sign_not_zero(p.x), (1.0f - fabs(p.x)) * probe_sign_not_zero(p.y));
  return p;
}

// Seed 004 Algorithm 2: octahedral coordinates -> unit direction.
inline float3 probe_oct_decode(float2 o) {
  float3 v = (float3)(o.x, o.y, 1.0f - fabs(o.x) - fabs(o.y));
  if (v.z < 0.0f) {
    float x = (1.0f - fabs(v.y)) * probe_sign_not_zero(v.x);
    float y = (1.0f - fabs(v.x)) * probe_sign_not_zero(v.y);
    v.x = x;
    v.y = y;
  }
  return normalize(v);
}

// Direction of the centre of interior texel (tx, ty), 0 <= tx, ty < res.
inline float3 probe_texel_direction(int tx, int ty, int res) {
  return probe_oct_decode((float2)(((float)tx + 0.5f) / (float)res * 2.0f - 1.0f,
                                   ((float)ty + 0.5f) / (float)res * 2.0f - 1.0f));
}

// Bilinear footprint of direction `dir` in a bordered map with `res` interior texels per side:
// the top-left tap (x0, y0) (both in 0 … res, so x0 + 1 <= res + 1 stays inside) and weights.
inline void probe_bilinear(float3 dir, int res, int* x0, int* y0, float2* t) {
  float2 f = (probe_oct_encode(dir) * 0.5f + 0.5f) * (float)res + 0.5f;
  float2 fl = floor(f);
  *x0 = clamp((int)fl.x, 0, res);
  *y0 = clamp((int)fl.y, 0, res);
  *t = clamp(f - (float2)((float)*x0, (float)*y0), 0.0f, 1.0f);
}

inline float3 probe_sample_irradiance(global const float4* irradiance, int probe, int res, float3 dir) {
  int x0, y0;
  float2 t;
  probe_bilinear(dir, res, &x0, &y0, &t);
  int side = res + 2;
  global const float4* m = irradiance + (size_t)probe * side * side + y0 * side + x0;
  float3 top = mix(m[0].xyz, m[1].xyz, t.x), bottom = mix(m[side].xyz, m[side + 1].xyz, t.x);
  return mix(top, bottom, t.y);
}

inline float2 probe_sample_distance(global const float2* distance, int probe, int res, float3 dir) {
  int x0, y0;
  float2 t;
  probe_bilinear(dir, res, &x0, &y0, &t);
  int side = res + 2;
  global const float2* m = distance + (size_t)probe * side * side + y0 * side + x0;
  float2 top = mix(m[0], m[1], t.x), bottom = mix(m[side], m[side + 1], t.x);
  return mix(top, bottom, t.y);
}

// The grid point of probe i (its position before relocation).
inline float3 probe_position(const GiProbeGrid* g, int3 i) {
  return vload3(0, g->origin) + convert_float3(i) * vload3(0, g->spacing);
}

// The backface term for cosθ = n · (direction to the probe), and DDGI's crush of a backface ×
// visibility weight w in place: w · min(1, w²/t²) is w³/t² below t and w above it (see the top of
// this file). Macros, so that the scalar function below and the lane-wise shading (probes.cl)
// share one formula for float and floatV; the arguments are variables.
#if GI_PROBE_BACKFACE_SMOOTH
#define PROBE_BACKFACE_WEIGHT(g, cosine) ((0.5f * ((cosine) + 1.0f)) * (0.5f * ((cosine) + 1.0f)) + 0.2f)
#else
#define PROBE_BACKFACE_WEIGHT(g, cosine) fmax((g)->backface_floor, (cosine))
#endif
#if GI_PROBE_CRUSH
#define PROBE_CRUSH_WEIGHT(w)                                                                        \
  {                                                                                                  \
    w = fmax(w, 1e-6f);                                                                              \
    w *= fmin(w * w * (1.0f / (GI_PROBE_CRUSH_THRESHOLD * GI_PROBE_CRUSH_THRESHOLD)), 1.0f);         \
  }
#else
#define PROBE_CRUSH_WEIGHT(w) \
  {}
#endif

// Irradiance E (W/m²) at surface point x with shading normal n, geometric normal ng and unit
// direction wo towards the viewer (the camera, or a probe ray's origin). `irradiance`: the maps of
// E, or of √E with GI_PROBE_PERCEPTUAL_BLEND.
inline float3 probe_field_irradiance(const GiProbeGrid* g, global const float4* irradiance,
                                     global const float2* distance, global const float4* probeStates, float3 x,
                                     float3 n, float3 ng, float3 wo) {
  int3 count = vload3(0, g->count);
  float3 spacing = vload3(0, g->spacing);
  // Self-shadowing bias (DDGI): the visibility test looks from a point moved off the surface.
  float3 xb = x + ng * g->normal_bias + wo * g->view_bias;
  float3 rel = (xb - vload3(0, g->origin)) / spacing;
  int3 base = clamp(convert_int3(floor(rel)), (int3)(0), max(count - 2, (int3)(0)));
  float3 alpha = clamp(rel - convert_float3(base), 0.0f, 1.0f);
  float3 sum = (float3)(0.0f);
  float wsum = 0.0f;
  // Written without early exits and with constant trip counts (unrolled): PoCL then vectorizes
  // the caller across work-items (PERFORMANCE_FACTS.md 1, 7); a zero weight simply adds nothing.
#pragma unroll
  for (int c = 0; c < 8; ++c) {
    int3 off = (int3)(c & 1, (c >> 1) & 1, c >> 2);
    float3 tri = select(1.0f - alpha, alpha, off != 0);
    int3 pi = min(base + off, count - 1);  // a one-probe axis uses probe 0 for both corners
    int probe = (pi.z * count.y + pi.y) * count.x + pi.x;
    float4 state = probeStates[probe];
    float3 pp = probe_position(g, pi) + state.xyz;
    float3 toProbe = pp - x;
    float len = length(toProbe);
    float cosine = dot(n, toProbe / len);
    float w = len > 0.0f ? PROBE_BACKFACE_WEIGHT(g, cosine) : 1.0f;
    float3 fromProbe = xb - pp;
    float r = length(fromProbe);
    float2 m = probe_sample_distance(distance, probe, g->distance_res, r > 0.0f ? fromProbe / r : n);
    float variance = fabs(m.y - m.x * m.x), d = r - m.x;
    float cheb = variance / fmax(variance + d * d, 1e-30f), v = 1.0f;
#pragma unroll
    for (int k = 0; k < GI_PROBE_CHEBYSHEV_POWER; ++k) v *= cheb;
    w *= r > m.x ? v : 1.0f;
    PROBE_CRUSH_WEIGHT(w)
    w *= (tri.x * tri.y * tri.z) * state.w;
    sum += w * probe_sample_irradiance(irradiance, probe, g->irradiance_res, n);
    wsum += w;
  }
  float3 e = wsum > 0.0f ? sum / wsum : (float3)(0.0f);
  return GI_PROBE_PERCEPTUAL_BLEND ? e * e : e;
}
