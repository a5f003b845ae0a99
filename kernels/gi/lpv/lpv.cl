// Light propagation volumes (Kaplanyan 2009; Kaplanyan & Dachsbacher 2010; seeds 003, 004) in the
// conventions of ALGORITHMS.md §4. docs/techniques/lpv.md describes the technique and its choices.
//
// Kernels, in frame order:
//   lpv_inject            RSM texels, merged in block×block groups, become VPLs moved `bias` cells
//                         (default ½) along their normal; each adds Φ/π × cosine-lobe(n) (its intensity I(ω),
//                         W/sr) to the cell it lands in, in every cascade that contains it.
//   lpv_geometry_rsm      RSM texels, and
//   lpv_geometry_camera   camera G-buffer pixels, as surfels of area A: each adds A/s² × cosine-lobe(n)
//                         (blocking potential) to the geometry-volume node nearest to it; the nodes
//                         sit on the LPV cell corners (the volume is offset by half a cell).
//   lpv_resolve_injection fixed-point sums -> the float grid the propagation starts from, which is
//                         also the first term of the accumulated grid.
//   lpv_resolve_geometry  fixed-point sums -> blocking potential per node: of the two surfel sources
//                         (RSM, camera) the one that saw more surface at the node (larger DC term);
//                         summing both would count a surface seen by both twice.
//   lpv_propagate         one gather step: each cell collects from its 6 neighbours, 5 faces each.
//   lpv_lookup            per pixel: trilinear in the accumulated grid at x + ½ cell along the
//                         geometric normal; irradiance by the clamped-cosine convolution at −n;
//                         L = ρ/π · E; cascades blended per seed 003 eq. 3.2.
//
// Determinism (§7): the scatter steps add integers (64-bit fixed point, `atom_add`), so the sums do
// not depend on the order work-items run in; each work-item first merges a run of LPV_RUN texels
// that fall into the same cell (integer sums again, so the merging does not change the result).
//
// Layouts (N = LPV_N, cells (z·N + y)·N + x, nodes the same with N + 1):
//   grid     float planes [cascade][channel r,g,b][coefficient][cell]: SH coefficients of intensity
//            (sh.h order), after LPV_PAD floats of padding (the buffer ends with LPV_PAD more), so
//            the propagation's row loads one cell left or right of a row stay inside the buffer;
//   gridAcc  long   [cascade][channel][cell][4]: fixed-point injection sums
//   geometry float planes [cascade][coefficient][node]; geometryAcc long [cascade][source rsm, camera][node][4]
//   cascades float4 [cascade]: (origin xyz of cell (0,0,0)'s corner, cell edge s), metres
// The propagation works on LPV_LANES cells of a row per work-item (16 on CPU devices: float16
// lanes; 1 on GPUs), the lane-wise convention of common/vector_width.h.
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#include "common/math.h"
#include "common/sh.h"
#include "common/shared_types.h"

#define LPV_CELLS (LPV_N * LPV_N * LPV_N)
#define LPV_PLANE(k, ch, coef) ((size_t)(((k) * 3 + (ch)) * 4 + (coef)) * LPV_CELLS)
#define LPV_M (LPV_N + 1)
#define LPV_NODES (LPV_M * LPV_M * LPV_M)

// Solid angles of the destination cell's faces seen from the neighbour's centre (ALGORITHMS.md §4).
#define LPV_MAIN_FACE_SOLID_ANGLE 0.4006696846f
#define LPV_SIDE_FACE_SOLID_ANGLE 0.4234413544f

inline int cell_index(int3 c) { return (c.z * LPV_N + c.y) * LPV_N + c.x; }
inline int node_index(int3 c) { return (c.z * LPV_M + c.y) * LPV_M + c.x; }

inline long4 to_fixed4(float4 v, float scale) { return convert_long4_rte(v * scale); }

inline void atomic_add_fixed4(global long* acc, long4 v) {
  if (v.x != 0) atom_add(acc + 0, v.x);
  if (v.y != 0) atom_add(acc + 1, v.y);
  if (v.z != 0) atom_add(acc + 2, v.z);
  if (v.w != 0) atom_add(acc + 3, v.w);
}

