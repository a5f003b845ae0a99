// Light-field probes (McGuire et al. 2017 as seed 004 used them; ALGORITHMS.md §6), updated by ray
// tracing in the DDGI manner (Majercik et al. 2019) instead of cube-map rendering:
//   probe_trace            one work-item per probe ray: the radiance leaving the first surface hit
//                          towards the probe and the hit distance (reference BVH traversal);
//   probe_blend_irradiance one work-item per irradiance texel: E = π Σ max(0, n·ω) L / Σ max(0, n·ω)
//                          over this update's rays, blended with the texel's previous value;
//   probe_blend_distance   one work-item per distance texel: weighted mean and mean² of the hit
//                          distance with weights max(0, n·ω)^GI_PROBE_DISTANCE_EXPONENT, blended;
//   probe_border_*         copy the texels across the octahedral seams into each map's border;
//   probe_relocate         one work-item per probe: DDGI relocation and classification from the
//                          update's rays (Majercik et al. 2021, §5: a probe whose rays hit back
//                          faces is inside geometry; it moves out through the nearest one, or is
//                          switched off when it cannot);
//   probe_shade            one work-item per camera pixel: ρ/π · E from probe_field_irradiance().
// The update kernels (all but probe_shade) take the probes of one update, `slots` (GiProbeUpdate,
// probe_types.h: every probe, or the probes.update_budget next ones of a round-robin order); the
// ray results hold one record per slot and ray.
// Radiance at a ray hit = the hit's emission (only emitters without a punctual stand-in: those
// with one already light the scene through it) + ρ/π · (E_direct + E_probes), where E_direct sums
// every punctual light (stand-ins included) with a shadow ray and E_probes, when multi-bounce is on,
// reads the probes' previous state (each update adds one more bounce). Surfaces are shaded two-sided,
// as the path tracer does; only the diffuse lobe is used (diffuse indirect light only).
#include "common/brdf.h"
#include "common/lights.h"
#include "common/vector_width.h"
#include "gi/probes/probe_field.h"
#include "reference/hit_surface.h"

#ifndef GI_PROBE_DISTANCE_EXPONENT_LOG2
#define GI_PROBE_DISTANCE_EXPONENT_LOG2 6
#endif

inline int probe_total(const GiProbeGrid* g) { return g->count[0] * g->count[1] * g->count[2]; }

inline int3 probe_index3(const GiProbeGrid* g, int probe) {
  return (int3)(probe % g->count[0], (probe / g->count[0]) % g->count[1], probe / (g->count[0] * g->count[1]));
}

// The probe that update slot `slot` updates (GiProbeUpdate, probe_types.h).
inline int probe_of_slot(const GiProbeUpdate* u, int slot, int total) {
  int position = u->first_position + slot;
  if (position >= total) position -= total;
  // Stride 1 (no budget): the index order, without the 64-bit multiply and remainder.
  return u->stride == 1 ? position : (int)((ulong)position * (ulong)u->stride % (ulong)total);
}

inline float probe_slot_hysteresis(const GiProbeUpdate* u, int slot) {
  return slot < u->later_slot ? u->hysteresis : u->later_hysteresis;
}

// rayDirs: this update's unit ray directions (the same for every probe), traced from each probe's
// relocated position, for the probes of `slots` (one work-item per slot and ray). Output per ray,
// at rayResults[slot · rays + ray]: (radiance towards the probe, ±hit distance), the distance
// negative when the ray hit the back of a single-sided surface (for probe_relocate; the blends use
// its magnitude); a miss records zero radiance at grid.max_distance.
kernel void probe_trace(GiProbeGrid grid, GI_BVH_ARGS, global const float4* positions, global const float4* normals,
                        global const float4* tangents, global const uint* triangleInstance,
                        global const uint* instanceEmits, global const GiLight* lights, int lightCount,
                        global const float4* rayDirs, global const float4* irradiance, global const float2* distance,
                        global const float4* probeStates, int multiBounce, GiProbeUpdate slots,
                        global float4* rayResults) {
  int gid = get_global_id(0);
  int slot = gid / grid.rays, ray = gid % grid.rays;
  if (slot >= slots.probes) return;
  int probe = probe_of_slot(&slots, slot, probe_total(&grid));
  GiBvh bvh = GI_BVH_MAKE;
  float3 o = probe_position(&grid, probe_index3(&grid, probe)) + probeStates[probe].xyz;
  float3 d = rayDirs[ray].xyz;
  GiHit hit;
  if (!trace_closest(&bvh, o, d, 0.0f, grid.max_distance, &hit)) {
    rayResults[gid] = (float4)(0.0f, 0.0f, 0.0f, grid.max_distance);
    return;
  }
  PtSurface sf = pt_surface(positions, normals, tangents, &bvh, hit.prim, hit.u, hit.v, true);
  float3 wo = -d, ng = sf.ng, n = sf.n;
  bool backface = dot(ng, wo) < 0.0f && !bvh.materials[sf.material].double_sided;
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
  if (multiBounce) E += probe_field_irradiance(&grid, irradiance, distance, probeStates, sf.p, n, ng, wo);
  L += s.diffuse * GI_INV_PI * E;
  rayResults[gid] = (float4)(L, backface ? -hit.t : hit.t);
}

// The blend kernels: one work-item takes GI_VW texels of one probe's map as the lanes of floatV
// and loops over the update's rays, each ray broadcast to all lanes (the VPL-gather pattern of
// PERFORMANCE_FACTS.md 2: a per-texel loop would run as scalar code). Lanes past the map's last
// texel repeat it and are not stored.

// Unit directions of the texel centres t (row-major in a res × res map), lane-wise
// (probe_texel_direction()).
inline void probe_texel_directionsV(intV t, int res, floatV* dx, floatV* dy, floatV* dz) {
  floatV ox = (convert_floatV(t % res) + 0.5f) / (float)res * 2.0f - 1.0f;
  floatV oy = (convert_floatV(t / res) + 0.5f) / (float)res * 2.0f - 1.0f;
  floatV vz = 1.0f - fabs(ox) - fabs(oy);
  floatV one = (floatV)(1.0f), minusOne = (floatV)(-1.0f);
  floatV fx = (1.0f - fabs(oy)) * GI_SEL(minusOne, one, ox >= 0.0f);
  floatV fy = (1.0f - fabs(ox)) * GI_SEL(minusOne, one, oy >= 0.0f);
  intV lower = vz < 0.0f;
  floatV vx = GI_SEL(ox, fx, lower), vy = GI_SEL(oy, fy, lower);
  floatV inv = 1.0f / sqrt(vx * vx + vy * vy + vz * vz);
  *dx = vx * inv;
  *dy = vy * inv;
  *dz = vz * inv;
}

