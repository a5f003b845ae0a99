// Lane-wise (GI_VW points per work-item, common/vector_width.h) forms of light_incident()
// (common/lights.h) and shadow_visibility() (common/shadow.h): the same formulas, lights and
// shadow views uniform across lanes. Used by direct lighting and the voxel light injection.
#pragma once
#include "common/lights.h"
#include "common/shadow.h"
#include "common/vector_width.h"

// The spot cone's factor on the intensity for lanes whose direction from the light makes cosine
// `c` with its axis (1 for point and directional lights); light_intensity_towards() lane-wise.
inline floatV light_spot_factorV(global const GiLight* l, floatV c) {
  if (l->type != GI_LIGHT_SPOT) return (floatV)(1.0f);
  if (l->falloff == GI_SPOT_FALLOFF_COSINE) return fmax(c, 0.0f);
  float scale = 1.0f / fmax(1e-3f, l->cos_inner - l->cos_outer);
  floatV t = clamp((c - l->cos_outer) * scale, 0.0f, 1.0f);
  return t * t;
}

// light_incident() lane-wise: the irradiance on a surface facing the light at x and the unit
// direction towards the light (*wi).
inline float3V light_incidentV(global const GiLight* l, float3V x, float3V* wi) {
  if (l->type == GI_LIGHT_DIRECTIONAL) {
    *wi = f3v((floatV)(-l->direction[0]), (floatV)(-l->direction[1]), (floatV)(-l->direction[2]));
    return f3v((floatV)(l->intensity[0]), (floatV)(l->intensity[1]), (floatV)(l->intensity[2]));
  }
  // light_intensity_towards() for point and spot lights
  float3V d = f3v(l->position[0] - x.x, l->position[1] - x.y, l->position[2] - x.z);
  floatV d2 = fmax(dotV(d, d), 1e-12f);
  floatV inv = rsqrt(d2);
  *wi = f3v(d.x * inv, d.y * inv, d.z * inv);
  floatV s = light_spot_factorV(l, -(wi->x * l->direction[0] + wi->y * l->direction[1] + wi->z * l->direction[2]));
  return f3v(l->intensity[0] * s / d2, l->intensity[1] * s / d2, l->intensity[2] * s / d2);
}

// Row 2 (view-space z) and rows 0, 1, 3 of a column-major matrix applied to (p, 1).
#define GI_MROW(m, r, p) ((m)[r] * (p).x + (m)[4 + r] * (p).y + (m)[8 + r] * (p).z + (m)[12 + r])

// shadow_pcf_view() lane-wise for view `vi` (the same view for every lane).
inline floatV shadow_pcf_viewV(global const GiView* views, global const uint* offsets, global const float* depths,
                               int vi, float3V x, float3V ng) {
  global const GiView* v = &views[vi];
  floatV xvz = GI_MROW(v->view, 2, x);
  floatV texel = v->orthographic ? (floatV)(v->texel_world_size) : v->texel_world_size * fmax(-xvz, 0.0f);
  floatV off = GI_SHADOW_NORMAL_OFFSET * texel;
  float3V xo = f3v(x.x + ng.x * off, x.y + ng.y * off, x.z + ng.z * off);
  floatV cx = GI_MROW(v->view_proj, 0, xo), cy = GI_MROW(v->view_proj, 1, xo), cw = GI_MROW(v->view_proj, 3, xo);
  floatV ndcx = cx / cw, ndcy = cy / cw;
  floatV depth = -GI_MROW(v->view, 2, xo) - GI_SHADOW_DEPTH_BIAS * texel;
  float W = (float)v->width, H = (float)v->height;
  floatV fx = (ndcx * 0.5f + 0.5f) * W;
  floatV fy = (0.5f - ndcy * 0.5f) * H;
  intV lit1 = (cw <= 0.0f) | (fx < 0.0f) | (fy < 0.0f) | (fx >= W) | (fy >= H) | isnan(fx) | isnan(fy);
  intV ix = convert_intV(floor(GI_SEL(fx, (floatV)(0.0f), lit1)));
  intV iy = convert_intV(floor(GI_SEL(fy, (floatV)(0.0f), lit1)));
  global const float* map = depths + offsets[vi];
  intV x0 = max(ix - 1, (intV)(0)), x2 = min(ix + 1, (intV)(v->width - 1));
  intV r0 = max(iy - 1, (intV)(0)) * v->width, r1 = iy * v->width, r2 = min(iy + 1, (intV)(v->height - 1)) * v->width;
  floatV one = (floatV)(1.0f), zero = (floatV)(0.0f);
  floatV lit = zero;
  if (v->width >= 4) {
    // Each row's 3 taps from one 4-texel load per lane at xs = clamp(ix − 1, 0, W − 4) (3 loads
    // and a transposition instead of 9 scalar gathers: −10 % CPU time of the voxel injection,
    // docs/PERFORMANCE.md), the taps picked from it by their clamped columns. The same taps:
    // the same bits (each adds 0 or 1).
    intV xs = min(max(ix - 1, (intV)(0)), (intV)(v->width - 4));
    intV j0 = x0 - xs, j1 = ix - xs, j2 = x2 - xs;
    intV rows[3] = {r0, r1, r2};
#define GI_PICK(j) GI_SEL(GI_SEL(d0, d1, (j) >= 1), GI_SEL(d2, d3, (j) >= 3), (j) >= 2)
#pragma unroll
    for (int r = 0; r < 3; ++r) {
      floatV d0, d1, d2, d3;
      GI_GATHER_SPAN4(float, map, rows[r] + xs, d0, d1, d2, d3)
      lit += GI_SEL(zero, one, depth <= GI_PICK(j0));
      lit += GI_SEL(zero, one, depth <= GI_PICK(j1));
      lit += GI_SEL(zero, one, depth <= GI_PICK(j2));
    }
#undef GI_PICK
  } else {
#define GI_TAP(r, c) GI_SEL(zero, one, depth <= GI_GATHER(floatV, map, (r) + (c)))
    lit = GI_TAP(r0, x0) + GI_TAP(r0, ix) + GI_TAP(r0, x2) + GI_TAP(r1, x0) + GI_TAP(r1, ix) + GI_TAP(r1, x2) +
          GI_TAP(r2, x0) + GI_TAP(r2, ix) + GI_TAP(r2, x2);
#undef GI_TAP
  }
  return GI_SEL(lit * (1.0f / 9.0f), one, lit1);
}