// Cell of cascade k containing p, or (-1, ...) when p is outside the grid.
inline int3 cell_of(float4 cascade, float3 p) {
  float3 u = (p - cascade.xyz) / cascade.w;
  int3 c = convert_int3_rtn(u);
  bool inside = all(u >= 0.0f) && all(c >= 0) && all(c < LPV_N);
  return inside ? c : (int3)(-1);
}

// Area of the surface seen through one texel/pixel of `view` at p with normal n (metres²): the
// texel's solid angle times distance² over the cosine at the surface, the cosine clamped at 0.1
// so that surfaces seen edge-on do not get an unbounded area.
inline float surfel_area(const GiView* view, float3 p, float3 n) {
  float3 axis = (float3)(-view->view[2], -view->view[6], -view->view[10]);
  float s2 = view->texel_world_size * view->texel_world_size;
  float3 dir = axis;
  float a = s2;
  if (!view->orthographic) {
    float3 d = p - vload3(0, view->eye);
    float dist = length(d);
    dir = d / dist;
    float z = dot(d, axis);
    a = s2 * z * z * (z / dist);  // texel solid angle s²·cos³α times dist² = s²·z²·cos α
  }
  return a / fmax(fabs(dot(n, dir)), 0.1f);
}

// ---- injection --------------------------------------------------------------------------------

// One work-item per LPV_RUN consecutive merged texels of one row of the block×block-merged RSM.
// A merged texel's VPL: flux = Σ Φ, position and normal = the Φ-weighted means (weights r+g+b).
kernel void lpv_inject(global const float4* rsmPosition, global const float4* rsmNormal,
                       global const float4* rsmFlux, int rsmRes, int block, float bias,
                       constant float4* cascades, float fixedScale, global long* gridAcc) {
  int mergedRes = rsmRes / block;
  int x0 = get_global_id(0) * LPV_RUN, y = get_global_id(1);
  if (y >= mergedRes || x0 >= mergedRes) return;
  int runCell[LPV_CASCADES];
  long4 run[LPV_CASCADES][3];
  for (int k = 0; k < LPV_CASCADES; ++k) {
    runCell[k] = -1;
    run[k][0] = run[k][1] = run[k][2] = (long4)(0);
  }
  int x1 = min(x0 + LPV_RUN, mergedRes);
  for (int x = x0; x <= x1; ++x) {
    float3 flux = (float3)(0.0f), p = (float3)(0.0f), n = (float3)(0.0f);
    float weight = 0.0f;
    if (x < x1) {
      for (int by = 0; by < block; ++by)
        for (int bx = 0; bx < block; ++bx) {
          size_t t = (size_t)(y * block + by) * rsmRes + (size_t)(x * block + bx);
          float3 f = rsmFlux[t].xyz;
          float w = f.x + f.y + f.z;
          if (!(w > 0.0f)) continue;
          flux += f;
          p += w * rsmPosition[t].xyz;
          n += w * rsmNormal[t].xyz;
          weight += w;
        }
    }
    bool valid = weight > 0.0f;  // false also for the flush step x == x1
    if (valid) {
      p /= weight;
      n = safe_normalize(n, (float3)(0.0f));  // normals that cancel: an isotropic emitter, same flux
    }
    float4 lobe = sh_cosine_lobe(n) * GI_INV_PI;
    for (int k = 0; k < LPV_CASCADES; ++k) {
      int cell = -1;
      if (valid) {
        int3 c = cell_of(cascades[k], p + bias * cascades[k].w * n);
        cell = c.x < 0 ? -1 : cell_index(c);
      }
      if (cell != runCell[k]) {
        if (runCell[k] >= 0)
          for (int ch = 0; ch < 3; ++ch)
            atomic_add_fixed4(gridAcc + ((size_t)(k * 3 + ch) * LPV_CELLS + runCell[k]) * 4, run[k][ch]);
        runCell[k] = cell;
        run[k][0] = run[k][1] = run[k][2] = (long4)(0);
      }
      if (cell >= 0) {
        run[k][0] += to_fixed4(lobe * flux.x, fixedScale);
        run[k][1] += to_fixed4(lobe * flux.y, fixedScale);
        run[k][2] += to_fixed4(lobe * flux.z, fixedScale);
      }
    }
  }
}

// ---- geometry volume --------------------------------------------------------------------------

