// Second-order illumination (Cochran & Steele 2007, seed 002; ALGORITHMS.md §2.6).
//
// Indirect lights: Halton points on the unit sphere around the light, the first N inside its cone
// (chosen on the host, src/gi/second_order/second_order_lights.cpp), each projected into the RSM
// and turned into a VPL (kernels/gi/vpl layout) carrying the light's power over Ω_cone/N.
// Negative lights: at M surface pixels picked by a 2D Halton sequence over the screen, the
// illumination the indirect lights deliver to the *back* side of the surface, E⁻ (receiver cosine
// max(0, +n·ω)), becomes a VPL with negative flux −E⁻·A_pixel·(valid pixels)/M emitting along the
// E⁻-weighted mean propagation direction: the light the visible surface blocks, removed from the
// receivers behind it. Final indirect: L = ρ/π · max(0, E_s − E_n).
// Multi-resolution: the gather runs at half resolution (so_shade_low on the pixels (2u, 2v)), is
// upsampled geometry-aware, and every pixel whose shading normal or view depth differs
// from its parent (2⌊x/2⌋, 2⌊y/2⌋) beyond the thresholds is re-shaded at full resolution. The list of
// those pixels is built here (flags, row counts, one scan, row-wise compaction): never read back.
//
//   so_place_indirect   one work-item per indirect light of one light
//   so_flag             GI_VW pixels of a row per work-item: bit 0 = re-shade at full resolution,
//                       bit 1 = surface
//   so_row_counts       one work-item per row: flagged and surface pixels of the row
//   so_scan_rows        one work-item: row offsets, totals (counters[0] flagged, [1] surface pixels)
//   so_pick_negative    one work-item: first M surface pixels along the screen Halton sequence
//                       (counters[2] = how many were found)
//   so_negative_lights  one work-item per negative light
//   so_shade_low        GI_VW half-resolution pixels of a row per work-item: E over all lights at
//                       the full-resolution pixel (2u, 2v), read in place (no copied G-buffer)
//   so_compact          one work-item per row: list of flagged pixels + their SoA planes
//   so_refine           GI_VW list entries per work-item: E over all lights, L = ρ/π·max(0, E);
//                       with GI_VPL_VISIBILITY (vpl.visibility=rays) one shadow ray per pair
#include "common/math.h"
#include "common/shared_types.h"
#include "common/vector_width.h"
#include "gi/vpl/vpl_pair.h"
#include "gi/vpl/vpl_visibility.h"

#define SO_FLAG_RESHADE 1
#define SO_FLAG_SURFACE 2

// samples[k]: perspective RSM: unit direction (x, y, z) in the light frame, z along the RSM axis,
// x right, y up; orthographic RSM (directional light): (u, v) in [0, 1)² over the RSM image.
// weight: perspective: Ω_accept/N, the solid angle each indirect light stands for (sr);
// orthographic: res²/N, the RSM texels each stands for.
kernel void so_place_indirect(GiView view, global const float4* samples, int count, float weight,
                              global const float4* rsmPosition, global const float4* rsmNormal,
                              global const float4* rsmFlux, float dminOverride, int firstVpl, global float4* vpls) {
  int k = get_global_id(0);
  if (k >= count) return;
  int res = view.width;
  float4 s = samples[k];
  float3 eye = vload3(0, view.eye);
  float3 axis = -(float3)(view.view[2], view.view[6], view.view[10]);
  int tx, ty;
  if (view.orthographic) {
    tx = clamp((int)(s.x * (float)res), 0, res - 1);
    ty = clamp((int)(s.y * (float)res), 0, res - 1);
  } else {
    float3 right = (float3)(view.view[0], view.view[4], view.view[8]);
    float3 up = (float3)(view.view[1], view.view[5], view.view[9]);
    float3 d = s.x * right + s.y * up + s.z * axis;
    float4 c = mat4_mul(view.view_proj, (float4)(eye + d, 1.0f));
    float nx = c.x / c.w, ny = c.y / c.w;
    tx = clamp((int)floor((nx * 0.5f + 0.5f) * (float)res), 0, res - 1);
    ty = clamp((int)floor((0.5f - ny * 0.5f) * (float)res), 0, res - 1);
  }
  size_t t = (size_t)ty * res + tx;
  float4 p = rsmPosition[t];
  float3 phi = rsmFlux[t].xyz;
  global float4* out = vpls + (size_t)(firstVpl + k) * 3;
  if (!(p.w > 0.0f)) {  // the sample left the scene: a light without power
    out[0] = (float4)(0.0f, 0.0f, 0.0f, 1.0f);
    out[1] = (float4)(0.0f);
    out[2] = (float4)(0.0f);
    return;
  }
  float scale = weight;
  float footprint = view.texel_world_size;
  if (!view.orthographic) {
    // The texel's flux is ρ·I·s(ω)·Ω_texel with Ω_texel = s²·cos³θ (rsm_resolve); the indirect
    // light carries ρ·I·s(ω)·Ω_accept/N.
    float3 w = p.xyz - eye;
    float depth = dot(w, axis);
    float c = depth / length(w);
    float omega = view.texel_world_size * view.texel_world_size * c * c * c;
    scale = omega > 0.0f ? weight / omega : 0.0f;
    footprint *= fabs(depth);
  }
  float dmin = dminOverride > 0.0f ? dminOverride : 0.5f * footprint;
  out[0] = (float4)(p.xyz, dmin * dmin);
  out[1] = (float4)(rsmNormal[t].xyz, 0.0f);
  out[2] = (float4)(phi * scale, 0.0f);
}