// shadow_cube_face() lane-wise: the cube face of a point light's shadow map that sees x.
inline intV shadow_cube_faceV(global const GiLight* l, float3V x) {
  float3V d = f3v(x.x - l->position[0], x.y - l->position[1], x.z - l->position[2]);
  floatV ax = fabs(d.x), ay = fabs(d.y), az = fabs(d.z);
  intV face = GI_SEL(GI_SEL((intV)(5), (intV)(4), d.z > 0.0f), GI_SEL((intV)(3), (intV)(2), d.y > 0.0f), ay >= az);
  return GI_SEL(face, GI_SEL((intV)(1), (intV)(0), d.x > 0.0f), (ax >= ay) & (ax >= az));
}

inline floatV shadow_visibilityV(global const GiLight* l, global const GiView* views, global const uint* offsets,
                                 global const float* depths, float3V x, float3V ng) {
  if (l->shadow_map < 0) return (floatV)(1.0f);
  int vi = l->shadow_map;
  if (!shadow_uses_cube(l)) return shadow_pcf_viewV(views, offsets, depths, vi, x, ng);
  // shadow_cube_face() per lane; each face present among the lanes is evaluated once.
  intV face = shadow_cube_faceV(l, x);
  floatV vis = (floatV)(1.0f);
  for (int f = 0; f < 6; ++f) {
    intV here = face == f;
    if (GI_ANY(here)) vis = GI_SEL(vis, shadow_pcf_viewV(views, offsets, depths, vi + f, x, ng), here);
  }
  return vis;
}

// shadow_voxel_view() lane-wise for view `vi` (the same view for every lane): the voxels' boxes
// have the same half side h.
inline floatV shadow_voxel_viewV(global const GiView* views, global const uint* offsets, global const float* depths,
                                 int vi, float3V centre, float h) {
  global const GiView* v = &views[vi];
  global const float* m = v->view;
  float3 extent = shadow_view_box_half(m, h);
  float hx = extent.x, hy = extent.y, hz = extent.z;
  floatV depth = -GI_MROW(m, 2, centre);
  floatV texel = v->orthographic ? (floatV)(v->texel_world_size) : v->texel_world_size * fmax(depth, 0.0f);
  floatV front = depth - hz - GI_SHADOW_DEPTH_BIAS * texel;
  floatV cx = GI_MROW(v->view_proj, 0, centre), cy = GI_MROW(v->view_proj, 1, centre), cw = GI_MROW(v->view_proj, 3, centre);
  float W = (float)v->width, H = (float)v->height;
  floatV fx = (cx / cw * 0.5f + 0.5f) * W;
  floatV fy = (0.5f - cy / cw * 0.5f) * H;
  intV allLit = (cw <= 0.0f) | (texel <= 0.0f);
  floatV invTexel = 1.0f / GI_SEL(texel, (floatV)(1.0f), allLit);
  floatV stepX = GI_VOXEL_SHADOW_TAP * hx * invTexel, stepY = GI_VOXEL_SHADOW_TAP * hy * invTexel;
  global const float* map = depths + offsets[vi];
  floatV one = (floatV)(1.0f), zero = (floatV)(0.0f);
  floatV lit = zero;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      floatV tx = fx + (float)dx * stepX, ty = fy + (float)dy * stepY;
      intV outside = allLit | GI_NOT((tx >= 0.0f) & (ty >= 0.0f) & (tx < W) & (ty < H));
      intV index = GI_SEL(convert_intV(ty) * v->width + convert_intV(tx), (intV)(0), outside);
      floatV stored = GI_GATHER(floatV, map, index);
      lit += GI_SEL(GI_SEL(zero, one, front <= stored), one, outside);
    }
  return lit * (1.0f / 9.0f);
}

inline floatV shadow_voxel_visibilityV(global const GiLight* l, global const GiView* views, global const uint* offsets,
                                       global const float* depths, float3V centre, float h) {
  if (l->shadow_map < 0) return (floatV)(1.0f);
  int vi = l->shadow_map;
  if (!shadow_uses_cube(l)) return shadow_voxel_viewV(views, offsets, depths, vi, centre, h);
  intV face = shadow_cube_faceV(l, centre);
  floatV vis = (floatV)(1.0f);
  for (int f = 0; f < 6; ++f) {
    intV here = face == f;
    if (GI_ANY(here)) vis = GI_SEL(vis, shadow_voxel_viewV(views, offsets, depths, vi + f, centre, h), here);
  }
  return vis;
}