// Adds the surfels of one row run (texels x0 .. x0 + LPV_RUN - 1 of row y of a width-wide view)
// to source `source` of the geometry accumulators. A surfel is valid where position.w > 0.
inline void add_surfels(const GiView* view, global const float4* position, global const float4* normal, int width,
                        int x0, int y, constant float4* cascades, float fixedScale, int source,
                        global long* geometryAcc) {
  int runNode[LPV_CASCADES];
  long4 run[LPV_CASCADES];
  for (int k = 0; k < LPV_CASCADES; ++k) {
    runNode[k] = -1;
    run[k] = (long4)(0);
  }
  int x1 = min(x0 + LPV_RUN, width);
  for (int x = x0; x <= x1; ++x) {
    bool valid = false;
    float3 p = (float3)(0.0f), n = (float3)(0.0f);
    float area = 0.0f;
    if (x < x1) {
      size_t t = (size_t)y * width + x;
      float4 pw = position[t];
      valid = pw.w > 0.0f;
      p = pw.xyz;
      n = normal[t].xyz;
      if (valid) area = surfel_area(view, p, n);
    }
    float4 lobe = sh_cosine_lobe(n);
    for (int k = 0; k < LPV_CASCADES; ++k) {
      int node = -1;
      float s = cascades[k].w;
      if (valid) {
        float3 u = (p - cascades[k].xyz) / s;
        int3 c = convert_int3_rte(u);
        node = all(u > -0.5f) && all(c >= 0) && all(c <= LPV_N) ? node_index(c) : -1;
      }
      if (node != runNode[k]) {
        if (runNode[k] >= 0)
          atomic_add_fixed4(geometryAcc + ((size_t)(k * 2 + source) * LPV_NODES + runNode[k]) * 4, run[k]);
        runNode[k] = node;
        run[k] = (long4)(0);
      }
      if (node >= 0) run[k] += to_fixed4(lobe * (area / (s * s)), fixedScale);
    }
  }
}

kernel void lpv_geometry_rsm(GiView view, global const float4* rsmPosition, global const float4* rsmNormal,
                             int rsmRes, constant float4* cascades, float fixedScale, global long* geometryAcc) {
  int x0 = get_global_id(0) * LPV_RUN, y = get_global_id(1);
  if (y >= rsmRes || x0 >= rsmRes) return;
  add_surfels(&view, rsmPosition, rsmNormal, rsmRes, x0, y, cascades, fixedScale, 0, geometryAcc);
}

kernel void lpv_geometry_camera(GiView view, global const float4* position, global const float4* geoNormal,
                                int width, int height, constant float4* cascades, float fixedScale,
                                global long* geometryAcc) {
  int x0 = get_global_id(0) * LPV_RUN, y = get_global_id(1);
  if (y >= height || x0 >= width) return;
  add_surfels(&view, position, geoNormal, width, x0, y, cascades, fixedScale, 1, geometryAcc);
}

// ---- resolve ----------------------------------------------------------------------------------

// One work-item per (cell, channel, cascade): global (LPV_CELLS, 3, LPV_CASCADES).
kernel void lpv_resolve_injection(global const long* gridAcc, float invFixedScale, global float* grid,
                                  global float* accumulated) {
  size_t cell = get_global_id(0), ch = get_global_id(1), k = get_global_id(2);
  float4 v = convert_float4(vload4((k * 3 + ch) * LPV_CELLS + cell, gridAcc)) * invFixedScale;
  grid += LPV_PAD;
  accumulated += LPV_PAD;
  for (int coef = 0; coef < 4; ++coef) {
    float c = coef == 0 ? v.x : coef == 1 ? v.y : coef == 2 ? v.z : v.w;
    grid[LPV_PLANE(k, ch, coef) + cell] = c;
    accumulated[LPV_PLANE(k, ch, coef) + cell] = c;
  }
}