kernel void so_flag(int width, int height, global const float* depth, global const float4* normal,
                    global const uint* instance, float tauD, float cosTauN, int everyPixel, global uchar* flags) {
  int x0 = get_global_id(0) * GI_VW, y = get_global_id(1);
  if (x0 >= width || y >= height) return;
  intV x = min(x0 + GI_LANES, width - 1);       // lanes past the row repeat its last pixel (not stored)
  intV i = y * width + x, q = (y & ~1) * width + (x & ~1);  // the pixel and its parent
  floatV z = GI_GATHER(floatV, depth, i), zq = GI_GATHER(floatV, depth, q);
  uintV id = GI_GATHER(uintV, instance, i), idq = GI_GATHER(uintV, instance, q);
  floatV nx, ny, nz, nw, qx, qy, qz, qw;
  GI_GATHER_AOS4(float, (global const float*)normal, i, nx, ny, nz, nw);
  GI_GATHER_AOS4(float, (global const float*)normal, q, qx, qy, qz, qw);
  intV surface = id != GI_INVALID_ID;
  intV differs = (idq == GI_INVALID_ID) | (fabs(zq - z) > tauD * z) | (qx * nx + qy * ny + qz * nz < cosTauN);
  intV reshade = GI_SEL((intV)(0), differs & (q != i), surface);
  if (everyPixel) reshade = surface;
  intV flag = GI_SEL((intV)(0), (intV)(SO_FLAG_RESHADE), reshade) | GI_SEL((intV)(0), (intV)(SO_FLAG_SURFACE), surface);
  int f[GI_VW];
  vstoreV(flag, 0, f);
  global uchar* row = flags + (size_t)y * width + x0;
  int lanes = min(GI_VW, width - x0);
  for (int l = 0; l < lanes; ++l) row[l] = (uchar)f[l];
}

kernel void so_row_counts(int width, int height, global const uchar* flags, global int* rowCounts) {
  int y = get_global_id(0);
  if (y >= height) return;
  global const uchar* f = flags + (size_t)y * width;
  int reshade = 0, surface = 0;
  for (int x = 0; x < width; ++x) {
    reshade += f[x] & SO_FLAG_RESHADE;
    surface += (f[x] >> 1) & 1;
  }
  rowCounts[2 * y] = reshade;
  rowCounts[2 * y + 1] = surface;
}

kernel void so_scan_rows(int height, global const int* rowCounts, global int* rowOffsets, global int* counters) {
  if (get_global_id(0) != 0) return;
  int reshade = 0, surface = 0;
  for (int y = 0; y < height; ++y) {
    rowOffsets[y] = reshade;
    reshade += rowCounts[2 * y];
    surface += rowCounts[2 * y + 1];
  }
  counters[0] = reshade;
  counters[1] = surface;
}

kernel void so_pick_negative(global const int* candidates, int candidateCount, global const uchar* flags, int count,
                             global int* picked, global int* counters) {
  if (get_global_id(0) != 0) return;
  int found = 0;
  for (int j = 0; j < candidateCount && found < count; ++j) {
    int p = candidates[j];
    if (flags[p] & SO_FLAG_SURFACE) picked[found++] = p;
  }
  counters[2] = found;
}