// Stores lane l of (a, b, c) to map[index of texel t_l] for the valid lanes; `old` lanes come
// from there too. Texel t of probe p: p · (res + 2)² + (t / res + 1) · (res + 2) + t % res + 1.
#define PROBE_TEXEL_INDEX(p, t, res) ((size_t)(p) * ((res) + 2) * ((res) + 2) + ((t) / (res) + 1) * ((res) + 2) + (t) % (res) + 1)

// The probes of `slots`, each with its slot's hysteresis (the weight of the texel's previous
// value: 0 on the probe's first update).
kernel void probe_blend_irradiance(GiProbeGrid grid, global const float4* rayDirs, global const float4* rayResults,
                                   GiProbeUpdate slots, global float4* irradiance) {
  int res = grid.irradiance_res, texels = res * res, groups = (texels + GI_VW - 1) / GI_VW;
  int gid = get_global_id(0), slot = gid / groups, t0 = (gid % groups) * GI_VW;
  if (slot >= slots.probes) return;
  int probe = probe_of_slot(&slots, slot, probe_total(&grid));
  float hysteresis = probe_slot_hysteresis(&slots, slot);
  floatV nx, ny, nz;
  probe_texel_directionsV(min(t0 + (intV)(GI_LANES), texels - 1), res, &nx, &ny, &nz);
  global const float4* rays = rayResults + (size_t)slot * grid.rays;
  floatV zero = (floatV)(0.0f), sx = zero, sy = zero, sz = zero, wsum = zero;
  for (int r = 0; r < grid.rays; ++r) {
    float4 d = rayDirs[r], L = rays[r];
    floatV w = fmax(nx * d.x + ny * d.y + nz * d.z, 0.0f);
    sx += w * L.x;
    sy += w * L.y;
    sz += w * L.z;
    wsum += w;
  }
  floatV scale = M_PI_F / wsum;
  float ex[GI_VW], ey[GI_VW], ez[GI_VW], ws[GI_VW];
  vstoreV(sx * scale, 0, ex);
  vstoreV(sy * scale, 0, ey);
  vstoreV(sz * scale, 0, ez);
  vstoreV(wsum, 0, ws);
  for (int l = 0; l < GI_VW && t0 + l < texels; ++l) {
    if (ws[l] <= 0.0f) continue;  // no ray in this texel's hemisphere this time: keep the old value
    size_t i = PROBE_TEXEL_INDEX(probe, t0 + l, res);
    irradiance[i] = (float4)(mix((float3)(ex[l], ey[l], ez[l]), irradiance[i].xyz, hysteresis), 0.0f);
  }
}

kernel void probe_blend_distance(GiProbeGrid grid, global const float4* rayDirs, global const float4* rayResults,
                                 GiProbeUpdate slots, global float2* distance) {
  int res = grid.distance_res, texels = res * res, groups = (texels + GI_VW - 1) / GI_VW;
  int gid = get_global_id(0), slot = gid / groups, t0 = (gid % groups) * GI_VW;
  if (slot >= slots.probes) return;
  int probe = probe_of_slot(&slots, slot, probe_total(&grid));
  float hysteresis = probe_slot_hysteresis(&slots, slot);
  floatV nx, ny, nz;
  probe_texel_directionsV(min(t0 + (intV)(GI_LANES), texels - 1), res, &nx, &ny, &nz);
  global const float4* rays = rayResults + (size_t)slot * grid.rays;
  floatV zero = (floatV)(0.0f), s1 = zero, s2 = zero, wsum = zero;
  for (int r = 0; r < grid.rays; ++r) {
    float4 d = rayDirs[r];
    float t = fabs(rays[r].w);
    floatV w = fmax(nx * d.x + ny * d.y + nz * d.z, 0.0f);
#pragma unroll
    for (int k = 0; k < GI_PROBE_DISTANCE_EXPONENT_LOG2; ++k) w *= w;  // max(0, cos)^(2^k), no pow()
    s1 += w * t;
    s2 += w * (t * t);
    wsum += w;
  }
  float m1[GI_VW], m2[GI_VW], ws[GI_VW];
  vstoreV(s1 / wsum, 0, m1);
  vstoreV(s2 / wsum, 0, m2);
  vstoreV(wsum, 0, ws);
  for (int l = 0; l < GI_VW && t0 + l < texels; ++l) {
    if (ws[l] <= 0.0f) continue;
    size_t i = PROBE_TEXEL_INDEX(probe, t0 + l, res);
    distance[i] = mix((float2)(m1[l], m2[l]), distance[i], hysteresis);
  }
}

// Border texel (x, y) of a bordered map (x or y is 0 or res + 1) repeats the interior texel that
// lies next to it across the octahedral seam: each edge is mirrored about its middle, and a corner
// takes the opposite interior corner (all four corners are the direction −z). The maps of the
// probes of `slots` (of `probes` in all).
inline int probe_border_source(int x, int y, int res) {
  int side = res + 2, last = res + 1;
  bool ex = x == 0 || x == last, ey = y == 0 || y == last;
  if (ex && ey) return (y == 0 ? res : 1) * side + (x == 0 ? res : 1);
  if (ey) return (y == 0 ? 1 : res) * side + (last - x);
  return (last - y) * side + (x == 0 ? 1 : res);
}

#define PROBE_BORDER_KERNEL(NAME, T)                                       \
  kernel void NAME(global T* map, int res, int probes, GiProbeUpdate slots) { \
    int side = res + 2, gid = get_global_id(0);                            \
    int slot = gid / (side * side), texel = gid % (side * side);           \
    if (slot >= slots.probes) return;                                      \
    int probe = probe_of_slot(&slots, slot, probes);                       \
    int x = texel % side, y = texel / side;                                \
    if (x > 0 && x <= res && y > 0 && y <= res) return;                    \
    global T* m = map + (size_t)probe * side * side;                       \
    m[texel] = m[probe_border_source(x, y, res)];                          \
  }
PROBE_BORDER_KERNEL(probe_border_irradiance, float4)
PROBE_BORDER_KERNEL(probe_border_distance, float2)

// probes.perceptual_blend: the map the shading and the probe rays read holds √E of every texel
// (borders included); the blends keep E itself, so the temporal mean stays a mean of irradiance.
// The maps (mapTexels texels each, borders included) of the probes of `slots` (of `probes`).
kernel void probe_encode_sqrt(global const float4* irradiance, int mapTexels, int probes, GiProbeUpdate slots,
                              global float4* encoded) {
  int gid = get_global_id(0), slot = gid / mapTexels;
  if (slot >= slots.probes) return;
  size_t i = (size_t)probe_of_slot(&slots, slot, probes) * mapTexels + gid % mapTexels;
  encoded[i] = sqrt(irradiance[i]);
}

