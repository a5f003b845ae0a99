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

// Whether light l's shadow map is a cube of 6 views (point lights and spot lights wider than
// GI_SPOT_CUBE_COS; the host decides the same in src/raster/gbuffer.cpp, usesCube) rather than one view.
inline bool shadow_uses_cube(global const GiLight* l) {
  return l->type == GI_LIGHT_POINT || (l->type == GI_LIGHT_SPOT && l->cos_outer < GI_SPOT_CUBE_COS);
}

// The shadow view of light l that sees x (its cube face for point and wide spot lights), −1 when
// the light casts no shadow.
inline int shadow_view_index(global const GiLight* l, float3 x) {
  if (l->shadow_map < 0) return -1;
  return l->shadow_map + (shadow_uses_cube(l) ? shadow_cube_face(x - vload3(0, l->position)) : 0);
}

inline float shadow_visibility(global const GiLight* l, global const GiView* views, global const uint* offsets,
                               global const float* depths, float3 x, float3 geoNormal) {
  int vi = shadow_view_index(l, x);
  return vi < 0 ? 1.0f : shadow_pcf_view(views, offsets, depths, vi, x, geoNormal);
}

// Fraction of a voxel's cross-section that the light reaches, for the voxel light injection (vct):
// the axis-aligned cube of half side h at `centre`, bounded in the view's space by the box
// centre ± (hx, hy, hz); 3×3 taps at the centres of the 3×3 cells of its x-y footprint on the map,
// each lit when the first surface the light meets there (the stored depth) is not in front of
// the box (depth ≥ its front − one texel footprint). The voxel's own surfaces lie inside the box,
// so they never shadow it (no normal offset or bias of the size of a texel is needed), and
// occluders in front of it shadow the part of the footprint they cover: a filtered visibility
// over the whole voxel rather than a point sample of it, which does not depend on the map's
// texel size (docs/techniques/vct.md, "Light injection").
#define GI_VOXEL_SHADOW_TAP 0.6666667f  // tap offsets: −⅔, 0, ⅔ of the half-extent

// Half-extents along the view's x, y and z axes of the axis-aligned cube of half side h, for the
// view matrix m (column-major; its rotation rows).
inline float3 shadow_view_box_half(global const float* m, float h) {
  return h * (float3)(fabs(m[0]) + fabs(m[4]) + fabs(m[8]), fabs(m[1]) + fabs(m[5]) + fabs(m[9]),
                      fabs(m[2]) + fabs(m[6]) + fabs(m[10]));
}

inline float shadow_voxel_view(global const GiView* views, global const uint* offsets, global const float* depths,
                               int vi, float3 centre, float h) {
  global const GiView* v = &views[vi];
  global const float* m = v->view;
  float3 extent = shadow_view_box_half(m, h);
  float hx = extent.x, hy = extent.y, hz = extent.z;
  float depth = -mat4_mul_global(m, (float4)(centre, 1.0f)).z;
  float texel = v->orthographic ? v->texel_world_size : v->texel_world_size * fmax(depth, 0.0f);
  float front = depth - hz - GI_SHADOW_DEPTH_BIAS * texel;
  float4 c = mat4_mul_global(v->view_proj, (float4)(centre, 1.0f));
  if (c.w <= 0.0f || texel <= 0.0f) return 1.0f;
  float fx = (c.x / c.w * 0.5f + 0.5f) * (float)v->width;
  float fy = (0.5f - c.y / c.w * 0.5f) * (float)v->height;
  float invTexel = 1.0f / texel;
  float stepX = GI_VOXEL_SHADOW_TAP * hx * invTexel, stepY = GI_VOXEL_SHADOW_TAP * hy * invTexel;
  global const float* map = depths + offsets[vi];
  float lit = 0.0f;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      float tx = fx + (float)dx * stepX, ty = fy + (float)dy * stepY;
      // Outside the map nothing was rendered that could occlude: lit.
      if (!(tx >= 0.0f && ty >= 0.0f && tx < (float)v->width && ty < (float)v->height)) {
        lit += 1.0f;
        continue;
      }
      lit += front <= map[(int)ty * v->width + (int)tx] ? 1.0f : 0.0f;
    }
  return lit * (1.0f / 9.0f);
}

inline float shadow_voxel_visibility(global const GiLight* l, global const GiView* views, global const uint* offsets,
                                     global const float* depths, float3 centre, float h) {
  int vi = shadow_view_index(l, centre);
  return vi < 0 ? 1.0f : shadow_voxel_view(views, offsets, depths, vi, centre, h);
}