// One work-item per (node, cascade): global (LPV_NODES, LPV_CASCADES).
kernel void lpv_resolve_geometry(global const long* geometryAcc, float invFixedScale, global float* geometry) {
  size_t node = get_global_id(0), k = get_global_id(1);
  long4 fromRsm = vload4((k * 2 + 0) * LPV_NODES + node, geometryAcc);
  long4 fromCamera = vload4((k * 2 + 1) * LPV_NODES + node, geometryAcc);
  float4 g = convert_float4(fromRsm.x >= fromCamera.x ? fromRsm : fromCamera) * invFixedScale;
  global float* planes = geometry + k * 4 * LPV_NODES + node;
  planes[0] = g.x;
  planes[LPV_NODES] = g.y;
  planes[2 * LPV_NODES] = g.z;
  planes[3 * LPV_NODES] = g.w;
}

// ---- propagation ------------------------------------------------------------------------------

#if LPV_LANES == 16
typedef float16 floatL;
typedef int16 intL;
#define vloadL vload16
#define vstoreL vstore16
#define LPV_LANE_IDS (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)
#elif LPV_LANES == 8
typedef float8 floatL;
typedef int8 intL;
#define vloadL vload8
#define vstoreL vstore8
#define LPV_LANE_IDS (int8)(0, 1, 2, 3, 4, 5, 6, 7)
#elif LPV_LANES == 4
typedef float4 floatL;
typedef int4 intL;
#define vloadL vload4
#define vstoreL vstore4
#define LPV_LANE_IDS (int4)(0, 1, 2, 3)
#else
typedef float floatL;
typedef int intL;
#define vloadL(o, p) ((p)[o])
#define vstoreL(v, o, p) ((p)[o] = (v))
#define LPV_LANE_IDS 0
#endif

// Index of axis a's linear SH coefficient in the (Y00, y, z, x) order.
#define LPV_COEF(a) ((a) == 0 ? 3 : (a))

// Adds one face's transport to out[12] (r, g, b × 4 coefficients). The evaluation direction is
// scale·(sa·axis_a + sb·axis_b) (b < 0: none), the re-emission lobe points along se·axis_e. The
// arguments are constants after inlining, so only the non-zero terms are computed.
inline void lpv_face(const floatL* in, const floatL* g, int blocking, int a, float sa, int b, float sb, float scale,
                     int e, float se, float solidAngle, floatL* out) {
  floatL w = (floatL)(solidAngle * GI_INV_PI);
  if (blocking) {
    floatL along = sa * g[LPV_COEF(a)];
    if (b >= 0) along += sb * g[LPV_COEF(b)];
    floatL potential = GI_SH_Y0 * g[0] - (GI_SH_Y1 * scale) * along;  // GV · Y(−ω)
    w *= 1.0f - clamp(potential, 0.0f, 1.0f);
  }
  for (int ch = 0; ch < 3; ++ch) {
    const floatL* c = in + 4 * ch;
    floatL along = sa * c[LPV_COEF(a)];
    if (b >= 0) along += sb * c[LPV_COEF(b)];
    floatL flux = fmax(GI_SH_Y0 * c[0] + (GI_SH_Y1 * scale) * along, 0.0f) * w;  // ΔΩ/π · max(0, I(ω))
    out[4 * ch] += GI_SH_LOBE0 * flux;
    out[4 * ch + LPV_COEF(e)] += (GI_SH_LOBE1 * se) * flux;
  }
}

