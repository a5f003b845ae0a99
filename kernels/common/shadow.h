// Shadow-map lookups with 3×3 percentage-closer filtering. All shadow maps of a frame live in one
// depth buffer; view v occupies depths[offsets[v] ...] with views[v].width × height texels and
// stores linear depth along its view axis (raster.cl). Point lights and wide spot lights use six
// consecutive cube-face views; other lights one view.
#pragma once
#include "common/lights.h"
#include "common/math.h"
#include "common/shared_types.h"

#define GI_SHADOW_NORMAL_OFFSET 1.5f  // receiver moved this many texel footprints along its normal
#define GI_SHADOW_DEPTH_BIAS 1.0f     // and compared this many texel footprints closer

inline int shadow_cube_face(float3 d) {
  float3 a = fabs(d);
  if (a.x >= a.y && a.x >= a.z) return d.x > 0.0f ? 0 : 1;
  if (a.y >= a.z) return d.y > 0.0f ? 2 : 3;
  return d.z > 0.0f ? 4 : 5;
}

// Fraction of the 3×3 texel neighbourhood that sees x lit, for the view `vi`.
inline float shadow_pcf_view(global const GiView* views, global const uint* offsets, global const float* depths,
                             int vi, float3 x, float3 geoNormal) {
  global const GiView* v = &views[vi];
  // Texel footprint at x: constant for orthographic views, growing with distance otherwise.
  float4 xv = mat4_mul_global(v->view, (float4)(x, 1.0f));
  float texel = v->orthographic ? v->texel_world_size : v->texel_world_size * fmax(-xv.z, 0.0f);
  float3 xo = x + geoNormal * (GI_SHADOW_NORMAL_OFFSET * texel);
  float4 c = mat4_mul_global(v->view_proj, (float4)(xo, 1.0f));
  if (c.w <= 0.0f) return 1.0f;
  float3 ndc = c.xyz / c.w;
  float depth = -mat4_mul_global(v->view, (float4)(xo, 1.0f)).z - GI_SHADOW_DEPTH_BIAS * texel;
  float fx = (ndc.x * 0.5f + 0.5f) * (float)v->width;
  float fy = (0.5f - ndc.y * 0.5f) * (float)v->height;
  // Outside the map's footprint nothing was rendered that could occlude: lit.
  if (fx < 0.0f || fy < 0.0f || fx >= (float)v->width || fy >= (float)v->height) return 1.0f;
  int cx = (int)floor(fx), cy = (int)floor(fy);
  global const float* map = depths + offsets[vi];
  float lit = 0.0f;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      int sx = clamp(cx + dx, 0, v->width - 1), sy = clamp(cy + dy, 0, v->height - 1);
      lit += depth <= map[sy * v->width + sx] ? 1.0f : 0.0f;
    }
  return lit * (1.0f / 9.0f);
}

inline float shadow_visibility(global const GiLight* l, global const GiView* views, global const uint* offsets,
                               global const float* depths, float3 x, float3 geoNormal) {
  if (l->shadow_map < 0) return 1.0f;
  int vi = l->shadow_map;
  bool cube = l->type == GI_LIGHT_POINT || (l->type == GI_LIGHT_SPOT && l->cos_outer < GI_SPOT_CUBE_COS);
  if (cube) vi += shadow_cube_face(x - vload3(0, l->position));
  return shadow_pcf_view(views, offsets, depths, vi, x, geoNormal);
}
