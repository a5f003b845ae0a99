// Light-field probes (McGuire et al. 2017 as seed 004 used them; ALGORITHMS.md §6), updated by ray
// tracing in the DDGI manner (Majercik et al. 2019) instead of cube-map rendering:
//   probe_trace            one work-item per probe ray: the radiance leaving the first surface hit
//                          towards the probe and the hit distance (reference BVH traversal);
//   probe_blend_irradiance one work-item per irradiance texel: E = π Σ max(0, n·ω) L / Σ max(0, n·ω)
//                          over this update's rays, blended with the texel's previous value;
//   probe_blend_distance   one work-item per distance texel: weighted mean and mean² of the hit
//                          distance with weights max(0, n·ω)^GI_PROBE_DISTANCE_EXPONENT, blended;
//   probe_border_*         copy the texels across the octahedral seams into each map's border;
//   probe_shade            one work-item per camera pixel: ρ/π · E from probe_field_irradiance().
// Radiance at a ray hit = the hit's emission (only emitters without a punctual stand-in: those
// with one already light the scene through it) + ρ/π · (E_direct + E_probes), where E_direct sums
// every punctual light (stand-ins included) with a shadow ray and E_probes, when multi-bounce is on,
// reads the probes' previous state (each update adds one more bounce). Surfaces are shaded two-sided,
// as the path tracer does; only the diffuse lobe is used (diffuse indirect light only).
#include "common/brdf.h"
#include "common/lights.h"
#include "gi/probes/probe_field.h"
#include "reference/hit_surface.h"

#ifndef GI_PROBE_DISTANCE_EXPONENT_LOG2
#define GI_PROBE_DISTANCE_EXPONENT_LOG2 6
#endif

inline int probe_total(const GiProbeGrid* g) { return g->count[0] * g->count[1] * g->count[2]; }

inline int3 probe_index3(const GiProbeGrid* g, int probe) {
  return (int3)(probe % g->count[0], (probe / g->count[0]) % g->count[1], probe / (g->count[0] * g->count[1]));
}

// rayDirs: this update's unit ray directions (the same for every probe). Output per ray:
// (radiance towards the probe, hit distance); a miss records zero radiance at grid.max_distance.
kernel void probe_trace(GiProbeGrid grid, GI_BVH_ARGS, global const float4* positions, global const float4* normals,
                        global const float4* tangents, global const uint* triangleInstance,
                        global const uint* instanceEmits, global const GiLight* lights, int lightCount,
                        global const float4* rayDirs, global const float4* irradiance, global const float2* distance,
                        int multiBounce, global float4* rayResults) {
  int gid = get_global_id(0);
  int probe = gid / grid.rays, ray = gid % grid.rays;
  if (probe >= probe_total(&grid)) return;
  GiBvh bvh = GI_BVH_MAKE;
  float3 o = probe_position(&grid, probe_index3(&grid, probe));
  float3 d = rayDirs[ray].xyz;
  GiHit hit;
  if (!trace_closest(&bvh, o, d, 0.0f, grid.max_distance, &hit)) {
    rayResults[gid] = (float4)(0.0f, 0.0f, 0.0f, grid.max_distance);
    return;
  }
  PtSurface sf = pt_surface(positions, normals, tangents, &bvh, hit.prim, hit.u, hit.v, true);
  float3 wo = -d, ng = sf.ng, n = sf.n;
  float3 L = (float3)(0.0f);
  if (instanceEmits[triangleInstance[hit.prim]] && dot(ng, wo) > 0.0f) L += pt_emission(&bvh, sf.material, sf.uv);
  if (dot(ng, wo) < 0.0f) { ng = -ng; n = -n; }
  SurfaceSample s = eval_material(bvh.materials + sf.material, bvh.textures, bvh.texels, sf.uv, 0.0f);
  float3 x = sf.p + ng * pt_offset_scale(sf.p);
  float3 E = (float3)(0.0f);
  for (int li = 0; li < lightCount; ++li) {
    float3 wi;
    float dist;
    float3 El = light_incident(lights + li, x, &wi, &dist);
    float cosI = dot(n, wi);
    if (cosI <= 0.0f || dot(ng, wi) <= 0.0f || !(El.x > 0.0f || El.y > 0.0f || El.z > 0.0f)) continue;
    float tmax = isinf(dist) ? INFINITY : dist * (1.0f - 1e-4f);
    if (!trace_any(&bvh, x, wi, 0.0f, tmax)) E += El * cosI;
  }
  if (multiBounce) E += probe_field_irradiance(&grid, irradiance, distance, sf.p, n, ng, wo);
  L += s.diffuse * GI_INV_PI * E;
  rayResults[gid] = (float4)(L, hit.t);
}