// Negative light j at picked pixel x with geometric normal n (facing the camera), from the
// `positive` indirect lights: E⁻ = Σ_p Φ_p·max(0, n_p·ω)·max(0, n·ω)/(π·max(d², d_min²)),
// ω = (x − x_p)/d; direction = normalize(Σ_p lum(E⁻_p)·ω); flux −E⁻·A·(surface pixels)/found, A
// the pixel's footprint on the surface s²·z²·cosθ_view/cosθ_surface (s = texel size at unit
// distance, the surface cosine kept ≥ 0.05); d_min = 0.5 × the pixel footprint s·z.
kernel void so_negative_lights(GiView camera, global const int* picked, global const int* counters, int count,
                               global const float4* position, global const float4* geoNormal,
                               global const float* depth, float dminOverride, int positive, global float4* vpls) {
  int j = get_global_id(0);
  if (j >= count) return;
  global float4* out = vpls + (size_t)(positive + j) * 3;
  int found = counters[2];
  if (j >= found) {
    out[0] = (float4)(0.0f, 0.0f, 0.0f, 1.0f);
    out[1] = (float4)(0.0f);
    out[2] = (float4)(0.0f);
    return;
  }
  int pix = picked[j];
  float3 x = position[pix].xyz, n = geoNormal[pix].xyz;
  float3 e = (float3)(0.0f), dir = (float3)(0.0f);
  for (int k = 0; k < positive; ++k) {
    float4 a = vpls[3 * k], b = vpls[3 * k + 1], f = vpls[3 * k + 2];
    float3 v = x - a.xyz;  // VPL -> receiver
    float d2 = dot(v, v);
    float g = max(dot(b.xyz, v), 0.0f) * max(dot(n, v), 0.0f) / (max(d2, 1e-20f) * max(d2, a.w));
    float3 c = f.xyz * g;
    e += c;
    dir += luminance(c) * v * rsqrt(max(d2, 1e-20f));
  }
  e *= GI_INV_PI;
  float z = depth[pix];
  float3 toEye = vload3(0, camera.eye) - x;
  float r = length(toEye);
  float s = camera.texel_world_size;
  float cosSurface = max(fabs(dot(n, toEye)) / r, 0.05f);
  float area = s * s * z * z * (z / r) / cosSurface;
  float weight = (float)counters[1] / (float)found;
  float len = length(dir);
  float dmin = dminOverride > 0.0f ? dminOverride : 0.5f * s * z;
  out[0] = (float4)(x, dmin * dmin);
  out[1] = (float4)(len > 0.0f ? dir / len : (float3)(0.0f), 0.0f);
  out[2] = (float4)(len > 0.0f ? -e * (area * weight) : (float3)(0.0f), 0.0f);
}

// Σ_p Φ_p·(pair term) over lights 0 … count − 1 for GI_VW receivers (E·π per channel); with
// GI_VPL_VISIBILITY every pair of an `active` lane with a positive term is tested by a shadow ray.
#ifdef GI_VPL_VISIBILITY
#define SO_VISIBILITY_PARAMS , const GiBvh* bvh, float rayEpsilon
#define SO_VISIBILITY_ARGS , &vpl_bvh, vpl_ray_epsilon
#else
#define SO_VISIBILITY_PARAMS
#define SO_VISIBILITY_ARGS
#endif
inline void so_irradiance(floatV px, floatV py, floatV pz, floatV nx, floatV ny, floatV nz, intV active,
                          global const float4* vpls, int count, floatV* e SO_VISIBILITY_PARAMS) {
  floatV er = (floatV)(0.0f), eg = (floatV)(0.0f), eb = (floatV)(0.0f);
  for (int k = 0; k < count; ++k) {
    float4 a = vpls[3 * k], b = vpls[3 * k + 1], f = vpls[3 * k + 2];
    floatV gterm = vpl_pair_term(px, py, pz, nx, ny, nz, a, b);
#ifdef GI_VPL_VISIBILITY
    gterm = vpl_visible(bvh, rayEpsilon, px, py, pz, a.xyz, GI_SEL((floatV)(0.0f), gterm, active));
#endif
    er += f.x * gterm;
    eg += f.y * gterm;
    eb += f.z * gterm;
  }
  e[0] = er;
  e[1] = eg;
  e[2] = eb;
}

