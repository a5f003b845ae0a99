// Rays and projections of a GiView (see src/render/views.h for the conventions).
#pragma once
#include "common/math.h"
#include "common/shared_types.h"

// World-space ray through the point (px, py) in pixel coordinates (pixel centres at +0.5).
// Perspective: origin at the eye. Orthographic: origin on the near plane, direction = view axis.
inline void view_pixel_ray(const GiView* v, float px, float py, float3* origin, float3* dir) {
  float nx = px / (float)v->width * 2.0f - 1.0f;
  float ny = 1.0f - py / (float)v->height * 2.0f;
  float4 pn = mat4_mul(v->inv_view_proj, (float4)(nx, ny, -1.0f, 1.0f));
  float4 pf = mat4_mul(v->inv_view_proj, (float4)(nx, ny, 1.0f, 1.0f));
  float3 a = pn.xyz / pn.w, b = pf.xyz / pf.w;
  *origin = v->orthographic ? a : vload3(0, v->eye);
  *dir = normalize(b - a);
}

// Ray-plane barycentrics of triangle (p0, p1, p2) (Möller–Trumbore without the inside test):
// returns (t, u, v) with hit = (1-u-v)·p0 + u·p1 + v·p2 = origin + t·dir.
inline float3 ray_triangle_barycentrics(float3 origin, float3 dir, float3 p0, float3 p1, float3 p2) {
  float3 e1 = p1 - p0, e2 = p2 - p0;
  float3 pv = cross(dir, e2);
  float det = dot(e1, pv);
  float inv = fabs(det) > 1e-30f ? 1.0f / det : 0.0f;
  float3 tv = origin - p0;
  float u = dot(tv, pv) * inv;
  float3 qv = cross(tv, e1);
  float w = dot(dir, qv) * inv;
  float t = dot(e2, qv) * inv;
  return (float3)(t, u, w);
}
