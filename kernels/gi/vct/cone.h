// Cone tracing through the voxel radiance mips (ALGORITHMS.md §5; Crassin et al. 2011).
//
// Positions and distances are in level-0 voxel units, measured from the grid's minimum corner.
// A cone of half-angle θ from o along unit d: at distance t its diameter is D = max(1, 2·t·tan θ)
// voxels and it samples the quadrilinearly filtered mip level log2(D). The step is
// max(½, step_factor·D); since one sample stands for a segment of length D while the march
// advances by Δt, its opacity is corrected to α' = 1 − (1 − α)^(Δt/D) (and its premultiplied
// radiance by α'/α), so the accumulated opacity does not depend on the step factor. Front to back:
//   c += (1 − a)·c_s·α'/α,  a += (1 − a)·α';
// the occlusion for ambient occlusion accumulates α' weighted by 1/(1 + λ·t) (λ per voxel).
// The march stops at a ≥ 0.99, past max_distance, or when the cone has left the grid.
// Footprint in front of the surface (vct.footprint_in_front): a cone leaving a surface samples, at
// height h (voxels) above the surface's tangent plane, a cell of level log2(D) whose trilinear
// stencil reaches cell centres up to D away; the cells holding the surface's own voxels (which
// reach 1 voxel in front of the plane) have centres up to 1 + D/2 above it. Capping D at the
// largest power of two ≤ (h − 1)/1.5 (so the quadrilinear blend takes no coarser level either) and
// sampling nothing below h = 2.5, the surface neither lights nor occludes itself; the cone then
// samples finer levels than its aperture near the surface (h = h0 + t·cos, cos = the cone axis'
// cosine with the normal). h0 = ∞ turns this off.
#pragma once
#include "gi/vct/voxel_grid.h"

typedef struct {
  float4 radiance;  // rgb: radiance arriving along the cone (W/(m²·sr)); w: accumulated opacity a
  float occlusion;  // distance-weighted opacity for ambient occlusion
} ConeResult;

// Sampled diameter (voxels) at distance t: the cone's, at least one voxel, and (footprint in front)
// at most the largest power of two ≤ (h − 1)/1.5, so that the quadrilinear lookup never blends in
// a level coarser than that bound.
inline float vct_footprint(float tanHalf, float t, float h0, float cosN) {
  float bound = (h0 + t * cosN - 1.0f) * (1.0f / 1.5f);
  float cap = bound >= 1.0f ? as_float(as_uint(bound) & 0xff800000u) : 1.0f;  // clear the mantissa
  return fmax(1.0f, fmin(2.0f * tanHalf * t, cap));
}

// One step of the march: t advances by max(½, step_factor·D(t)); returns the step and sets
// *diameter to the footprint at the new t.
inline float vct_cone_advance(float tanHalf, float stepFactor, float h0, float cosN, float* t, float* diameter) {
  float step = fmax(0.5f, stepFactor * vct_footprint(tanHalf, *t, h0, cosN));
  *t += step;
  *diameter = vct_footprint(tanHalf, *t, h0, cosN);
  return step;
}

// One front-to-back compositing step (above) of sample s (premultiplied radiance, α), its opacity
// corrected for the step: c += (1 − a)·s.rgb·α'/α, a += (1 − a)·α' with α' = 1 − (1 − α)^(Δt/D),
// occlusion weighted by 1/(1 + λt) (aoLambdaT = λt). Returns whether the cone is saturated.
inline bool vct_composite(float4 s, float stepOverDiameter, float aoLambdaT, float3* c, float* a, float* occ) {
  if (!(s.w > 1e-6f)) return false;
  float alpha = fmin(s.w, 1.0f);
  float corrected = 1.0f - powr(1.0f - alpha, stepOverDiameter);
  *c += (1.0f - *a) * s.xyz * (corrected / s.w);
  *occ += (1.0f - *occ) * corrected / (1.0f + aoLambdaT);
  *a += (1.0f - *a) * corrected;
  return *a >= 0.99f;
}