// Gathers from the neighbour at −s along axis a (light travelling along s·axis_a into the cells
// (x0 .. x0 + LPV_LANES − 1, y, z)): 1 main face and the 4 side faces.
inline void lpv_gather(int a, float s, global const float* src, global const float* geometry, int x0, int y, int z,
                       int blocking, floatL* out) {
  int3 c = (int3)(x0, y, z);
  int coord = a == 1 ? y : z;
  if (a != 0 && (coord - (int)s < 0 || coord - (int)s >= LPV_N)) return;  // whole row outside
  int stride = a == 0 ? 1 : a == 1 ? LPV_N : LPV_N * LPV_N;
  int cell = (z * LPV_N + y) * LPV_N + x0 - (int)s * stride;  // may be −1 or LPV_CELLS: padding
  floatL in[12];
  for (int p = 0; p < 12; ++p) in[p] = vloadL(0, src + (size_t)p * LPV_CELLS + cell);
  if (a == 0) {
    intL x = x0 + LPV_LANE_IDS - (int)s;
    intL inside = x >= 0 && x < LPV_N;
    for (int p = 0; p < 12; ++p) in[p] = select((floatL)(0.0f), in[p], inside);
  }
  floatL g[4];
  if (blocking) {
    // The shared face's 4 corner nodes: on the plane between neighbour and cell along a.
    int3 base = c + (int3)(a == 0 && s < 0.0f, a == 1 && s < 0.0f, a == 2 && s < 0.0f);
    size_t n0 = (size_t)(base.z * LPV_M + base.y) * LPV_M + base.x;
    size_t u = a == 0 ? LPV_M : 1, v = a == 2 ? LPV_M : LPV_M * LPV_M;
    for (int q = 0; q < 4; ++q) {
      global const float* plane = geometry + (size_t)q * LPV_NODES + n0;
      g[q] = 0.25f * (vloadL(0, plane) + vloadL(0, plane + u) + vloadL(0, plane + v) + vloadL(0, plane + u + v));
    }
  }
  lpv_face(in, g, blocking, a, s, -1, 0.0f, 1.0f, a, s, LPV_MAIN_FACE_SOLID_ANGLE, out);
  const float sideScale = 0.4472135955f;  // 1/√5: ω = normalize(2·d ± t)
  int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
  lpv_face(in, g, blocking, a, 2.0f * s, b1, 1.0f, sideScale, b1, 1.0f, LPV_SIDE_FACE_SOLID_ANGLE, out);
  lpv_face(in, g, blocking, a, 2.0f * s, b1, -1.0f, sideScale, b1, -1.0f, LPV_SIDE_FACE_SOLID_ANGLE, out);
  lpv_face(in, g, blocking, a, 2.0f * s, b2, 1.0f, sideScale, b2, 1.0f, LPV_SIDE_FACE_SOLID_ANGLE, out);
  lpv_face(in, g, blocking, a, 2.0f * s, b2, -1.0f, sideScale, b2, -1.0f, LPV_SIDE_FACE_SOLID_ANGLE, out);
}

// One gather step. Work-item = LPV_LANES destination cells of a row (global (N / LPV_LANES, N,
// N·cascades)). Light travels from the neighbour at cell − d in direction d (6 axes). Per
// neighbour, 5 faces of the destination: the main face opposite the shared one (evaluated along
// d, solid angle 0.4007 sr seen from the neighbour's centre, re-emitted along d) and the 4 side
// faces (evaluated along normalize(2d + t), from the neighbour's centre to the side face's
// centre, 0.4234 sr, re-emitted along t). Flux through a face = ΔΩ/π·max(0, I(ω)) × (1 − blocking),
// re-emitted as a clamped cosine lobe. Blocking is the geometry volume at the shared face (the
// mean of its 4 corner nodes: all light into the destination enters there) evaluated towards −ω;
// `blocking` = 0 skips it (first iteration, or occlusion off).
kernel void lpv_propagate(global const float* src, global float* dst, global float* accumulated,
                          global const float* geometry, int blocking) {
  int x0 = get_global_id(0) * LPV_LANES, y = get_global_id(1);
  int z = get_global_id(2) % LPV_N, k = get_global_id(2) / LPV_N;
  size_t base = LPV_PAD + LPV_PLANE(k, 0, 0);
  src += base;
  geometry += (size_t)k * 4 * LPV_NODES;
  floatL out[12];
  for (int p = 0; p < 12; ++p) out[p] = (floatL)(0.0f);
  lpv_gather(0, 1.0f, src, geometry, x0, y, z, blocking, out);
  lpv_gather(0, -1.0f, src, geometry, x0, y, z, blocking, out);
  lpv_gather(1, 1.0f, src, geometry, x0, y, z, blocking, out);
  lpv_gather(1, -1.0f, src, geometry, x0, y, z, blocking, out);
  lpv_gather(2, 1.0f, src, geometry, x0, y, z, blocking, out);
  lpv_gather(2, -1.0f, src, geometry, x0, y, z, blocking, out);
  size_t cell = (size_t)(z * LPV_N + y) * LPV_N + x0;
  for (int p = 0; p < 12; ++p) {
    size_t o = base + (size_t)p * LPV_CELLS + cell;
    vstoreL(out[p], 0, dst + o);
    vstoreL(vloadL(0, accumulated + o) + out[p], 0, accumulated + o);
  }
}

