// VPL visibility (`--set vpl.visibility=rays`) for every VPL gather (vpl, igi, splat, sh-igi):
// one shadow ray per receiver–VPL pair through the reference path tracer's BVH any-hit traversal
// (kernels/reference/bvh_traverse.h, the same code, not a copy). Exact up to the ray offsets;
// slow on a CPU: the accuracy anchor for the visibility-free approximations.
//
// A program compiled with GI_VPL_VISIBILITY takes, after its own arguments, `float rayEpsilon`
// then the BVH arguments (GI_VPL_VISIBILITY_PARAMS; src/gi/vpl/vpl_visibility.h sets them).
// Without the define the parameters and the test vanish: the visibility-free gather is unchanged.
//
// The segment from receiver x to VPL x_p is tested on t ∈ (ε/d, 1 − ε/d) with d = |x_p − x|:
// ε (metres) keeps the ray off the receiver's and the VPL's own surfaces, whose rasterized
// positions are interpolated, not ray-traced. Pairs closer than 2ε are never occluded.
#pragma once

#ifdef GI_VPL_VISIBILITY
#include "reference/bvh_traverse.h"

#define GI_VPL_VISIBILITY_PARAMS , float vpl_ray_epsilon, GI_BVH_ARGS

// `weight` with the lanes whose receiver (px, py, pz) cannot see their VPL at (vx, vy, vz) set to 0
// (one VPL per lane: sh-igi's lanes belong to different VPL sets). Only lanes with a positive
// weight trace a ray (back-facing pairs and empty slots cost nothing).
inline floatV vpl_visible_lanes(const GiBvh* bvh, float epsilon, floatV px, floatV py, floatV pz, floatV vx,
                                floatV vy, floatV vz, floatV weight) {
  float w[GI_VW], ox[GI_VW], oy[GI_VW], oz[GI_VW], tx[GI_VW], ty[GI_VW], tz[GI_VW];
  vstoreV(weight, 0, w);
  vstoreV(px, 0, ox);
  vstoreV(py, 0, oy);
  vstoreV(pz, 0, oz);
  vstoreV(vx, 0, tx);
  vstoreV(vy, 0, ty);
  vstoreV(vz, 0, tz);
  for (int l = 0; l < GI_VW; ++l) {
    if (!(w[l] > 0.0f)) continue;
    float3 o = (float3)(ox[l], oy[l], oz[l]);
    float3 d = (float3)(tx[l], ty[l], tz[l]) - o;  // t = 1 at the VPL
    float t0 = epsilon / length(d);
    if (t0 < 0.5f && trace_any(bvh, o, d, t0, 1.0f - t0)) w[l] = 0.0f;
  }
  return vloadV(0, w);
}

// The same for one VPL at xp shared by all lanes.
inline floatV vpl_visible(const GiBvh* bvh, float epsilon, floatV px, floatV py, floatV pz, float3 xp,
                          floatV weight) {
  return vpl_visible_lanes(bvh, epsilon, px, py, pz, (floatV)(xp.x), (floatV)(xp.y), (floatV)(xp.z), weight);
}

#define GI_VPL_VISIBILITY_BEGIN GiBvh vpl_bvh = GI_BVH_MAKE;
#define GI_VPL_VISIBLE(px, py, pz, xp, weight) vpl_visible(&vpl_bvh, vpl_ray_epsilon, px, py, pz, xp, weight)
#define GI_VPL_VISIBLE_LANES(px, py, pz, vx, vy, vz, weight) \
  vpl_visible_lanes(&vpl_bvh, vpl_ray_epsilon, px, py, pz, vx, vy, vz, weight)
#else
#define GI_VPL_VISIBILITY_PARAMS
#define GI_VPL_VISIBILITY_BEGIN
#define GI_VPL_VISIBLE(px, py, pz, xp, weight) (weight)
#define GI_VPL_VISIBLE_LANES(px, py, pz, vx, vy, vz, weight) (weight)
#endif