// DDGI probe relocation and classification (Majercik et al. 2021, "Scaling probe-based real-time
// dynamic global illumination for production", §5), from this update's rays of the probe:
//   - more than `backfaceFraction` of the rays hit back faces: the probe is inside geometry. It
//     moves through the nearest back face to `minFrontface` beyond it; it is classified inactive
//     (state.w = 0) until an update sees it outside;
//   - else, nearer than `minFrontface` to a front face: it moves away from that face to that
//     distance; farther: it moves back towards its grid point by the margin it has.
// A move is taken only while the offset stays inside the ellipsoid of 0.45 × the spacing around
// the grid point (the probe stays in its own cell, so the trilinear weights remain meaningful).
// move = 0: classification only. One work-item per slot of `slots` (the probes just traced).
kernel void probe_relocate(GiProbeGrid grid, global const float4* rayDirs, global const float4* rayResults,
                           float backfaceFraction, float minFrontface, int move, GiProbeUpdate slots,
                           global float4* probeStates) {
  int slot = get_global_id(0);
  if (slot >= slots.probes) return;
  int probe = probe_of_slot(&slots, slot, probe_total(&grid));
  global const float4* rays = rayResults + (size_t)slot * grid.rays;
  int backfaces = 0;
  float closestBack = INFINITY, closestFront = INFINITY;
  float3 backDir = (float3)(0.0f), frontDir = (float3)(0.0f);
  for (int r = 0; r < grid.rays; ++r) {
    float t = rays[r].w;
    float3 d = rayDirs[r].xyz;
    if (t < 0.0f) {
      ++backfaces;
      if (-t < closestBack) { closestBack = -t; backDir = d; }
    } else if (t < closestFront) {
      closestFront = t;
      frontDir = d;
    }
  }
  float4 state = probeStates[probe];
  bool inside = (float)backfaces > backfaceFraction * (float)grid.rays;
  state.w = inside ? 0.0f : 1.0f;
  if (move) {
    float3 offset = state.xyz, moved = offset;
    if (inside) {
      moved += backDir * (closestBack + minFrontface);
    } else if (closestFront < minFrontface) {
      moved -= frontDir * (minFrontface - closestFront);
    } else {
      float len = length(offset);
      if (len > 0.0f) moved -= offset / len * fmin(closestFront - minFrontface, len);
    }
    float3 e = moved / (0.45f * vload3(0, grid.spacing));
    if (dot(e, e) < 1.0f) state.xyz = moved;
  }
  probeStates[probe] = state;
}

// probe_field_irradiance() for GI_VW pixels at once, lanes as floatV (PERFORMANCE_FACTS.md 2:
// a per-pixel loop over the 8 probes would run as scalar code). The formulas are those of
// probe_field.h, written lane-wise. On a CPU (GI_VW > 1) the lanes' map reads are what costs:
// a per-lane record load and its transposition into lanes take ≈ 60 instructions per bilinear
// tap for 16 lanes. But a work-item's adjacent pixels share most of what they read: usually one
// probe cell (the same 8 probes), and per probe a few distance texels and, for the normal, a few
// irradiance texels. So the lanes are taken in passes: one per different cell among them, and
// within it one per different footprint, each reading its texels once as scalars broadcast into
// the lanes' multiply-adds (the lanes not in the pass discard the result). The footprint of the
// normal is the same for the 8 probes and is computed once. With one pixel per work-item
// (GI_VW = 1, GPUs) every read is the pixel's own.
__attribute__((always_inline)) inline void probe_octahedral_footprintV(floatV dx, floatV dy, floatV dz, int res, intV* offset, floatV* tx,
                                        floatV* ty) {
  floatV inv = 1.0f / (fabs(dx) + fabs(dy) + fabs(dz));
  floatV px = dx * inv, py = dy * inv;
  floatV one = (floatV)(1.0f), minusOne = (floatV)(-1.0f);
  intV lower = dz < 0.0f;
  floatV qx = GI_SEL(px, (1.0f - fabs(py)) * GI_SEL(minusOne, one, px >= 0.0f), lower);
  floatV qy = GI_SEL(py, (1.0f - fabs(px)) * GI_SEL(minusOne, one, py >= 0.0f), lower);
  floatV fx = (qx * 0.5f + 0.5f) * (float)res + 0.5f, fy = (qy * 0.5f + 0.5f) * (float)res + 0.5f;
  // fx, fy > −1 for every direction (|q| <= 1 up to rounding), where truncation and the clamp to
  // 0 … res give floor's texel; a NaN direction (background lanes) converts to some integer that
  // the clamp puts in range (its result is not stored).
  // (Vector bounds: oclgrind mis-evaluates min/max/clamp of an integer vector with scalar bounds.)
  intV x0 = clamp(convert_intV(fx), (intV)(0), (intV)(res));
  intV y0 = clamp(convert_intV(fy), (intV)(0), (intV)(res));
  *tx = clamp(fx - convert_floatV(x0), 0.0f, 1.0f);
  *ty = clamp(fy - convert_floatV(y0), 0.0f, 1.0f);
  *offset = y0 * (res + 2) + x0;
}

// Bilinear weights of the taps (x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1) for the
// fractions (tx, ty): a bilinear lookup is then one multiply-add per tap and channel (with the
// same texel for all lanes, a scalar from memory broadcast into the multiply-add).
typedef struct {
  floatV w00, w10, w01, w11;
} ProbeBilinearV;

__attribute__((always_inline)) inline ProbeBilinearV probe_bilinear_weightsV(floatV tx, floatV ty) {
  ProbeBilinearV q;
  floatV sx = 1.0f - tx, sy = 1.0f - ty;
  q.w00 = sx * sy;
  q.w10 = tx * sy;
  q.w01 = sx * ty;
  q.w11 = tx * ty;
  return q;
}

// What a probe's weight needs (probe_sightV, then the distance passes, then probe_sight_weightV):
// the probe's distance footprint (texel offset i00 of its top-left tap, into the whole map array
// or the probe's map, and the bilinear fractions tx, ty), the trilinear weight × active flag w,
// the backface term, the distance r from the probe to the biased point and the bilinear distance
// moments (mean, mean²) there.
typedef struct {
  intV i00;
  floatV tx, ty, w, backface, r, mean, mean2;
} ProbeSightV;

#if GI_VW > 1
// The smallest of the lanes' values.
inline int probe_lane_min(intV v) {
#if GI_VW == 16
  int8 a = min(v.lo, v.hi);
  int4 b = min(a.lo, a.hi);
#else
  int4 b = min(v.lo, v.hi);
#endif
  int2 c = min(b.lo, b.hi);
  return min(c.x, c.y);
}