inline ConeResult vct_cone(VoxelMips m, float3 o, float3 d, float tanHalf, float maxDistance, float stepFactor,
                           float aoLambda, float h0, float cosN) {
  ConeResult r;
  float3 c = (float3)(0.0f);
  float a = 0.0f, occ = 0.0f;
  float t = 0.0f;
  float limit = (float)m.N;
  for (;;) {
    float diameter;
    float step = vct_cone_advance(tanHalf, stepFactor, h0, cosN, &t, &diameter);
    if (t > maxDistance) break;
    float3 p = o + d * t;
    float margin = 0.5f * diameter;
    if (any(p < -margin) || any(p > limit + margin)) break;
    // Footprint in front: below h = 2.5 voxels even level 0 would touch the surface's own voxels.
    if (h0 + t * cosN - 1.0f < 1.5f) continue;
    float4 s = vox_sample(m, p, d, log2(diameter));
    if (vct_composite(s, step / diameter, aoLambda * t, &c, &a, &occ)) break;
  }
  r.radiance = (float4)(c, a);
  r.occlusion = occ;
  return r;
}

// The level-aligned march (vct.diffuse_steps=levels, the default for the diffuse cones;
// vct.specular_steps=levels for the specular cone): samples where the diameter is at most a power
// of two, each reading exactly that level with one trilinear lookup (the march above blends two
// levels at fractional log2 D). Level l stands for the segment of the cone where its diameter is
// in (2^(l−1), 2^l] voxels, (t_(l−1), t_l] with t_l = 2^l / (2·tan θ) (level 0 from t = 0: the
// diameter is at least one voxel), split into k_l equal steps of at most max(½, stepFactor·2^l)
// voxels (k_l = 1 for stepFactor = ∞: one sample per level, at t_l, the diffuse cones); each of its
// samples reads level l and its opacity is corrected by Δt/2^l as above. For the diffuse cones'
// 60° apertures Δt/D = 1/(4·tan θ) = 0.43; a narrow specular cone (tan θ = 0.04) takes 13 steps of
// half a diameter per level instead of one step of 6.3 diameters. Levels past the top of the chain
// sample the top (1³) level with the cone's diameter. Same stop rules as vct_cone. Without
// footprint-in-front only (that mode caps D below the cone's diameter: the continuous march).
inline ConeResult vct_cone_levels(VoxelMips m, float3 o, float3 d, float tanHalf, float maxDistance, float stepFactor,
                                  float aoLambda) {
  ConeResult r;
  float3 c = (float3)(0.0f);
  float a = 0.0f, occ = 0.0f;
  float tPrevious = 0.0f, limit = (float)m.N;
  float tUnit = 0.5f / tanHalf;  // where the cone's diameter is one voxel
  float diameter = 1.0f;
  for (int level = 0, more = 1; more; ++level, diameter *= 2.0f) {
    float tEnd = diameter * tUnit, tStart = level == 0 ? 0.0f : 0.5f * tEnd;
    float steps = fmax(1.0f, ceil((tEnd - tStart) / fmax(0.5f, stepFactor * diameter)));
    float delta = (tEnd - tStart) / steps;
    for (float j = 1.0f; j <= steps; j += 1.0f) {
      float t = j == steps ? tEnd : tStart + j * delta;
      float3 p = o + d * t;
      float margin = 0.5f * diameter;
      if (t > maxDistance || any(p < -margin) || any(p > limit + margin)) {
        more = 0;
        break;
      }
      float step = t - tPrevious;
      tPrevious = t;
      float4 s = vox_level_sample(m, min(level, m.levels - 1), p, d);
#if GI_VCT_SH
      s.xyz = fmax(s.xyz, 0.0f);
#endif
      if (vct_composite(s, step / diameter, aoLambda * t, &c, &a, &occ)) {
        more = 0;
        break;
      }
    }
  }
  r.radiance = (float4)(c, a);
  r.occlusion = occ;
  return r;
}

