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

// ---- Importance sampling of the same BRDF (added for the reference path tracer) ----------------
// Lobe choice: the specular lobe with probability lum(F(n·wo)) / (lum(F) + lum(ρ)), the Lambert
// lobe otherwise; diffuse by cosine-weighted directions; specular by GGX visible normals
// (Heitz 2018, "Sampling the GGX distribution of visible normals"). pdfs are per solid angle of wi.

// Smith G1 for GGX (the masking term whose product form the height-correlated V approximates).
inline float ggx_G1(float nv, float a2) {
  return 2.0f * nv / (nv + sqrt(a2 + (1.0f - a2) * nv * nv));
}

inline float brdf_specular_probability(SurfaceSample s, float3 n, float3 wo) {
  float ls = luminance(fresnel_schlick(s.f0, fmax(dot(n, wo), 0.0f)));
  float ld = luminance(s.diffuse);
  if (ls + ld <= 0.0f) return 0.0f;
  return ls / (ls + ld);
}

// Visible normal in the local frame (z = normal) for view direction v (local, v.z > 0).
inline float3 ggx_sample_vndf_local(float3 v, float a, float u1, float u2) {
  float3 vh = normalize((float3)(a * v.x, a * v.y, v.z));
  float lensq = vh.x * vh.x + vh.y * vh.y;
  float3 t1 = lensq > 0.0f ? (float3)(-vh.y, vh.x, 0.0f) * rsqrt(lensq) : (float3)(1.0f, 0.0f, 0.0f);
  float3 t2 = cross(vh, t1);
  float r = sqrt(u1), phi = 2.0f * GI_PI * u2;
  float p1 = r * cos(phi), p2 = r * sin(phi);
  float sh = 0.5f * (1.0f + vh.z);
  p2 = (1.0f - sh) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + sh * p2;
  float3 nh = p1 * t1 + p2 * t2 + sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
  return normalize((float3)(a * nh.x, a * nh.y, fmax(1e-6f, nh.z)));
}

// pdf of brdf_sample choosing wi (mixture of both lobes); pspec from brdf_specular_probability.
inline float brdf_pdf(SurfaceSample s, float3 n, float3 wo, float3 wi, float pspec) {
  float nl = dot(n, wi), nv = dot(n, wo);
  if (nl <= 0.0f) return 0.0f;
  float pdf = (1.0f - pspec) * nl * GI_INV_PI;
  if (pspec > 0.0f && nv > 0.0f) {
    float a = ggx_alpha(s.roughness), a2 = a * a;
    float3 h = normalize(wo + wi);
    pdf += pspec * ggx_G1(nv, a2) * ggx_D(fmax(dot(n, h), 0.0f), a2) / (4.0f * nv);
  }
  return pdf;
}

// Samples wi for outgoing wo around shading normal n with uniforms u (u.x picks the lobe).
// Returns false when no direction above the surface was produced.
inline bool brdf_sample(SurfaceSample s, float3 n, float3 wo, float pspec, float3 u, float3* wi) {
  float3 t, b;
  orthonormal_basis(n, &t, &b);
  if (u.x < pspec) {
    float3 vl = (float3)(dot(wo, t), dot(wo, b), dot(wo, n));
    if (vl.z <= 0.0f) return false;
    float3 hl = ggx_sample_vndf_local(vl, ggx_alpha(s.roughness), u.y, u.z);
    float3 h = t * hl.x + b * hl.y + n * hl.z;
    *wi = 2.0f * dot(wo, h) * h - wo;
  } else {
    float r = sqrt(u.y), phi = 2.0f * GI_PI * u.z;
    float3 l = (float3)(r * cos(phi), r * sin(phi), sqrt(fmax(0.0f, 1.0f - u.y)));
    *wi = t * l.x + b * l.y + n * l.z;
  }
  return dot(n, *wi) > 0.0f;
}