// Whether any lane of a mask (lanes −1 or 0) is set. With AVX-512 (16 lanes) the lanes' sign bits as
// a mask register (vpmovd2m), with AVX (8 lanes) as a general register (vmovmskps): one instruction
// each; elsewhere the lane minimum.
#if defined(__has_builtin) && defined(GI_DEVICE_CPU) && GI_VW == 16 && defined(__AVX512DQ__)
#if __has_builtin(__builtin_ia32_cvtd2mask512)
#define PROBE_MASK_BITS(m) __builtin_ia32_cvtd2mask512(m)
#endif
#elif defined(__has_builtin) && defined(GI_DEVICE_CPU) && GI_VW == 8 && defined(__AVX__)
#if __has_builtin(__builtin_ia32_movmskps256)
#define PROBE_MASK_BITS(m) __builtin_ia32_movmskps256(as_float8(m))
#endif
#endif
inline int probe_lane_any(intV m) {
#ifdef PROBE_MASK_BITS
  return PROBE_MASK_BITS(m) != 0;
#else
  return probe_lane_min(m) != 0;
#endif
}

// Lane l of v (l varies). With AVX-512 (16 lanes) or AVX2 (8 lanes) one lane permutation (vpermd)
// of v by a vector of l; elsewhere v through a private array. (Through the array with AVX-512, a
// 64-byte vector stored in 16-byte parts and a 4-byte load of one of them, the distance passes' key
// reads cost 6–10 % of the shading: docs/PERFORMANCE.md, "probes: the 8 probes' weights without
// branches, lane keys by permutation".) __has_builtin is tested only where PROBE_MASK_BITS says it
// exists.
#ifdef PROBE_MASK_BITS
#if GI_VW == 16 && __has_builtin(__builtin_ia32_permvarsi512)
#define PROBE_LANE_PERMUTE
inline int probe_lane(intV v, int l) { return __builtin_ia32_permvarsi512(v, (intV)(l))[0]; }
#elif GI_VW == 8 && defined(__AVX2__) && __has_builtin(__builtin_ia32_permvarsi256)
#define PROBE_LANE_PERMUTE
inline int probe_lane(intV v, int l) { return __builtin_ia32_permvarsi256(v, (intV)(l))[0]; }
#endif
#endif
#ifndef PROBE_LANE_PERMUTE
inline int probe_lane(intV v, int l) {
  int lanes[GI_VW];
  vstoreV(v, 0, lanes);
  return lanes[l];
}
#endif

// The key of a lane set in `pending`, INT_MAX when none is (keys are texel offsets and cell
// indices, far below INT_MAX): with AVX-512 the first such lane's (mask bits, tzcnt, one lane
// permutation), elsewhere the smallest (a lane reduction). The pass loops take the lanes key by
// key with it: one call per pass both finds the next key and ends the loop (PoCL turns any() and
// all() of 16 lanes into a chain of per-lane tests and branches). Each lane's result depends only
// on its own key, so the order of the passes does not change it.
#ifdef PROBE_LANE_PERMUTE
inline int probe_next_key(intV keys, intV pending) {
  int bits = PROBE_MASK_BITS(pending);
  return bits ? probe_lane(keys, __builtin_ctz((uint)bits)) : INT_MAX;
}
// The first and the last lane set in a mask that has one.
inline int probe_first_lane(intV m) { return __builtin_ctz((uint)PROBE_MASK_BITS(m)); }
inline int probe_last_lane(intV m) { return 31 - __builtin_clz((uint)PROBE_MASK_BITS(m)); }
#else
inline int probe_next_key(intV keys, intV pending) { return probe_lane_min(GI_SEL((intV)(INT_MAX), keys, pending)); }
inline int probe_first_lane(intV m) { return probe_next_key((intV)(GI_LANES), m); }
inline int probe_last_lane(intV m) { return -probe_next_key(-(intV)(GI_LANES), m); }
#endif

// PROBE_DISTANCE_PASS(s, q, map, side, o): the lanes of sight s whose distance footprint is texel
// offset o take the bilinear (mean, mean²) with weights q from the four float2 records there, read
// as scalars.
#define PROBE_DISTANCE_PASS(s, q, map, side, o)                                                                    \
  {                                                                                                             \
    intV these = (s).i00 == (o);                                                                                \
    global const float* t = (map) + 2 * (o);                                                                    \
    (s).mean = GI_SEL((s).mean, (q).w00 * t[0] + (q).w10 * t[2] + (q).w01 * t[2 * (side)] +                    \
                                    (q).w11 * t[2 * (side) + 2], these);                                        \
    (s).mean2 = GI_SEL((s).mean2, (q).w00 * t[1] + (q).w10 * t[3] + (q).w01 * t[2 * (side) + 1] +              \
                                      (q).w11 * t[2 * (side) + 3], these);                                      \
  }

// Bilinear (mean, mean²) of one probe's distance map (float2 texels) at the lanes' footprints
// s->i00, for the lanes set in `lanes`. The directions from one probe to a work-item's adjacent
// pixels usually fall in one or two texels (a distance texel spans 2/res of the octahedron): one
// pass per different footprint, its four records read as scalars. The first two passes take the
// footprints of the first and the last lane of `lanes` (firstLane, lastLane: opposite corners of
// the tile, or of its part in this cell pass), unconditionally, even when they are the same
// footprint: no lane reduction and no branch on the footprints, which cost more than a redundant
// pass (Sponza 640×360: the two are the same in 76 % of the calls). Returns the lanes with a third
// footprint or more (12 % of the calls), for probe_distance_restV, which the caller runs after all
// 8 probes of the cell: the 8 probes' weights are then one block of code without branches (with
// the loop inside each probe's code the shading took 3 % more CPU time; docs/PERFORMANCE.md).
__attribute__((always_inline)) inline intV probe_distance_cornersV(global const float* map, ProbeSightV* s, intV lanes,
                                                                   int firstLane, int lastLane, int side) {
  int first = probe_lane(s->i00, firstLane), last = probe_lane(s->i00, lastLane);
  ProbeBilinearV q = probe_bilinear_weightsV(s->tx, s->ty);
  s->mean = s->mean2 = (floatV)(0.0f);
  PROBE_DISTANCE_PASS(*s, q, map, side, first)
  PROBE_DISTANCE_PASS(*s, q, map, side, last)
  return lanes & (s->i00 != first) & (s->i00 != last);
}