// ---- lookup -----------------------------------------------------------------------------------

// Irradiance (W/m² per channel) at p with geometric normal ng and shading normal n from cascade k:
// trilinear over cell centres at p + ½ cell along ng (clamped at the grid's border cells).
inline float3 cascade_irradiance(global const float* accumulated, constant float4* cascades, int k, float3 p,
                                 float3 ng, float3 n) {
  float4 cascade = cascades[k];
  float s = cascade.w;
  float3 u = (p + 0.5f * s * ng - cascade.xyz) / s - 0.5f;
  u = clamp(u, 0.0f, (float)(LPV_N - 1));
  int3 c0 = min(convert_int3_rtn(u), LPV_N - 2);
  float3 f = u - convert_float3(c0);
  global const float* g = accumulated + LPV_PAD + LPV_PLANE(k, 0, 0);
  float4 r = (float4)(0.0f), gr = (float4)(0.0f), b = (float4)(0.0f);
#pragma unroll
  for (int corner = 0; corner < 8; ++corner) {
    int3 o = (int3)(corner & 1, (corner >> 1) & 1, corner >> 2);
    float w = (o.x ? f.x : 1.0f - f.x) * (o.y ? f.y : 1.0f - f.y) * (o.z ? f.z : 1.0f - f.z);
    global const float* p = g + cell_index(c0 + o);
    r += w * (float4)(p[0], p[LPV_CELLS], p[2 * LPV_CELLS], p[3 * LPV_CELLS]);
    gr += w * (float4)(p[4 * LPV_CELLS], p[5 * LPV_CELLS], p[6 * LPV_CELLS], p[7 * LPV_CELLS]);
    b += w * (float4)(p[8 * LPV_CELLS], p[9 * LPV_CELLS], p[10 * LPV_CELLS], p[11 * LPV_CELLS]);
  }
  // Radiance = intensity / s²; light arriving at the surface travels along −n.
  float3 m = -n;
  float4 conv = (float4)(GI_SH_COSCONV0 * GI_SH_Y0, GI_SH_COSCONV1 * GI_SH_Y1 * m.y, GI_SH_COSCONV1 * GI_SH_Y1 * m.z,
                         GI_SH_COSCONV1 * GI_SH_Y1 * m.x) / (s * s);
  return (float3)(dot(r, conv), dot(gr, conv), dot(b, conv));
}

// Blend factor of seed 003 eq. 3.2: 0 well inside cascade k, rising to 1 over the outer tenth of
// its extent (largest component over the axes).
inline float cascade_blend(float4 cascade, float3 p) {
  float extent = cascade.w * LPV_N, w = 0.1f * extent;
  float3 centre = cascade.xyz + 0.5f * extent;
  float3 a = clamp((fabs(p - centre) - (0.5f * extent - w)) / w, 0.0f, 1.0f);
  return fmax(a.x, fmax(a.y, a.z));
}

// One work-item per pixel. `blendCascades` = 0 for a single grid fitted to the scene.
kernel void lpv_lookup(int width, int height, global const float4* position, global const float4* geoNormal,
                       global const float4* normal, global const float4* albedo, constant float4* cascades,
                       int blendCascades, global const float* accumulated, global float4* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  size_t i = (size_t)y * width + x;
  float4 pw = position[i];
  if (!(pw.w > 0.0f)) {
    out[i] = (float4)(0.0f);
    return;
  }
  float3 p = pw.xyz, ng = geoNormal[i].xyz, n = normal[i].xyz;
  float3 e;
  if (!blendCascades) {
    e = cascade_irradiance(accumulated, cascades, 0, p, ng, n);
  } else {
    int k = 0;
    float a = cascade_blend(cascades[0], p);
    while (k < LPV_CASCADES - 1 && a >= 1.0f) {
      ++k;
      a = cascade_blend(cascades[k], p);
    }
    e = cascade_irradiance(accumulated, cascades, k, p, ng, n);
    if (a > 0.0f && k < LPV_CASCADES - 1)
      e = mix(e, cascade_irradiance(accumulated, cascades, k + 1, p, ng, n), a);
  }
  out[i] = (float4)(fmax(albedo[i].xyz * GI_INV_PI * e, 0.0f), 0.0f);
}