kernel void so_shade_low(int width, int height, int lowWidth, int lowHeight, global const float4* position,
                         global const float4* normal, global const float4* vpls, int lightCount,
                         global float4* lowIrradiance GI_VPL_VISIBILITY_PARAMS) {
  GI_VPL_VISIBILITY_BEGIN
  int u0 = get_global_id(0) * GI_VW, v = get_global_id(1);
  if (u0 >= lowWidth || v >= lowHeight) return;
  intV u = u0 + GI_LANES;
  intV i = min(2 * v, height - 1) * width + min(2 * min(u, lowWidth - 1), width - 1);
  floatV px, py, pz, pw, nx, ny, nz, nw;
  GI_GATHER_AOS4(float, (global const float*)position, i, px, py, pz, pw);
  GI_GATHER_AOS4(float, (global const float*)normal, i, nx, ny, nz, nw);
  intV active = (pw > 0.0f) & (u < lowWidth);  // background and lanes past the row: E = 0, no rays
  floatV zero = (floatV)(0.0f);
  nx = GI_SEL(zero, nx, active);
  ny = GI_SEL(zero, ny, active);
  nz = GI_SEL(zero, nz, active);
  floatV e[3];
  so_irradiance(px, py, pz, nx, ny, nz, active, vpls, lightCount, e SO_VISIBILITY_ARGS);
  floatV er = e[0] * GI_INV_PI, eg = e[1] * GI_INV_PI, eb = e[2] * GI_INV_PI;
  float t[4 * GI_VW];
  GI_AOS4_STORE(t, er, eg, eb, zero)
  global float4* row = lowIrradiance + (size_t)v * lowWidth + u0;
  int lanes = min(GI_VW, lowWidth - u0);
  for (int l = 0; l < lanes; ++l) row[l] = vload4(l, t);
}

kernel void so_compact(int width, int height, global const uchar* flags, global const int* rowOffsets,
                       global const float4* position, global const float4* normal, int capacity, global int* list,
                       global float* planes) {
  int y = get_global_id(0);
  if (y >= height) return;
  int o = rowOffsets[y];
  for (int x = 0; x < width; ++x) {
    size_t i = (size_t)y * width + x;
    if (!(flags[i] & SO_FLAG_RESHADE)) continue;
    float4 p = position[i], n = normal[i];
    list[o] = (int)i;
    planes[o] = p.x;
    planes[capacity + o] = p.y;
    planes[2 * capacity + o] = p.z;
    planes[3 * capacity + o] = n.x;
    planes[4 * capacity + o] = n.y;
    planes[5 * capacity + o] = n.z;
    ++o;
  }
}

kernel void so_refine(global const int* counters, global const int* list, global const float* planes, int capacity,
                      global const float4* vpls, int lightCount, global const float4* albedo,
                      global float4* out GI_VPL_VISIBILITY_PARAMS) {
  GI_VPL_VISIBILITY_BEGIN
  size_t g = get_global_id(0);
  int count = counters[0];
  int first = (int)(g * GI_VW);
  if (first >= count) return;
  floatV px = vloadV(g, planes), py = vloadV(g, planes + capacity), pz = vloadV(g, planes + 2 * capacity);
  floatV nx = vloadV(g, planes + 3 * capacity), ny = vloadV(g, planes + 4 * capacity);
  floatV nz = vloadV(g, planes + 5 * capacity);
  floatV ev[3];
  intV listed = (first + GI_LANES) < count;  // no rays for the stale slots past the list's end
  so_irradiance(px, py, pz, nx, ny, nz, listed, vpls, lightCount, ev SO_VISIBILITY_ARGS);
  float e[3][GI_VW];
  vstoreV(ev[0], 0, e[0]);
  vstoreV(ev[1], 0, e[1]);
  vstoreV(ev[2], 0, e[2]);
  int lanes = min(GI_VW, count - first);
  for (int l = 0; l < lanes; ++l) {
    int i = list[first + l];
    float3 ee = max((float3)(e[0][l], e[1][l], e[2][l]) * GI_INV_PI, 0.0f);
    out[i] = (float4)(albedo[i].xyz * (ee * GI_INV_PI), 0.0f);
  }
}