// Diffuse cone sets around n (local frame z = n): directions, weights w_i (Σ w_i = π, so that
// E = Σ w_i·L_i reproduces E = π·L under uniform radiance) and the aperture half-angle.
//  6 cones (ALGORITHMS.md §5): one along n (π/4) and five at 60° from it, 72° apart (3π/20 each);
//  9 cones (ten Brug, seed 003 §3.4.3): n, the four side directions (±t + n)/√2 at 45° and the four
//    corners (±t ± b + n)/√3 at 54.7° of the box around n; the thesis gives no weights, we weight by
//    cos θ_i normalised to π.
// Both with 60° apertures (half-angle 30°).
#define VCT_DIFFUSE_TAN_HALF 0.57735027f
#if GI_VCT_CONES == 6
#define VCT_CONE_COUNT 6
constant float4 VCT_CONES[6] = {
    (float4)(0.0f, 0.0f, 1.0f, 0.78539816f),
    (float4)(0.86602540f, 0.0f, 0.5f, 0.47123890f),
    (float4)(0.26761657f, 0.82363910f, 0.5f, 0.47123890f),
    (float4)(-0.70062927f, 0.50903696f, 0.5f, 0.47123890f),
    (float4)(-0.70062927f, -0.50903696f, 0.5f, 0.47123890f),
    (float4)(0.26761657f, -0.82363910f, 0.5f, 0.47123890f),
};
#elif GI_VCT_CONES == 9
#define VCT_CONE_COUNT 9
// weights: π·cos θ_i / (1 + 4/√2 + 4/√3)
constant float4 VCT_CONES[9] = {
    (float4)(0.0f, 0.0f, 1.0f, 0.51184735f),
    (float4)(0.70710678f, 0.0f, 0.70710678f, 0.36193124f),
    (float4)(-0.70710678f, 0.0f, 0.70710678f, 0.36193124f),
    (float4)(0.0f, 0.70710678f, 0.70710678f, 0.36193124f),
    (float4)(0.0f, -0.70710678f, 0.70710678f, 0.36193124f),
    (float4)(0.57735027f, 0.57735027f, 0.57735027f, 0.29551631f),
    (float4)(-0.57735027f, 0.57735027f, 0.57735027f, 0.29551631f),
    (float4)(0.57735027f, -0.57735027f, 0.57735027f, 0.29551631f),
    (float4)(-0.57735027f, -0.57735027f, 0.57735027f, 0.29551631f),
};
#endif

#ifdef VCT_CONE_COUNT
// Irradiance (rgb) at a surface point p (voxel units) with normal n from the diffuse cone set,
// starting start_offset voxels along n; w: ambient-occlusion visibility 1 − Σ (w_i/π)·occlusion_i.
// levelSteps: the level-aligned march (vct_cone_levels) unless footprintInFront.
inline float4 vct_diffuse_irradiance(VoxelMips m, float3 p, float3 n, float startOffset, float maxDistance,
                                     float stepFactor, float aoLambda, int footprintInFront, int levelSteps) {
  float3 t, b;
  orthonormal_basis(n, &t, &b);
  float3 o = p + n * startOffset;
  float3 E = (float3)(0.0f);
  float occlusion = 0.0f;
  for (int i = 0; i < VCT_CONE_COUNT; ++i) {
    float4 cone = VCT_CONES[i];
    float3 d = normalize(t * cone.x + b * cone.y + n * cone.z);
    ConeResult r = levelSteps && !footprintInFront
                       ? vct_cone_levels(m, o, d, VCT_DIFFUSE_TAN_HALF, maxDistance, INFINITY, aoLambda)
                       : vct_cone(m, o, d, VCT_DIFFUSE_TAN_HALF, maxDistance, stepFactor, aoLambda,
                                  footprintInFront ? startOffset : INFINITY, cone.z);
    E += cone.w * r.radiance.xyz;
    occlusion += cone.w * GI_INV_PI * r.occlusion;
  }
  return (float4)(E, 1.0f - occlusion);
}
#endif