// The lanes `pending` of probe_distance_cornersV: one pass per further footprint, one lane
// reduction each.
__attribute__((always_inline)) inline void probe_distance_restV(global const float* map, ProbeSightV* s, intV pending,
                                                                int side) {
  ProbeBilinearV q = probe_bilinear_weightsV(s->tx, s->ty);
  for (int o = probe_next_key(s->i00, pending); o != INT_MAX; o = probe_next_key(s->i00, pending)) {
    PROBE_DISTANCE_PASS(*s, q, map, side, o)
    pending &= s->i00 != o;
  }
}
#undef PROBE_DISTANCE_PASS
#else
// One pixel per work-item: the distance map's four taps at texel offset i00 (a row's two taps
// one 128-bit record).
__attribute__((always_inline)) inline void probe_distance_pixelV(global const float* map, intV i00, int side,
                                                                 ProbeBilinearV q, floatV* mean, floatV* mean2) {
  floatV am, am2, bm, bm2, cm, cm2, dm, dm2;
  GI_GATHER_SPAN4(float, map, i00 * 2, am, am2, bm, bm2)
  GI_GATHER_SPAN4(float, map, (i00 + side) * 2, cm, cm2, dm, dm2)
  *mean = q.w00 * am + q.w10 * bm + q.w01 * cm + q.w11 * dm;
  *mean2 = q.w00 * am2 + q.w10 * bm2 + q.w01 * cm2 + q.w11 * dm2;
}
#endif

// Trilinear weight of corner c (bit 0: +x, bit 1: +y, bit 2: +z) of a probe cell at fractions
// (ax, ay, az).
inline floatV probe_trilinearV(int c, floatV ax, floatV ay, floatV az) {
  return ((c & 1) ? ax : 1.0f - ax) * ((c & 2) ? ay : 1.0f - ay) * ((c & 4) ? az : 1.0f - az);
}

// What the 8 probes of a pixel share: the biased point xb, the normal's irradiance footprint
// (texel offset and bilinear weights) and the running sums.
typedef struct {
  float3V x, n, xb;
  intV irrOffset;
  ProbeBilinearV irrTaps;
  floatV Ex, Ey, Ez, wsum;
} ProbeBlendV;

// One probe's weight, part 1: from its relocated position pp, with w its trilinear weight times
// its active flag, the backface term, the distance to the biased point and the distance map
// footprint of the direction to it (texel offset distBase + the footprint's).
__attribute__((always_inline)) inline ProbeSightV probe_sightV(const GiProbeGrid* g, const ProbeBlendV* b, floatV w,
                                                               floatV ppx, floatV ppy, floatV ppz, intV distBase) {
  ProbeSightV s;
  floatV tpx = ppx - b->x.x, tpy = ppy - b->x.y, tpz = ppz - b->x.z;
  floatV len = sqrt(tpx * tpx + tpy * tpy + tpz * tpz);
  floatV cosine = (b->n.x * tpx + b->n.y * tpy + b->n.z * tpz) / len;
  s.w = w;
  s.backface = GI_SEL((floatV)(1.0f), PROBE_BACKFACE_WEIGHT(g, cosine), len > 0.0f);
  floatV fpx = b->xb.x - ppx, fpy = b->xb.y - ppy, fpz = b->xb.z - ppz;
  s.r = sqrt(fpx * fpx + fpy * fpy + fpz * fpz);
  intV far = s.r > 0.0f;
  intV distOffset;
  probe_octahedral_footprintV(GI_SEL(b->n.x, fpx, far), GI_SEL(b->n.y, fpy, far), GI_SEL(b->n.z, fpz, far),
                              g->distance_res, &distOffset, &s.tx, &s.ty);
  s.i00 = distBase + distOffset;
  return s;
}

// One probe's weight, part 2, once s's distance moments are read: w × the crushed backface term ×
// Chebyshev visibility.
__attribute__((always_inline)) inline floatV probe_sight_weightV(const ProbeSightV* s) {
  floatV mean = s->mean, variance = fabs(s->mean2 - mean * mean), d = s->r - mean;
  floatV cheb = variance / fmax(variance + d * d, 1e-30f), v = (floatV)(1.0f);
#pragma unroll
  for (int k = 0; k < GI_PROBE_CHEBYSHEV_POWER; ++k) v *= cheb;
  floatV visible = s->backface * GI_SEL((floatV)(1.0f), v, s->r > mean);
  PROBE_CRUSH_WEIGHT(visible)
  return s->w * visible;
}

#if GI_VW > 1
// Σ_c weight[c] · (bilinear irradiance of probe c's map at the lanes' footprint), for the 8 maps
// irrMaps[c], all lanes reading the same texel offset o: scalar taps broadcast into multiply-adds.
__attribute__((always_inline)) inline float3V probe_irradiance_sharedV(global const float* const* irrMaps, int o,
                                                                       int side, ProbeBilinearV q,
                                                                       const floatV* weight) {
  // Σ_c weight[c] · Σ_tap q_tap · texel = Σ_tap q_tap · (Σ_c weight[c] · texel): per tap and
  // channel the 8 probes' weighted texels first (one multiply-add each, its texel a broadcast
  // scalar), then the four bilinear weights once, 108 instead of 128 vector operations.
  floatV zero = (floatV)(0.0f);
  floatV ar = zero, ag = zero, ab = zero, br = zero, bg = zero, bb = zero;
  floatV cr = zero, cg = zero, cb = zero, dr = zero, dg = zero, db = zero;
#pragma unroll
  for (int c = 0; c < 8; ++c) {
    global const float* t = irrMaps[c] + 4 * o;
    global const float* u = t + 4 * side;
    floatV w = weight[c];
    ar += w * t[0];
    ag += w * t[1];
    ab += w * t[2];
    br += w * t[4];
    bg += w * t[5];
    bb += w * t[6];
    cr += w * u[0];
    cg += w * u[1];
    cb += w * u[2];
    dr += w * u[4];
    dg += w * u[5];
    db += w * u[6];
  }
  return f3v(q.w00 * ar + q.w10 * br + q.w01 * cr + q.w11 * dr, q.w00 * ag + q.w10 * bg + q.w01 * cg + q.w11 * dg,
             q.w00 * ab + q.w10 * bb + q.w01 * cb + q.w11 * db);
}

