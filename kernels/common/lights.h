// Punctual-light emission (ALGORITHMS.md §0, KHR_lights_punctual): radiant intensity of point and
// spot lights towards a direction, irradiance of directional lights. Used by direct lighting,
// RSM flux and (where it samples punctual lights) the path tracer.
#pragma once
#include "common/shared_types.h"

// Intensity (W/sr per channel) of a point/spot light towards unit direction w (pointing away from
// the light). Spot falloff: glTF's reference smooth ramp between the outer and inner cone, squared;
// or I0·cos θ for the emissive-area stand-ins.
inline float3 light_intensity_towards(global const GiLight* l, float3 w) {
  float3 I = vload3(0, l->intensity);
  if (l->type != GI_LIGHT_SPOT) return I;
  float c = dot(w, vload3(0, l->direction));
  if (l->falloff == GI_SPOT_FALLOFF_COSINE) return I * fmax(c, 0.0f);
  float scale = 1.0f / fmax(1e-3f, l->cos_inner - l->cos_outer);
  float a = clamp((c - l->cos_outer) * scale, 0.0f, 1.0f);
  return I * (a * a);
}

// Incident light at x from light l: unit direction towards the light (*wi), distance (*dist,
// +inf for directional) and the irradiance on a surface facing the light (W/m² per channel,
// i.e. without the receiver cosine).
inline float3 light_incident(global const GiLight* l, float3 x, float3* wi, float* dist) {
  if (l->type == GI_LIGHT_DIRECTIONAL) {
    *wi = -vload3(0, l->direction);
    *dist = INFINITY;
    return vload3(0, l->intensity);
  }
  float3 d = vload3(0, l->position) - x;
  float d2 = fmax(dot(d, d), 1e-12f);
  float inv = rsqrt(d2);
  *wi = d * inv;
  *dist = d2 * inv;
  return light_intensity_towards(l, -*wi) / d2;
}
