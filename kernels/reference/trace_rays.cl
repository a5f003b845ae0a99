// Batch ray tracing through the BVH: one ray per work-item, for tests, benchmarks and tools that
// want hits on the host. Rays: origin.xyz + tmin in .w, direction.xyz + tmax in .w.
#include "reference/bvh_traverse.h"

// Closest hits: (t, u, v, as_float(prim)); prim = GI_INVALID_ID on a miss (t = tmax then).
kernel void trace_closest_rays(GI_BVH_ARGS, global const float4* origins, global const float4* dirs,
                               global float4* hits, uint count) {
  uint i = get_global_id(0);
  if (i >= count) return;
  GiBvh bvh = GI_BVH_MAKE;
  float4 o = origins[i], d = dirs[i];
  GiHit h;
  trace_closest(&bvh, o.xyz, d.xyz, o.w, d.w, &h);
  hits[i] = (float4)(h.t, h.u, h.v, as_float(h.prim));
}

// Occlusion: 1 when anything is hit in (tmin, tmax), else 0.
kernel void trace_any_rays(GI_BVH_ARGS, global const float4* origins, global const float4* dirs,
                           global uint* occluded, uint count) {
  uint i = get_global_id(0);
  if (i >= count) return;
  GiBvh bvh = GI_BVH_MAKE;
  float4 o = origins[i], d = dirs[i];
  occluded[i] = trace_any(&bvh, o.xyz, d.xyz, o.w, d.w) ? 1u : 0u;
}
