// The one BRDF of the engine (ALGORITHMS.md §0): Lambert ρ/π plus GGX microfacet specular with
// height-correlated Smith masking and Fresnel-Schlick. The diffuse lobe is not scaled by (1 − F),
// so that diffuse-only techniques and the reference agree on L = ρ/π · E.
#pragma once
#include "common/material.h"

#define GI_MIN_GGX_ALPHA 1e-3f  // keeps the mirror limit finite

inline float ggx_alpha(float roughness) { return fmax(roughness * roughness, GI_MIN_GGX_ALPHA); }

inline float ggx_D(float nh, float a2) {
  float d = nh * nh * (a2 - 1.0f) + 1.0f;
  return a2 / (GI_PI * d * d);
}

// Height-correlated Smith visibility V = G2 / (4 |n·l| |n·v|).
inline float smith_visibility(float nl, float nv, float a2) {
  float gv = nl * sqrt(nv * nv * (1.0f - a2) + a2);
  float gl = nv * sqrt(nl * nl * (1.0f - a2) + a2);
  return 0.5f / fmax(gv + gl, 1e-12f);
}

inline float3 fresnel_schlick(float3 f0, float cosTheta) {
  float m = clamp(1.0f - cosTheta, 0.0f, 1.0f);
  float m2 = m * m;
  return f0 + (1.0f - f0) * (m2 * m2 * m);
}

// Specular part of f(wo, wi) (no cosine), both directions pointing away from the surface.
inline float3 brdf_specular(SurfaceSample s, float3 n, float3 wo, float3 wi) {
  float nl = dot(n, wi), nv = dot(n, wo);
  if (nl <= 0.0f || nv <= 0.0f) return (float3)(0.0f);
  float3 h = normalize(wo + wi);
  float a = ggx_alpha(s.roughness);
  float a2 = a * a;
  return ggx_D(fmax(dot(n, h), 0.0f), a2) * smith_visibility(nl, nv, a2) * fresnel_schlick(s.f0, dot(wi, h));
}

// f(wo, wi): Lambert + GGX. Zero for light from below the surface; the specular lobe also needs
// the viewer above it (a normal-mapped normal can tilt away from the viewer).
inline float3 brdf_eval(SurfaceSample s, float3 n, float3 wo, float3 wi) {
  if (dot(n, wi) <= 0.0f) return (float3)(0.0f);
  return s.diffuse * GI_INV_PI + brdf_specular(s, n, wo, wi);
}