// The 8 probes of cell `cell` for the lanes set in `lanes` (the others get meaningless values):
// scalar probe states and positions broadcast; first the 8 weights, then the irradiance. The
// normal's irradiance footprint is the same for the 8 probes; a work-item's normals fall in 4
// different footprints on average (Sponza 640×360, 16 lanes: normal maps spread them; an
// irradiance texel spans 2/res of the octahedron), each one pass of scalar taps broadcast into
// its lanes' multiply-adds (16 instructions per probe), which costs less than per-lane records
// and their transposition (≈ 60 instructions per tap and probe) even at 8 passes. Sets b's sums.
__attribute__((always_inline)) inline void probe_cell_sharedV(const GiProbeGrid* g, ProbeBlendV* b, intV lanes,
                                                               global const float* irradiance,
                                                               global const float* distance,
                                                               global const float* probeStates, int cell,
                                                               floatV ax, floatV ay, floatV az) {
  int cx = g->count[0], cy = g->count[1], cz = g->count[2];
  int ux = cell % cx, uy = (cell / cx) % cy, uz = cell / (cx * cy);
  float sx = g->spacing[0], sy = g->spacing[1], sz = g->spacing[2];
  float ox = g->origin[0], oy = g->origin[1], oz = g->origin[2];
  int iside = g->irradiance_res + 2, dside = g->distance_res + 2;
  int irrTexels = iside * iside, distTexels = dside * dside;
  floatV weight[8];
  ProbeSightV sight[8];
  intV rest[8];
  global const float* irrMaps[8];
  global const float* distMaps[8];
  // The first and the last lane of this cell pass (once per pass; the distance lookups start there).
  int firstLane = probe_first_lane(lanes), lastLane = probe_last_lane(lanes);
#pragma unroll
  for (int c = 0; c < 8; ++c) {
    int offx = c & 1, offy = (c >> 1) & 1, offz = c >> 2;
    floatV w = probe_trilinearV(c, ax, ay, az);
    int pix = min(ux + offx, cx - 1), piy = min(uy + offy, cy - 1), piz = min(uz + offz, cz - 1);
    int probe = (piz * cy + piy) * cx + pix;
    float4 state = vload4(probe, probeStates);  // relocation offset, active flag
    w *= state.w;
    distMaps[c] = distance + (size_t)probe * distTexels * 2;
    sight[c] = probe_sightV(g, b, w, (floatV)(ox + (float)pix * sx + state.x), (floatV)(oy + (float)piy * sy + state.y),
                            (floatV)(oz + (float)piz * sz + state.z), (intV)(0));
    rest[c] = probe_distance_cornersV(distMaps[c], &sight[c], lanes, firstLane, lastLane, dside);
    weight[c] = probe_sight_weightV(&sight[c]);
    irrMaps[c] = irradiance + (size_t)probe * irrTexels * 4;
  }
  // The probes with lanes in a third distance footprint or more: their further passes and weights
  // (unrolled: as a loop over c, sight[] indexed at run time, the shading took 9 % more CPU time;
  // one test of all 8 probes' lanes before these 8 took 15 % more).
#pragma unroll
  for (int c = 0; c < 8; ++c)
    if (probe_lane_any(rest[c])) {
      probe_distance_restV(distMaps[c], &sight[c], rest[c], dside);
      weight[c] = probe_sight_weightV(&sight[c]);
    }
  b->wsum = (floatV)(0.0f);
#pragma unroll
  for (int c = 0; c < 8; ++c) b->wsum += weight[c];
  float3V e = f3v((floatV)(0.0f), (floatV)(0.0f), (floatV)(0.0f));
  intV pending = lanes;
  for (int o = probe_next_key(b->irrOffset, pending); o != INT_MAX; o = probe_next_key(b->irrOffset, pending)) {
    intV these = b->irrOffset == o;
    e = selV(e, probe_irradiance_sharedV(irrMaps, o, iside, b->irrTaps, weight), these);
    pending &= ~these;
  }
  b->Ex = e.x;
  b->Ey = e.y;
  b->Ez = e.z;
}
#else
// One pixel per work-item: weight × the bilinear irradiance of the map at texel offset i00.
__attribute__((always_inline)) inline float3V probe_irradiance_pixelV(global const float* map, intV i00, int side,
                                                                      ProbeBilinearV q, floatV weight) {
  floatV ar, ag, ab, br, bg, bb, cr, cg, cb, dr, dg, db, unused;
  GI_GATHER_AOS4(float, map, i00, ar, ag, ab, unused)
  GI_GATHER_AOS4(float, map, i00 + 1, br, bg, bb, unused)
  GI_GATHER_AOS4(float, map, i00 + side, cr, cg, cb, unused)
  GI_GATHER_AOS4(float, map, i00 + side + 1, dr, dg, db, unused)
  floatV a = weight * q.w00, b = weight * q.w10, c = weight * q.w01, d = weight * q.w11;
  return f3v(a * ar + b * br + c * cr + d * dr, a * ag + b * bg + c * cg + d * dg, a * ab + b * bb + c * cb + d * db);
}

// One pixel per work-item: the 8 probes of its cell (bx, by, bz). Sets b's sums.
__attribute__((always_inline)) inline void probe_cell_pixelV(const GiProbeGrid* g, ProbeBlendV* b,
                                                              global const float* irradiance,
                                                              global const float* distance,
                                                              global const float* probeStates, intV bx, intV by,
                                                              intV bz, floatV ax, floatV ay, floatV az) {
  int cx = g->count[0], cy = g->count[1], cz = g->count[2];
  float sx = g->spacing[0], sy = g->spacing[1], sz = g->spacing[2];
  float ox = g->origin[0], oy = g->origin[1], oz = g->origin[2];
  int iside = g->irradiance_res + 2, dside = g->distance_res + 2;
  int irrTexels = iside * iside, distTexels = dside * dside;
  floatV zero = (floatV)(0.0f);
  b->Ex = b->Ey = b->Ez = b->wsum = zero;
#pragma unroll
  for (int c = 0; c < 8; ++c) {
    int offx = c & 1, offy = (c >> 1) & 1, offz = c >> 2;
    floatV w = probe_trilinearV(c, ax, ay, az);
    intV pix = min(bx + offx, cx - 1), piy = min(by + offy, cy - 1), piz = min(bz + offz, cz - 1);
    intV probe = (piz * cy + piy) * cx + pix;
    floatV movedX, movedY, movedZ, active;  // the probe's state: relocation offset, active flag
    GI_GATHER_AOS4(float, probeStates, probe, movedX, movedY, movedZ, active)
    w *= active;
    ProbeSightV sight = probe_sightV(g, b, w, ox + convert_floatV(pix) * sx + movedX,
                                     oy + convert_floatV(piy) * sy + movedY, oz + convert_floatV(piz) * sz + movedZ,
                                     probe * distTexels);
    probe_distance_pixelV(distance, sight.i00, dside, probe_bilinear_weightsV(sight.tx, sight.ty), &sight.mean,
                          &sight.mean2);
    w = probe_sight_weightV(&sight);
    b->wsum += w;
    float3V e = probe_irradiance_pixelV(irradiance, probe * irrTexels + b->irrOffset, iside, b->irrTaps, w);
    b->Ex += e.x;
    b->Ey += e.y;
    b->Ez += e.z;
  }
}
#endif