// hysteresis: weight of the texel's previous value (0 on the first update).
kernel void probe_blend_irradiance(GiProbeGrid grid, global const float4* rayDirs, global const float4* rayResults,
                                   float hysteresis, global float4* irradiance) {
  int res = grid.irradiance_res, gid = get_global_id(0);
  int probe = gid / (res * res), texel = gid % (res * res);
  if (probe >= probe_total(&grid)) return;
  int tx = texel % res, ty = texel / res;
  float3 n = probe_texel_direction(tx, ty, res);
  global const float4* rays = rayResults + (size_t)probe * grid.rays;
  float3 sum = (float3)(0.0f);
  float wsum = 0.0f;
  for (int r = 0; r < grid.rays; ++r) {
    float w = fmax(0.0f, dot(n, rayDirs[r].xyz));
    sum += w * rays[r].xyz;
    wsum += w;
  }
  if (wsum <= 0.0f) return;  // no ray in this texel's hemisphere this time: keep the old value
  int side = res + 2;
  size_t i = (size_t)probe * side * side + (ty + 1) * side + tx + 1;
  float3 E = M_PI_F * sum / wsum;
  irradiance[i] = (float4)(mix(E, irradiance[i].xyz, hysteresis), 0.0f);
}

kernel void probe_blend_distance(GiProbeGrid grid, global const float4* rayDirs, global const float4* rayResults,
                                 float hysteresis, global float2* distance) {
  int res = grid.distance_res, gid = get_global_id(0);
  int probe = gid / (res * res), texel = gid % (res * res);
  if (probe >= probe_total(&grid)) return;
  int tx = texel % res, ty = texel / res;
  float3 n = probe_texel_direction(tx, ty, res);
  global const float4* rays = rayResults + (size_t)probe * grid.rays;
  float2 sum = (float2)(0.0f);
  float wsum = 0.0f;
  for (int r = 0; r < grid.rays; ++r) {
    float w = fmax(0.0f, dot(n, rayDirs[r].xyz));
    for (int k = 0; k < GI_PROBE_DISTANCE_EXPONENT_LOG2; ++k) w *= w;  // max(0, cos)^(2^k), no pow()
    float t = rays[r].w;
    sum += w * (float2)(t, t * t);
    wsum += w;
  }
  if (wsum <= 0.0f) return;
  int side = res + 2;
  size_t i = (size_t)probe * side * side + (ty + 1) * side + tx + 1;
  distance[i] = mix(sum / wsum, distance[i], hysteresis);
}

// Border texel (x, y) of a bordered map (x or y is 0 or res + 1) repeats the interior texel that
// lies next to it across the octahedral seam: each edge is mirrored about its middle, and a corner
// takes the opposite interior corner (all four corners are the direction −z).
inline int probe_border_source(int x, int y, int res) {
  int side = res + 2, last = res + 1;
  bool ex = x == 0 || x == last, ey = y == 0 || y == last;
  if (ex && ey) return (y == 0 ? res : 1) * side + (x == 0 ? res : 1);
  if (ey) return (y == 0 ? 1 : res) * side + (last - x);
  return (last - y) * side + (x == 0 ? 1 : res);
}

#define PROBE_BORDER_KERNEL(NAME, T)                                      \
  kernel void NAME(global T* map, int res, int probes) {                  \
    int side = res + 2, gid = get_global_id(0);                           \
    int probe = gid / (side * side), texel = gid % (side * side);         \
    if (probe >= probes) return;                                          \
    int x = texel % side, y = texel / side;                               \
    if (x > 0 && x <= res && y > 0 && y <= res) return;                   \
    global T* m = map + (size_t)probe * side * side;                      \
    m[texel] = m[probe_border_source(x, y, res)];                         \
  }
PROBE_BORDER_KERNEL(probe_border_irradiance, float4)
PROBE_BORDER_KERNEL(probe_border_distance, float2)

// Indirect radiance ρ/π · E per camera pixel (0 on the background).
kernel void probe_shade(GiProbeGrid grid, global const float4* irradiance, global const float2* distance, GiView camera,
                        global const float4* gPosition, global const float4* gGeoNormal, global const float4* gNormal,
                        global const float4* gAlbedo, global float4* indirect) {
  int px = get_global_id(0), py = get_global_id(1);
  if (px >= camera.width || py >= camera.height) return;
  size_t i = (size_t)py * camera.width + px;
  float4 p = gPosition[i];
  if (p.w == 0.0f) {
    indirect[i] = (float4)(0.0f);
    return;
  }
  float3 wo;
  if (camera.orthographic)
    wo = -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz);
  else
    wo = normalize(vload3(0, camera.eye) - p.xyz);
  float3 E = probe_field_irradiance(&grid, irradiance, distance, p.xyz, gNormal[i].xyz, gGeoNormal[i].xyz, wo);
  indirect[i] = (float4)(gAlbedo[i].xyz * GI_INV_PI * E, 0.0f);
}