__attribute__((always_inline)) inline float3V probe_field_irradianceV(const GiProbeGrid* g, global const float* irradiance,
                                       global const float* distance, global const float* probeStates, float3V x,
                                       float3V n, float3V ng, float3V wo) {
  int cx = g->count[0], cy = g->count[1], cz = g->count[2];
  float sx = g->spacing[0], sy = g->spacing[1], sz = g->spacing[2];
  float ox = g->origin[0], oy = g->origin[1], oz = g->origin[2];
  ProbeBlendV b;
  b.x = x;
  b.n = n;
  b.xb = f3v(x.x + ng.x * g->normal_bias + wo.x * g->view_bias, x.y + ng.y * g->normal_bias + wo.y * g->view_bias,
             x.z + ng.z * g->normal_bias + wo.z * g->view_bias);
  floatV rx = (b.xb.x - ox) / sx, ry = (b.xb.y - oy) / sy, rz = (b.xb.z - oz) / sz;
  intV zeroI = (intV)(0);
  intV bx = clamp(convert_intV(GI_SEL((floatV)(0.0f), floor(rx), rx == rx)), zeroI, (intV)(max(cx - 2, 0)));
  intV by = clamp(convert_intV(GI_SEL((floatV)(0.0f), floor(ry), ry == ry)), zeroI, (intV)(max(cy - 2, 0)));
  intV bz = clamp(convert_intV(GI_SEL((floatV)(0.0f), floor(rz), rz == rz)), zeroI, (intV)(max(cz - 2, 0)));
  floatV ax = clamp(rx - convert_floatV(bx), 0.0f, 1.0f), ay = clamp(ry - convert_floatV(by), 0.0f, 1.0f),
         az = clamp(rz - convert_floatV(bz), 0.0f, 1.0f);
  floatV itx, ity;
  probe_octahedral_footprintV(n.x, n.y, n.z, g->irradiance_res, &b.irrOffset, &itx, &ity);
  b.irrTaps = probe_bilinear_weightsV(itx, ity);
  floatV zero = (floatV)(0.0f);
#if GI_VW > 1
  // Most work-items' pixels lie in one probe cell (adjacent pixels; Sponza 640×360, 16 lanes: 1.3
  // different cells on average): per cell among the lanes, its 8 probes, their states and
  // positions are the same for all lanes (scalar loads, broadcast), and their map taps are read
  // once per different footprint. One pass per cell, the other lanes' results discarded.
  intV cell = (bz * cy + by) * cx + bx;
  b.Ex = b.Ey = b.Ez = b.wsum = zero;
  intV pending = (intV)(-1);
  for (int next = probe_next_key(cell, pending); next != INT_MAX; next = probe_next_key(cell, pending)) {
    intV these = cell == next;
    ProbeBlendV other = b;
    probe_cell_sharedV(g, &other, these, irradiance, distance, probeStates, next, ax, ay, az);
    b.Ex = GI_SEL(b.Ex, other.Ex, these);
    b.Ey = GI_SEL(b.Ey, other.Ey, these);
    b.Ez = GI_SEL(b.Ez, other.Ez, these);
    b.wsum = GI_SEL(b.wsum, other.wsum, these);
    pending &= ~these;
  }
#else
  probe_cell_pixelV(g, &b, irradiance, distance, probeStates, bx, by, bz, ax, ay, az);
#endif
  floatV inv = GI_SEL(zero, 1.0f / b.wsum, b.wsum > 0.0f);
  floatV ex = b.Ex * inv, ey = b.Ey * inv, ez = b.Ez * inv;
#if GI_PROBE_PERCEPTUAL_BLEND
  return f3v(ex * ex, ey * ey, ez * ez);  // the maps read hold √E
#else
  return f3v(ex, ey, ez);
#endif
}

// A work-item's pixels form a tile of 2^shift × GI_VW / 2^shift pixels, lane l at
// (l mod 2^shift, l / 2^shift): a compact tile lies in fewer probe cells and map footprints than a
// row of GI_VW pixels, so it takes fewer passes. 16 lanes: 8 × 2 at full resolution, 4 × 4 at
// down > 1 (the faster shapes in A/B runs, docs/PERFORMANCE.md); 8 lanes: 4 × 2; one lane: 1 × 1.
// The host sizes the launch from the same shapes (ProbeField::shade).
#define PROBE_TILE_SHIFT(down) (GI_VW == 16 ? ((down) == 1 ? 3 : 2) : GI_VW == 8 ? 2 : 0)

#if GI_VW > 1
// The float4 records of a full-resolution tile whose rows start at p and p + stride (floats), as
// four floatV: a 4-pixel row segment is one 16-float load.
#if GI_VW == 16
#define PROBE_TILE_LOAD4(p, stride, X, Y, Z, W)                                                             \
  {                                                                                                         \
    float16 a_ = vload16(0, p), b_ = vload16(1, p), c_ = vload16(0, (p) + (stride)),                        \
            d_ = vload16(1, (p) + (stride));                                                                \
    X = (float16)(a_.s048c, b_.s048c, c_.s048c, d_.s048c);                                                  \
    Y = (float16)(a_.s159d, b_.s159d, c_.s159d, d_.s159d);                                                  \
    Z = (float16)(a_.s26ae, b_.s26ae, c_.s26ae, d_.s26ae);                                                  \
    W = (float16)(a_.s37bf, b_.s37bf, c_.s37bf, d_.s37bf);                                                  \
  }
#else
#define PROBE_TILE_LOAD4(p, stride, X, Y, Z, W)                 \
  {                                                             \
    float16 a_ = vload16(0, p), b_ = vload16(0, (p) + (stride)); \
    X = (float8)(a_.s048c, b_.s048c);                           \
    Y = (float8)(a_.s159d, b_.s159d);                           \
    Z = (float8)(a_.s26ae, b_.s26ae);                           \
    W = (float8)(a_.s37bf, b_.s37bf);                           \
  }
#endif
#endif

#if GI_VW > 1
// The tiles' G-buffer reads missed the caches (≈ 20 % of the kernel's perf samples on the loads
// of PROBE_TILE_LOAD4): a tile row is tileW float4 records (two 64-byte lines at 16 lanes) of
// each of the four buffers, and the work-items of a work-group row read one short run of them
// before jumping 2 rows down, too short a stream for the hardware prefetcher. So each work-item
// of a full-resolution tile prefetches the rows of the tile below it: the items of a work-group
// run in order on one CPU core, x fastest, so that tile is read one work-group row (8 items)
// later. clang's __builtin_prefetch, as PoCL's prefetch() is a no-op (as vct_inject and the rsm
// gather do); CPU devices only (GI_VW > 1). Results unchanged; −11 % CPU time (docs/PERFORMANCE.md,
// "probes: G-buffer prefetch, distance passes").
inline void probe_prefetch_tile_below(global const float* P, global const float* G, global const float* N,
                                      global const float* A, size_t first, int stride, int tileW, int tileH) {
  for (int r = tileH; r < 2 * tileH; ++r)
    for (int k = 0; k < tileW / 4; ++k) {
      size_t at = first + (size_t)r * stride + 16 * k;
      __builtin_prefetch(P + at);
      __builtin_prefetch(G + at);
      __builtin_prefetch(N + at);
      __builtin_prefetch(A + at);
    }
}
#endif

// One work-item: a tile of pixels (u, v) of a (⌈W/down⌉ × ⌈H/down⌉) image, pixel (u, v)
// evaluated at camera pixel (u·down, v·down): down = 1 writes the indirect radiance ρ/π · E,
// down > 1 writes E for the geometry-aware upsampler (gi/filters). Background: 0.
kernel void probe_shade(GiProbeGrid grid, global const float4* irradiance, global const float2* distance,
                        global const float4* probeStates, GiView camera,
                        global const float4* gPosition, global const float4* gGeoNormal, global const float4* gNormal,
                        global const float4* gAlbedo, int down, global float4* out) {
  int shift = PROBE_TILE_SHIFT(down), tileW = 1 << shift, tileH = GI_VW >> shift;
  int u0 = get_global_id(0) * tileW, v0 = get_global_id(1) * tileH;
  int lw = (camera.width + down - 1) / down, lh = (camera.height + down - 1) / down;
  if (u0 >= lw || v0 >= lh) return;
  // Camera pixel of each lane (lanes past the image's edge repeat its last pixel).
  intV u = min((intV)(u0) + ((intV)(GI_LANES) & (tileW - 1)), (intV)(lw - 1));
  intV v = min((intV)(v0) + ((intV)(GI_LANES) >> shift), (intV)(lh - 1));
  intV i = min(v * down, (intV)(camera.height - 1)) * camera.width + min(u * down, (intV)(camera.width - 1));
  global const float* P = (global const float*)gPosition;
  global const float* G = (global const float*)gGeoNormal;
  global const float* N = (global const float*)gNormal;
  global const float* A = (global const float*)gAlbedo;
  floatV pw, unused;
  float3V x, ng, n, alb;
  // The lanes' G-buffer records: a whole tile's rows are contiguous vector loads (down = 1), else
  // one 128-bit load per lane.
  int fullTile = u0 + tileW <= lw && v0 + tileH <= lh;
#if GI_VW > 1
  size_t first = (size_t)v0 * camera.width + u0;
  int stride = 4 * camera.width;
  if (down == 1 && fullTile) {
    if (v0 + 2 * tileH <= lh) probe_prefetch_tile_below(P, G, N, A, 4 * first, stride, tileW, tileH);
    PROBE_TILE_LOAD4(P + 4 * first, stride, x.x, x.y, x.z, pw)
    PROBE_TILE_LOAD4(G + 4 * first, stride, ng.x, ng.y, ng.z, unused)
    PROBE_TILE_LOAD4(N + 4 * first, stride, n.x, n.y, n.z, unused)
  } else
#endif
  {
    GI_GATHER_AOS4(float, P, i, x.x, x.y, x.z, pw)
    GI_GATHER_AOS4(float, G, i, ng.x, ng.y, ng.z, unused)
    GI_GATHER_AOS4(float, N, i, n.x, n.y, n.z, unused)
  }
  float3V wo;
  if (camera.orthographic) {
    float3 w = -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz);
    wo = f3v((floatV)(w.x), (floatV)(w.y), (floatV)(w.z));
  } else {
    floatV dx = camera.eye[0] - x.x, dy = camera.eye[1] - x.y, dz = camera.eye[2] - x.z;
    floatV inv = 1.0f / sqrt(dx * dx + dy * dy + dz * dz);
    wo = f3v(dx * inv, dy * inv, dz * inv);
  }
  float3V E = probe_field_irradianceV(&grid, (global const float*)irradiance, (global const float*)distance,
                                      (global const float*)probeStates, x, n, ng, wo);
  if (down == 1) {
#if GI_VW > 1
    if (fullTile)
      PROBE_TILE_LOAD4(A + 4 * first, stride, alb.x, alb.y, alb.z, unused)
    else
#endif
      GI_GATHER_AOS4(float, A, i, alb.x, alb.y, alb.z, unused)
    E = f3v(alb.x * GI_INV_PI * E.x, alb.y * GI_INV_PI * E.y, alb.z * GI_INV_PI * E.z);
  }
  intV surface = pw != 0.0f;
  floatV zero = (floatV)(0.0f);
  floatV ox = GI_SEL(zero, E.x, surface), oy = GI_SEL(zero, E.y, surface), oz = GI_SEL(zero, E.z, surface);
#if GI_VW > 1
  // A whole tile: lanes 4k … 4k + 3 are 4 adjacent pixels of a tile row, one 16-float store each
  // (through a private array first, the stores and reloads cost more: docs/PERFORMANCE.md).
  if (fullTile) {
#define PROBE_STORE4(k, a, b, c, d)                                                                         \
  vstore16((float16)(ox.a, oy.a, oz.a, zero.a, ox.b, oy.b, oz.b, zero.b, ox.c, oy.c, oz.c, zero.c, ox.d, oy.d, \
                     oz.d, zero.d),                                                                         \
           0, (global float*)(out + (size_t)(v0 + ((4 * (k)) >> shift)) * lw + u0 + ((4 * (k)) & (tileW - 1))));
    PROBE_STORE4(0, s0, s1, s2, s3)
    PROBE_STORE4(1, s4, s5, s6, s7)
#if GI_VW == 16
    PROBE_STORE4(2, s8, s9, sa, sb)
    PROBE_STORE4(3, sc, sd, se, sf)
#endif
#undef PROBE_STORE4
    return;
  }
#endif
  float tmp[4 * GI_VW];
  GI_AOS4_STORE(tmp, ox, oy, oz, zero)
  for (int l = 0; l < GI_VW; ++l) {
    int ul = u0 + (l & (tileW - 1)), vl = v0 + (l >> shift);
    if (ul < lw && vl < lh) out[(size_t)vl * lw + ul] = vload4(l, tmp);
  }
}
