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
//   lpv_face_factors      the 30 face transmittances T_f of every cell (6 neighbours × 5 faces) from
//                         those potentials, once per frame, in half precision: the blocked step
//                         only reads them.
//   lpv_face_geometry     blocking potential per cell face (mean of its 4 corner nodes), once per
//                         frame: the geometry volume does not change over the steps.
//   lpv_propagate_blocked, lpv_propagate_open
//                         one gather step: each cell collects from its 6 neighbours, 5 faces each
//                         (with or without the geometry volume's blocking).
//   lpv_lookup_grid       accumulated grid -> the lookup grid (irradiance coefficients, float4 per
//                         cell and channel; copied into a 3D image on devices that filter images
//                         in hardware, lpv.lookup_storage).
//   lpv_lookup            per pixel: trilinear in the lookup grid at x + ½ cell along the
//                         geometric normal; irradiance by the clamped-cosine convolution at −n;
//                         L = ρ/π · E; cascades blended per seed 003 eq. 3.2.
//
// Determinism (§7): the scatter steps add integers (64-bit fixed point, `atom_add`), so the sums do
// not depend on the order work-items run in. Each work-item first sums, in float and in a fixed
// order, the texels of its run of LPV_RUN that fall into the same cell, and converts that sum to
// fixed point once (the conversion costs more than the sum): the same texels always give the same
// partial sums, so the result stays bit-identical run to run.
//
// Layouts (N = LPV_N, cells (z·N + y)·N + x, nodes the same with N + 1):
//   grid     float row blocks [cascade][z][y][channel r,g,b][coefficient][x] (LPV_AT): SH
//            coefficients of intensity (sh.h order) in grid units (LPV_UNIT0/1 below: each
//            coefficient times its basis constant), after LPV_PAD floats of padding, each z slice
//            followed by LPV_SKEW floats (zero), so the propagation's row loads one cell left or
//            right of a row stay inside the buffer;
//   gridAcc  long   [cascade][channel][cell][4]: fixed-point injection sums
//   geometry float planes [cascade][coefficient][node]; geometryAcc long [cascade][source rsm, camera][node][4]
//   faceGeometry half row blocks [cascade][z][y][axis][coefficient][x] (laid out like grid)
//   faceFactors half row blocks [cascade][z][y][direction·5 + face][x] (LPV_FACTOR_AT)
//   lookupGrid float4 [cascade][cell][channel] (LPV_LOOKUP_AT; [cascade][channel][cell] when it is
//            copied into a 3D image)
//   cascades float4 [cascade]: (origin xyz of cell (0,0,0)'s corner, cell edge s), metres
// The propagation works on LPV_LANES cells of a row per work-item, the injection and surfel
// kernels on GI_VW texels at a time (the native float width on CPU devices: 16 with AVX-512, 8
// with AVX2; 1 on GPUs), the lane-wise convention of common/vector_width.h.
// Two forms are avoided so that the kernels run correctly under Oclgrind (README, "Development
// notes"), which mis-evaluates them; both are correct OpenCL, and the forms used instead compile
// to the same code on PoCL:
//  - integer min/max of a lane vector and a scalar, min(x, n): written min(x, (intV)(n)). Oclgrind
//    21.10 evaluates the integer min/max/clamp(gentype, sgentype) overloads as if the scalar were
//    a vector (lane i read from past its storage): lanes 1.. got garbage clamped indices, so it
//    reported invalid reads in lpv_inject, lpv_geometry_* and lpv_lookup that no device makes;
//  - `!` of a vector comparison, e.g. `m && !(a == b)`: written as the opposite comparison,
//    `m && a != b`. Oclgrind turns !(a == b) into 1 / −2 per lane instead of 0 / −1 (it mis-
//    evaluates the xor with an i1 `true` vector of its lowering), so lpv_lookup's loop over the
//    distinct cells never ended there and grew until the memory ran out.
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#include "common/math.h"
#include "common/sh.h"
#include "common/shared_types.h"
#include "common/vector_width.h"

#define LPV_CELLS (LPV_N * LPV_N * LPV_N)
// Row blocks: each row of cells (cascade k, z, y) holds its 12 planes p = channel·4 + coefficient
// of LPV_N floats one after the other, so that a propagation work-item reads 5 nearby rows of the
// source grid (its own, y ± 1, z ± 1) and one row block of each other grid: a few sequential
// streams. With whole planes of N³ floats per coefficient a work-item read ~60 streams far apart,
// more than the hardware prefetchers follow: a 32³ step then waited on memory (docs/PERFORMANCE.md).
// Slices lie LPV_SLICE = 12·N² + LPV_SKEW floats apart (12·N² alone is a multiple of 4096 bytes at
// N = 32: the z ± 1 rows would share cache sets).
#define LPV_ROW (12 * LPV_N)
#define LPV_SLICE (LPV_ROW * LPV_N + LPV_SKEW)
// Float offset (after the LPV_PAD floats of padding) of plane p of cell (x, y, z) in cascade k.
#define LPV_AT(k, p, x, y, z) ((size_t)((k) * LPV_N + (z)) * LPV_SLICE + (size_t)(y) * LPV_ROW + (p) * LPV_N + (x))
// The face factors' row blocks: 30 planes per row, slices skewed like the grid's.
#define LPV_FACTOR_ROW (30 * LPV_N)
#define LPV_FACTOR_SLICE (LPV_FACTOR_ROW * LPV_N + LPV_SKEW)
#define LPV_FACTOR_AT(k, p, x, y, z) \
  ((size_t)((k) * LPV_N + (z)) * LPV_FACTOR_SLICE + (size_t)(y) * LPV_FACTOR_ROW + (p) * LPV_N + (x))
#define LPV_M (LPV_N + 1)
#define LPV_NODES (LPV_M * LPV_M * LPV_M)

// Solid angles of the destination cell's faces seen from the neighbour's centre (ALGORITHMS.md §4).
#define LPV_MAIN_FACE_SOLID_ANGLE 0.4006696846f
#define LPV_SIDE_FACE_SOLID_ANGLE 0.4234413544f
#define LPV_SIDE_SCALE 0.4472135955f  // 1/√5: ω = normalize(2·d ± e_b), the direction to a side face
// Grid units: the grids hold c0·LPV_UNIT0 and c_i·LPV_UNIT1 (i = y, z, x) for the SH coefficients
// c of intensity, i.e. the terms of I(ω) = Y0·c0 + Y1·(c·ω) pre-multiplied by the constants the
// propagation evaluates them with (side faces: Y1/√5): a face's intensity is then adds and one
// fused multiply-add, 3 multiplies fewer per neighbour and channel. The host converts
// (LpvVolume::readGrid, setInjected); the lookup grid is in plain irradiance coefficients.
#define LPV_UNIT0 GI_SH_Y0
#define LPV_UNIT1 (GI_SH_Y1 * LPV_SIDE_SCALE)

inline int cell_index(int3 c) { return (c.z * LPV_N + c.y) * LPV_N + c.x; }

inline long4 to_fixed4(float4 v, float scale) { return convert_long4_rte(v * scale); }

inline void atomic_add_fixed4(global long* acc, long4 v) {
  if (v.x != 0) atom_add(acc + 0, v.x);
  if (v.y != 0) atom_add(acc + 1, v.y);
  if (v.z != 0) atom_add(acc + 2, v.z);
  if (v.w != 0) atom_add(acc + 3, v.w);
}

// LPV_LANES cells of a row as one vector (the propagation, the resolve and grid conversions).
#if LPV_LANES == 16
typedef float16 floatL;
typedef int16 intL;
typedef ushort16 ushortL;
#define convert_intL convert_int16
#define convert_floatL convert_float16
#define as_floatL as_float16
#define vloadL vload16
#define vstoreL vstore16
#define LPV_LANE_IDS (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)
#define vload_halfL vload_half16
#define vstore_halfL_rte vstore_half16_rte
#elif LPV_LANES == 8
typedef float8 floatL;
typedef int8 intL;
typedef ushort8 ushortL;
#define convert_intL convert_int8
#define convert_floatL convert_float8
#define as_floatL as_float8
#define vloadL vload8
#define vstoreL vstore8
#define LPV_LANE_IDS (int8)(0, 1, 2, 3, 4, 5, 6, 7)
#define vload_halfL vload_half8
#define vstore_halfL_rte vstore_half8_rte
#elif LPV_LANES == 4
typedef float4 floatL;
typedef int4 intL;
typedef ushort4 ushortL;
#define convert_intL convert_int4
#define convert_floatL convert_float4
#define as_floatL as_float4
#define vloadL vload4
#define vstoreL vstore4
#define LPV_LANE_IDS (int4)(0, 1, 2, 3)
#define vload_halfL vload_half4
#define vstore_halfL_rte vstore_half4_rte
#else
typedef float floatL;
typedef int intL;
typedef ushort ushortL;
#define convert_intL convert_int
#define convert_floatL convert_float
#define as_floatL as_float
#define vload_halfL vload_half
#define vstore_halfL_rte vstore_half_rte
#define vloadL(o, p) ((p)[o])
#define vstoreL(v, o, p) ((p)[o] = (v))
#define LPV_LANE_IDS 0
#endif

// ---- injection --------------------------------------------------------------------------------

// One work-item per LPV_RUN consecutive merged texels of one row of the block×block-merged RSM.
// A merged texel's VPL: flux = Σ Φ, position and normal = the Φ-weighted means (weights r+g+b).
// Lane-wise (common/vector_width.h): the VPLs and their cells of GI_VW merged texels at a time as
// vectors; then they are merged into runs one by one, in order.
kernel void lpv_inject(global const float4* rsmPosition, global const float4* rsmNormal,
                       global const float4* rsmFlux, int rsmRes, int block, float bias,
                       constant float4* cascades, float fixedScale, global long* gridAcc) {
  int mergedRes = rsmRes / block;
  int x0 = get_global_id(0) * LPV_RUN, y = get_global_id(1);
  if (y >= mergedRes || x0 >= mergedRes) return;
  int runCell[LPV_CASCADES];
  float4 run[LPV_CASCADES][3];
#pragma unroll
  for (int k = 0; k < LPV_CASCADES; ++k) {
    runCell[k] = -1;
    run[k][0] = run[k][1] = run[k][2] = (float4)(0.0f);
  }
  for (int chunk = 0; chunk < LPV_RUN / GI_VW; ++chunk) {
    intV x = x0 + chunk * GI_VW + GI_LANES;
    intV column = min(x, (intV)(mergedRes - 1)) * block;  // lanes past the row's end re-read its last texel, dropped below
    floatV fr = 0.0f, fg = 0.0f, fb = 0.0f, px = 0.0f, py = 0.0f, pz = 0.0f, nx = 0.0f, ny = 0.0f, nz = 0.0f;
    floatV weight = 0.0f;
    for (int by = 0; by < block; ++by)
      for (int bx = 0; bx < block; ++bx) {
        intV t = (y * block + by) * rsmRes + column + bx;
        floatV r, g, b, unused, qx, qy, qz, mx, my, mz;
        GI_GATHER_AOS4(float, (global const float*)rsmFlux, t, r, g, b, unused);
        GI_GATHER_AOS4(float, (global const float*)rsmPosition, t, qx, qy, qz, unused);
        GI_GATHER_AOS4(float, (global const float*)rsmNormal, t, mx, my, mz, unused);
        floatV w = r + g + b;
        intV lit = w > 0.0f;
        fr += GI_SEL(0.0f, r, lit);
        fg += GI_SEL(0.0f, g, lit);
        fb += GI_SEL(0.0f, b, lit);
        px += GI_SEL(0.0f, w * qx, lit);
        py += GI_SEL(0.0f, w * qy, lit);
        pz += GI_SEL(0.0f, w * qz, lit);
        nx += GI_SEL(0.0f, w * mx, lit);
        ny += GI_SEL(0.0f, w * my, lit);
        nz += GI_SEL(0.0f, w * mz, lit);
        weight += GI_SEL(0.0f, w, lit);
      }
    intV valid = weight > 0.0f && x < mergedRes;
    floatV invWeight = 1.0f / weight;  // one division for the 3 means
    px *= invWeight;
    py *= invWeight;
    pz *= invWeight;
    // Normals that cancel: an isotropic emitter with the same flux.
    floatV l2 = nx * nx + ny * ny + nz * nz, inv = GI_SEL(0.0f, rsqrt(l2), l2 > 1e-30f);
    nx *= inv;
    ny *= inv;
    nz *= inv;
    int cell[LPV_CASCADES][GI_VW];
#pragma unroll
    for (int k = 0; k < LPV_CASCADES; ++k) {
      float4 c = cascades[k];
      float invCell = 1.0f / c.w;  // a scalar division per cascade, not 3 vector divisions per chunk
      floatV ux = fma(nx, bias, (px - c.x) * invCell), uy = fma(ny, bias, (py - c.y) * invCell),
             uz = fma(nz, bias, (pz - c.z) * invCell);  // (p + bias·s·n − origin)/s
      intV cx = convert_intV(floor(ux)), cy = convert_intV(floor(uy)), cz = convert_intV(floor(uz));
      intV inside = valid && ux >= 0.0f && uy >= 0.0f && uz >= 0.0f && cx < LPV_N && cy < LPV_N && cz < LPV_N;
      vstoreV(GI_SEL((intV)(-1), (cz * LPV_N + cy) * LPV_N + cx, inside), 0, cell[k]);
    }
    float fluxR[GI_VW], fluxG[GI_VW], fluxB[GI_VW], lobeY[GI_VW], lobeZ[GI_VW], lobeX[GI_VW];
    vstoreV(fr, 0, fluxR);
    vstoreV(fg, 0, fluxG);
    vstoreV(fb, 0, fluxB);
    vstoreV(GI_SH_LOBE1 * ny * GI_INV_PI, 0, lobeY);
    vstoreV(GI_SH_LOBE1 * nz * GI_INV_PI, 0, lobeZ);
    vstoreV(GI_SH_LOBE1 * nx * GI_INV_PI, 0, lobeX);
    for (int i = 0; i < GI_VW; ++i) {
      float4 lobe = (float4)(GI_SH_LOBE0 * GI_INV_PI, lobeY[i], lobeZ[i], lobeX[i]);  // Φ = 1: I(ω) = lobe/π
#pragma unroll
      for (int k = 0; k < LPV_CASCADES; ++k) {
        if (cell[k][i] != runCell[k]) {
          if (runCell[k] >= 0)
            for (int ch = 0; ch < 3; ++ch)
              atomic_add_fixed4(gridAcc + ((size_t)(k * 3 + ch) * LPV_CELLS + runCell[k]) * 4,
                                to_fixed4(run[k][ch], fixedScale));
          runCell[k] = cell[k][i];
          run[k][0] = run[k][1] = run[k][2] = (float4)(0.0f);
        }
        if (runCell[k] >= 0) {
          run[k][0] += lobe * fluxR[i];
          run[k][1] += lobe * fluxG[i];
          run[k][2] += lobe * fluxB[i];
        }
      }
    }
  }
  for (int k = 0; k < LPV_CASCADES; ++k)
    if (runCell[k] >= 0)
      for (int ch = 0; ch < 3; ++ch)
        atomic_add_fixed4(gridAcc + ((size_t)(k * 3 + ch) * LPV_CELLS + runCell[k]) * 4, to_fixed4(run[k][ch], fixedScale));
}

// ---- geometry volume --------------------------------------------------------------------------

// Adds the surfels of one row run (texels x0 .. x0 + LPV_RUN − 1 of row y of a width-wide view)
// to source `source` of the geometry accumulators. A surfel is valid where position.w > 0; its
// area is the texel's solid angle times distance² over the cosine at the surface (for an
// orthographic view the texel's square), the cosine clamped at 0.1 so that surfaces seen edge-on
// do not get an unbounded area. Lane-wise (common/vector_width.h): areas and nodes of GI_VW
// texels at a time as vectors; then the texels are merged into runs one by one, in order.
// With `albedo` (camera surfels when lpv.bounces is on; null otherwise) each surfel also adds
// (ρ·w, w), w = A/s², to its node in `albedoAcc`: the area-weighted albedo the blockers reflect
// with (lpv_face_albedo), merged into runs and added as integers like the potential.
inline void add_surfels(const GiView* view, global const float4* position, global const float4* normal, int width,
                        int x0, int y, constant float4* cascades, float fixedScale, int source,
                        global long* geometryAcc, global const float4* albedo, global long* albedoAcc) {
  int runNode[LPV_CASCADES];
  float4 run[LPV_CASCADES], runAlbedo[LPV_CASCADES];
#pragma unroll
  for (int k = 0; k < LPV_CASCADES; ++k) {
    runNode[k] = -1;
    run[k] = runAlbedo[k] = (float4)(0.0f);
  }
  const float3 axis = (float3)(-view->view[2], -view->view[6], -view->view[10]);
  const float3 eye = vload3(0, view->eye);
  const float texelArea = view->texel_world_size * view->texel_world_size;
  for (int chunk = 0; chunk < LPV_RUN / GI_VW; ++chunk) {
    intV x = x0 + chunk * GI_VW + GI_LANES;
    intV texel = y * width + min(x, (intV)(width - 1));  // lanes past the row's end re-read its last texel, dropped below
    floatV px, py, pz, pw, nx, ny, nz, nw;
    GI_GATHER_AOS4(float, (global const float*)position, texel, px, py, pz, pw);
    GI_GATHER_AOS4(float, (global const float*)normal, texel, nx, ny, nz, nw);
    intV valid = pw > 0.0f && x < width;
    floatV dirx = (floatV)(axis.x), diry = (floatV)(axis.y), dirz = (floatV)(axis.z), area = (floatV)(texelArea);
    if (!view->orthographic) {
      floatV dx = px - eye.x, dy = py - eye.y, dz = pz - eye.z;
      floatV dist = sqrt(dx * dx + dy * dy + dz * dz);
      floatV invDist = 1.0f / dist;  // one division for the direction and the area
      dirx = dx * invDist;
      diry = dy * invDist;
      dirz = dz * invDist;
      floatV along = dx * axis.x + dy * axis.y + dz * axis.z;
      area = texelArea * along * along * (along * invDist);  // texel solid angle s²·cos³α times dist²
    }
    area = area / fmax(fabs(nx * dirx + ny * diry + nz * dirz), 0.1f);
    int node[LPV_CASCADES][GI_VW];
    float weight[LPV_CASCADES][GI_VW], lobeY[GI_VW], lobeZ[GI_VW], lobeX[GI_VW];
#pragma unroll
    for (int k = 0; k < LPV_CASCADES; ++k) {
      float4 c = cascades[k];
      float invCell = 1.0f / c.w;  // a scalar division per cascade, not 4 vector divisions per chunk
      floatV ux = (px - c.x) * invCell, uy = (py - c.y) * invCell, uz = (pz - c.z) * invCell;
      intV cx = convert_intV(rint(ux)), cy = convert_intV(rint(uy)), cz = convert_intV(rint(uz));  // nearest node
      intV inside = valid && ux > -0.5f && uy > -0.5f && uz > -0.5f && cx >= 0 && cy >= 0 && cz >= 0 &&
                    cx <= LPV_N && cy <= LPV_N && cz <= LPV_N;
      vstoreV(GI_SEL((intV)(-1), (cz * LPV_M + cy) * LPV_M + cx, inside), 0, node[k]);
      vstoreV(area * (invCell * invCell), 0, weight[k]);
    }
    vstoreV(GI_SH_LOBE1 * ny, 0, lobeY);
    vstoreV(GI_SH_LOBE1 * nz, 0, lobeZ);
    vstoreV(GI_SH_LOBE1 * nx, 0, lobeX);
    float rhoR[GI_VW], rhoG[GI_VW], rhoB[GI_VW];
    if (albedo) {
      floatV r, g, b, unused;
      GI_GATHER_AOS4(float, (global const float*)albedo, texel, r, g, b, unused);
      vstoreV(r, 0, rhoR);
      vstoreV(g, 0, rhoG);
      vstoreV(b, 0, rhoB);
    }
    for (int i = 0; i < GI_VW; ++i) {
      float4 lobe = (float4)(GI_SH_LOBE0, lobeY[i], lobeZ[i], lobeX[i]);
#pragma unroll
      for (int k = 0; k < LPV_CASCADES; ++k) {
        if (node[k][i] != runNode[k]) {
          if (runNode[k] >= 0) {
            atomic_add_fixed4(geometryAcc + ((size_t)(k * 2 + source) * LPV_NODES + runNode[k]) * 4,
                              to_fixed4(run[k], fixedScale));
            if (albedo)
              atomic_add_fixed4(albedoAcc + ((size_t)k * LPV_NODES + runNode[k]) * 4, to_fixed4(runAlbedo[k], fixedScale));
          }
          runNode[k] = node[k][i];
          run[k] = runAlbedo[k] = (float4)(0.0f);
        }
        if (runNode[k] >= 0) {
          run[k] += lobe * weight[k][i];
          if (albedo) runAlbedo[k] += (float4)(rhoR[i], rhoG[i], rhoB[i], 1.0f) * weight[k][i];
        }
      }
    }
  }
  for (int k = 0; k < LPV_CASCADES; ++k)
    if (runNode[k] >= 0) {
      atomic_add_fixed4(geometryAcc + ((size_t)(k * 2 + source) * LPV_NODES + runNode[k]) * 4,
                        to_fixed4(run[k], fixedScale));
      if (albedo)
        atomic_add_fixed4(albedoAcc + ((size_t)k * LPV_NODES + runNode[k]) * 4, to_fixed4(runAlbedo[k], fixedScale));
    }
}

kernel void lpv_geometry_rsm(GiView view, global const float4* rsmPosition, global const float4* rsmNormal,
                             int rsmRes, constant float4* cascades, float fixedScale, global long* geometryAcc) {
  int x0 = get_global_id(0) * LPV_RUN, y = get_global_id(1);
  if (y >= rsmRes || x0 >= rsmRes) return;
  add_surfels(&view, rsmPosition, rsmNormal, rsmRes, x0, y, cascades, fixedScale, 0, geometryAcc, 0, 0);
}

// `albedo` and `albedoAcc` null unless lpv.bounces is on (the RSM has no albedo plane: the blockers'
// albedo comes from the camera's surfels only).
kernel void lpv_geometry_camera(GiView view, global const float4* position, global const float4* geoNormal,
                                int width, int height, constant float4* cascades, float fixedScale,
                                global long* geometryAcc, global const float4* albedo, global long* albedoAcc) {
  int x0 = get_global_id(0) * LPV_RUN, y = get_global_id(1);
  if (y >= height || x0 >= width) return;
  add_surfels(&view, position, geoNormal, width, x0, y, cascades, fixedScale, 1, geometryAcc, albedo, albedoAcc);
}

// ---- resolve ----------------------------------------------------------------------------------

// Fixed-point sums to float, rounded to nearest as convert_float4 rounds: 2^52 + 2^51 + v is a
// double whose mantissa holds v exactly (for |v| < 2^51: the injection sums stay below 2^48 by
// construction of their scale, the geometry sums below 2^51 while a node's blocking potential
// stays below 2048), then one rounding to float. AVX2 has no packed 64-bit integer conversion:
// convert_float4 of a long4 compiled to 4 scalar conversions, which made the resolve the slowest
// of the per-frame passes for 3 cascades.
#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
inline float4 lpv_fixed_to_float4(long4 v) {
  return convert_float4(as_double4(v + 0x4338000000000000L) - 6755399441055744.0);  // bits of 2^52 + 2^51
}
#else
inline float4 lpv_fixed_to_float4(long4 v) { return convert_float4(v); }
#endif

// LPV_LANES cells of a row and one channel per work-item, global (N / LPV_LANES, N, N · 3 ·
// LPV_CASCADES) with z + N·(k·3 + ch) along the third axis: the cells' fixed-point sums (one
// contiguous block) become 4 coefficient rows of the grid, in grid units.
kernel void lpv_resolve_injection(global const long* gridAcc, float invFixedScale, global float* grid,
                                  global float* accumulated) {
  int x0 = get_global_id(0) * LPV_LANES, y = get_global_id(1), z = get_global_id(2) % LPV_N;
  int slab = get_global_id(2) / LPV_N, k = slab / 3, ch = slab % 3;  // slab = k·3 + ch
  global const long* sums = gridAcc + ((size_t)slab * LPV_CELLS + (z * LPV_N + y) * LPV_N + x0) * 4;
  const float4 scale = invFixedScale * (float4)(LPV_UNIT0, LPV_UNIT1, LPV_UNIT1, LPV_UNIT1);  // grid units
  float c[4][LPV_LANES];
#pragma unroll
  for (int l = 0; l < LPV_LANES; ++l) {
    float4 v = lpv_fixed_to_float4(vload4(l, sums)) * scale;
    c[0][l] = v.x;
    c[1][l] = v.y;
    c[2][l] = v.z;
    c[3][l] = v.w;
  }
  size_t at = LPV_PAD + LPV_AT(k, ch * 4, x0, y, z);
#pragma unroll
  for (int q = 0; q < 4; ++q) {
    floatL v = vloadL(0, c[q]);
    vstoreL(v, 0, grid + at + q * LPV_N);
    vstoreL(v, 0, accumulated + at + q * LPV_N);
  }
}

// LPV_LANES consecutive nodes per work-item, global (⌈LPV_NODES / LPV_LANES⌉ rounded up to whole
// work-groups, LPV_CASCADES).
kernel void lpv_resolve_geometry(global const long* geometryAcc, float invFixedScale, global float* geometry) {
  int node0 = get_global_id(0) * LPV_LANES, k = get_global_id(1);
  if (node0 >= LPV_NODES) return;
  global const long* fromRsm = geometryAcc + ((size_t)(k * 2 + 0) * LPV_NODES + node0) * 4;
  global const long* fromCamera = geometryAcc + ((size_t)(k * 2 + 1) * LPV_NODES + node0) * 4;
  float c[4][LPV_LANES];
#pragma unroll
  for (int l = 0; l < LPV_LANES; ++l) {
    int i = min(l, LPV_NODES - 1 - node0);  // lanes past the last node repeat it, not stored
    long4 r = vload4(i, fromRsm), m = vload4(i, fromCamera);
    float4 g = lpv_fixed_to_float4(r.x >= m.x ? r : m) * invFixedScale;
    c[0][l] = g.x;
    c[1][l] = g.y;
    c[2][l] = g.z;
    c[3][l] = g.w;
  }
  global float* planes = geometry + (size_t)k * 4 * LPV_NODES + node0;
  if (node0 + LPV_LANES <= LPV_NODES) {
#pragma unroll
    for (int q = 0; q < 4; ++q) vstoreL(vloadL(0, c[q]), 0, planes + q * LPV_NODES);
  } else {
    for (int l = 0; node0 + l < LPV_NODES; ++l)
      for (int q = 0; q < 4; ++q) planes[q * LPV_NODES + l] = c[q][l];
  }
}

// ---- propagation ------------------------------------------------------------------------------
//
// Light travels from the neighbour at cell − d into the cell, for the 6 directions d = s·e_a
// (direction index 2a + (s < 0)). Per direction, 5 faces of the destination seen from the
// neighbour's centre: the main face opposite the shared one (evaluated along d, solid angle
// 0.4007 sr, re-emitted along d) and the 4 side faces (evaluated along normalize(2d ± e_b), the
// direction to the side face's centre, 0.4234 sr, re-emitted along ±e_b; b the two other axes in
// the order a + 1, a + 2, each + then −). Flux through a face = T_f · max(0, I_nb(ω_f)), re-emitted
// as a clamped cosine lobe, with T_f = ΔΩ_f/π · (1 − clamp(GV · Y(−ω_f), 0, 1)): the geometry
// volume GV at the face the two cells share (the mean of its 4 corner nodes: all light into the
// destination enters there) blocks every face's share.


// Index of the lookup grid's float4 for channel ch of cell `cell` (cell_index order) of cascade
// k. For the lookup's own interpolation the 3 channels of a cell lie side by side, so that the 8
// corners of a trilinear lookup are 4 runs of 2 × 48 contiguous bytes (with one slab per channel
// they were 12 runs in 3 slabs 0.5 MB apart, and their loads were the lookup's hot spot); the 3D
// image stacks the (cascade, channel) slabs along z, so for it the buffer keeps that order.
#if LPV_IMAGES
#define LPV_LOOKUP_AT(k, ch, cell) ((size_t)((k) * 3 + (ch)) * LPV_CELLS + (cell))
#define LPV_LOOKUP_CELL_STRIDE 1
#else
#define LPV_LOOKUP_AT(k, ch, cell) (((size_t)(k) * LPV_CELLS + (cell)) * 3 + (ch))
#define LPV_LOOKUP_CELL_STRIDE 3
#endif

// The lookup grid (lpv_lookup_grid below) for LPV_LANES cells of a row, from cell `cell0` on, from
// their accumulated coefficients c[0..3] (channel ch, grid units) in cascade k: the SH coefficients
// times the clamped-cosine convolution and 1/s², one float4 per cell and channel. Written by the
// last propagation step of each cascade and, when no step has run since the grid was set, by
// lpv_lookup_grid.
inline void lpv_store_lookup_cells(const floatL* c, constant float4* cascades, int k, int ch, int cell0,
                                   global float4* lookupGrid) {
  global float4* out = lookupGrid + LPV_LOOKUP_AT(k, ch, cell0);
  float s = cascades[k].w, s2 = s * s;
  const float f0 = GI_SH_COSCONV0 * GI_SH_Y0 / LPV_UNIT0, f1 = GI_SH_COSCONV1 * GI_SH_Y1 / LPV_UNIT1;
  floatL q0 = (f0 / s2) * c[0], q1 = (f1 / s2) * c[1], q2 = (f1 / s2) * c[2], q3 = (f1 / s2) * c[3];
#if LPV_LANES == GI_VW && GI_VW > 1 && LPV_LOOKUP_CELL_STRIDE == 1
  GI_AOS4_STORE((global float*)out, q0, q1, q2, q3);
#else
  float v[4][LPV_LANES];
  vstoreL(q0, 0, v[0]);
  vstoreL(q1, 0, v[1]);
  vstoreL(q2, 0, v[2]);
  vstoreL(q3, 0, v[3]);
  for (int l = 0; l < LPV_LANES; ++l) out[l * LPV_LOOKUP_CELL_STRIDE] = (float4)(v[0][l], v[1][l], v[2][l], v[3][l]);
#endif
}

// Index of axis a's linear SH coefficient in the (Y00, y, z, x) order.
#define LPV_COEF(a) ((a) == 0 ? 3 : (a))
// Blocking potential at each cell's 3 lower faces, once per frame (the geometry volume does not
// change over the propagation steps): the mean of the 4 corner nodes of the face between cell
// c − e_a and c. Plane p = a·4 + coefficient of the grids' row-block layout (LPV_AT). Stored in
// half precision (rounded to nearest, 11 significant bits: relative error <= 2.4e-4, far below the
// approximation of a cell face's occluders by 4 SH coefficients), clamped to half's finite range
// (tests/lpv_host_reference.h rounds the same way); lpv_face_factors turns them into the factors.
// LPV_LANES cells of a row per work-item (contiguous node loads), global (N / LPV_LANES, N,
// N · 3 · LPV_CASCADES) with z + N·(k·3 + a) along the third axis.
kernel void lpv_face_geometry(global const float* geometry, global half* faceGeometry) {
  int x0 = get_global_id(0) * LPV_LANES, y = get_global_id(1), z = get_global_id(2) % LPV_N;
  int slab = get_global_id(2) / LPV_N, k = slab / 3, a = slab % 3;  // slab = k·3 + axis
  size_t n0 = (size_t)(z * LPV_M + y) * LPV_M + x0;
  size_t u = a == 0 ? LPV_M : 1, v = a == 2 ? LPV_M : LPV_M * LPV_M;  // the face's two in-plane axes
  for (int q = 0; q < 4; ++q) {
    global const float* plane = geometry + (k * 4 + q) * LPV_NODES + n0;
    floatL mean = 0.25f * (vloadL(0, plane) + vloadL(0, plane + u) + vloadL(0, plane + v) + vloadL(0, plane + u + v));
    vstore_halfL_rte(clamp(mean, -65504.0f, 65504.0f), 0, faceGeometry + LPV_PAD + LPV_AT(k, a * 4 + q, x0, y, z));
  }
}

// T_f of the 5 faces for light along direction dir from the blocking potential g (4 coefficients)
// of the face the two cells share: ΔΩ_f/π · (1 − clamp(GV · Y(−ω_f), 0, 1)), evaluated as
// clamp(ΔΩ_f/π − ΔΩ_f/π · GV · Y(−ω_f), 0, ΔΩ_f/π) with the constants folded into fused
// multiply-adds (2 per face and direction fewer than the plain form). The upper bounds mainMax and
// sideMax are ΔΩ_f/π, or 0 in the lanes whose neighbour lies outside the grid (x borders): a zero
// factor there replaces a select on each of the neighbour's 12 coefficients. A zero potential
// gives exactly ΔΩ_f/π.
inline void lpv_transmittance(int dir, const floatL* g, floatL mainMax, floatL sideMax, floatL* t) {
  int a = dir / 2;
  float s = dir % 2 ? -1.0f : 1.0f;
  int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
  const float mainWeight = LPV_MAIN_FACE_SOLID_ANGLE * GI_INV_PI, sideWeight = LPV_SIDE_FACE_SOLID_ANGLE * GI_INV_PI;
  // GV · Y(−ω) = Y0·g0 − Y1·(ω · g_lin) for ω = d (main) and normalize(2d ± e_b) (sides).
  floatL openMain = fma(g[LPV_COEF(a)], (floatL)(mainWeight * GI_SH_Y1 * s),
                        fma(g[0], (floatL)(-mainWeight * GI_SH_Y0), (floatL)(mainWeight)));
  floatL openSide = fma(g[LPV_COEF(a)], (floatL)(sideWeight * GI_SH_Y1 * LPV_SIDE_SCALE * 2.0f * s),
                        fma(g[0], (floatL)(-sideWeight * GI_SH_Y0), (floatL)(sideWeight)));
  floatL sideB1 = (sideWeight * GI_SH_Y1 * LPV_SIDE_SCALE) * g[LPV_COEF(b1)];
  floatL sideB2 = (sideWeight * GI_SH_Y1 * LPV_SIDE_SCALE) * g[LPV_COEF(b2)];
  t[0] = fmin(fmax(openMain, 0.0f), mainMax);
  t[1] = fmin(fmax(openSide + sideB1, 0.0f), sideMax);
  t[2] = fmin(fmax(openSide - sideB1, 0.0f), sideMax);
  t[3] = fmin(fmax(openSide + sideB2, 0.0f), sideMax);
  t[4] = fmin(fmax(openSide - sideB2, 0.0f), sideMax);
}

// The unblocked factors ΔΩ_f/π of the main and side faces for the 6 directions, for LPV_LANES
// cells of a row from x0; 0 in the lanes whose x neighbour (x − 1 for dir 0, x + 1 for dir 1) lies
// outside the grid: a zero factor there replaces a select on each of the neighbour's 12 coefficients.
inline void lpv_open_factors(int x0, floatL* maxMain, floatL* maxSide) {
  intL x = x0 + LPV_LANE_IDS;
  const float mainWeight = LPV_MAIN_FACE_SOLID_ANGLE * GI_INV_PI, sideWeight = LPV_SIDE_FACE_SOLID_ANGLE * GI_INV_PI;
  intL inside[2] = {x >= 1, x < LPV_N - 1};
#pragma unroll
  for (int dir = 0; dir < 6; ++dir) {
    maxMain[dir] = dir < 2 ? select((floatL)(0.0f), (floatL)(mainWeight), inside[dir]) : (floatL)(mainWeight);
    maxSide[dir] = dir < 2 ? select((floatL)(0.0f), (floatL)(sideWeight), inside[dir]) : (floatL)(sideWeight);
  }
}

// The 30 face factors T_f of LPV_LANES cells of a row (6 neighbour directions × 5 faces, plane
// dir·5 + face of LPV_FACTOR_AT), once per frame: the geometry volume does not change over the
// steps. Computed in every blocked step instead, the 30 factors of a work-item did not fit in
// AVX2's 16 registers: their arithmetic and spills were about a fifth of the step's instructions
// (1367 against 1076 per 8 cells reading them). Stored in half precision (rounded to nearest,
// relative error <= 2^-11; tests/lpv_host_reference.h rounds the same way): 60 bytes per cell and
// step; in float (120 bytes) the extra stream cost more than the arithmetic saved. The x
// neighbours outside the grid get factor 0 in their lanes; a y or z neighbour row outside the
// grid (its factors are not used) is given the cell's own face in place of one that may lie past
// the buffer. Global (N / LPV_LANES, N, N · LPV_CASCADES) with z + N·k along the third axis.
kernel void lpv_face_factors(global const half* faceGeometry, global half* faceFactors) {
  int x0 = get_global_id(0) * LPV_LANES, y = get_global_id(1), z = get_global_id(2) % LPV_N;
  int k = get_global_id(2) / LPV_N;
  size_t row = LPV_PAD + LPV_AT(k, 0, x0, y, z);
  global half* out = faceFactors + LPV_PAD + LPV_FACTOR_AT(k, 0, x0, y, z);
  floatL maxMain[6], maxSide[6];
  lpv_open_factors(x0, maxMain, maxSide);
  bool inside[6] = {true, true, y >= 1, y < LPV_N - 1, z >= 1, z < LPV_N - 1};
  const int stride[3] = {1, LPV_ROW, LPV_SLICE};
#pragma unroll
  for (int dir = 0; dir < 6; ++dir) {
    // The shared face: the lower face along a of the cell itself (light along +a) or of the cell above.
    global const half* face = faceGeometry + row + (dir / 2) * 4 * LPV_N + (inside[dir] && dir % 2 ? stride[dir / 2] : 0);
    floatL g[4], t[5];
#pragma unroll
    for (int q = 0; q < 4; ++q) g[q] = vload_halfL(0, face + q * LPV_N);
    lpv_transmittance(dir, g, maxMain[dir], maxSide[dir], t);
#pragma unroll
    for (int f = 0; f < 5; ++f) vstore_halfL_rte(t[f], 0, out + (dir * 5 + f) * LPV_N);
  }
}

// The 16 half-precision face factors of one plane of a work-item as float16. Where the target has
// AVX-512 this is one conversion instruction (vcvtph2ps zmm) through clang's storage-only __fp16;
// PoCL's vload_half16 converts two halves of 8 and joins them (3 instructions; without
// cl_khr_fp16 a half vector cannot be loaded as such). Same values either way.
#if LPV_LANES == 16 && defined(__AVX512F__)
typedef __fp16 lpv_half16 __attribute__((ext_vector_type(16), aligned(2)));
inline float16 lpv_load_factor(global const half* p) {
  return __builtin_convertvector(*(global const lpv_half16*)p, float16);
}
#else
inline floatL lpv_load_factor(global const half* p) { return vload_halfL(0, p); }
#endif

// Store of LPV_LANES floats of a row (4-byte aligned). PoCL's vstore16 stores a float16 in 16-byte
// pieces (4 stores and 3 extracts on AVX-512), and a propagation step stores 12 rows, 24 every
// other step; through clang's ext_vector_type with 4-byte alignment it is one unaligned vector
// store (vmovups zmm): the compiled 32³ step (work-group of 2 work-items) lost 216 16-byte stores
// and 156 extracts, 6870 → 6330 instructions (docs/PERFORMANCE.md). Same bits either way.
#if LPV_LANES > 1 && defined(__x86_64__)
typedef float lpv_floatL_unaligned __attribute__((ext_vector_type(LPV_LANES), aligned(4)));
#define lpv_storeL(v, p) (*(global lpv_floatL_unaligned*)(p) = (v))
#else
#define lpv_storeL(v, p) vstoreL(v, 0, p)
#endif

// Prefetch of one cache line for reading (PoCL on x86: the pointer is a plain address there); a
// no-op elsewhere.
#if defined(__x86_64__)
#define LPV_PREFETCH(p) __builtin_prefetch((const void*)(size_t)(p), 0, 3)
#define LPV_PREFETCH_WRITE(p) __builtin_prefetch((const void*)(size_t)(p), 1, 3)
#else
#define LPV_PREFETCH(p)
#define LPV_PREFETCH_WRITE(p)
#endif

// Adds the light channel `in` (4 coefficients, grid units) of the neighbour in direction `dir`
// sends through the destination's 5 faces: face fluxes T_f · max(0, I(ω_f)) into o[0] (sum of the
// fluxes) and o[1..3] (signed along the re-emission axis), scaled by the lobe constants at the end.
// In grid units I(d) = in0 + s·√5·in_a on the main face and I(normalize(2d ± e_b)) = in0 + 2s·in_a
// ± in_b on the side faces. The fluxes go into the sums by fused multiply-adds, each factor used
// twice (for o[0] and for its axis): 11 operations after the 11 that form the clamped
// intensities, against 15 with the products formed first. The direction's 5 fluxes are summed
// first and added to o[0] once, so that o[0] is not one chain of 30 dependent operations per channel.
inline void lpv_faces(int dir, const floatL* in, const floatL* t, floatL* o) {
  int a = dir / 2;
  float s = dir % 2 ? -1.0f : 1.0f;
  int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
  floatL fMain = fmax(fma(in[LPV_COEF(a)], (floatL)(s / LPV_SIDE_SCALE), in[0]), 0.0f);
  floatL side = fma(in[LPV_COEF(a)], (floatL)(2.0f * s), in[0]);
  floatL f1p = fmax(side + in[LPV_COEF(b1)], 0.0f), f1m = fmax(side - in[LPV_COEF(b1)], 0.0f);
  floatL f2p = fmax(side + in[LPV_COEF(b2)], 0.0f), f2m = fmax(side - in[LPV_COEF(b2)], 0.0f);
  o[0] += fma(f2m, t[4], fma(f2p, t[3], fma(f1m, t[2], fma(f1p, t[1], fMain * t[0]))));
  o[LPV_COEF(a)] = fma(s > 0.0f ? fMain : -fMain, t[0], o[LPV_COEF(a)]);
  o[LPV_COEF(b1)] = fma(-f1m, t[2], fma(f1p, t[1], o[LPV_COEF(b1)]));
  o[LPV_COEF(b2)] = fma(-f2m, t[4], fma(f2p, t[3], o[LPV_COEF(b2)]));
}

// One gather step of cascade k. Work-item = LPV_LANES destination cells of a row (global
// (N / LPV_LANES, N, N)). Direction after direction: its 5 face transmittances T_f (read from
// lpv_face_factors' planes), then the neighbour's 4 coefficients of each channel into that
// channel's 4 accumulators. The 12 accumulators, 5 factors and one neighbour channel fit in
// AVX-512's 32 vector registers, so each factor is loaded once and nothing spills; with all 30
// factors loaded first and the channels outer (the order before, for AVX2's 16 registers) 14 of
// them spilled: 1946 against 1742 instructions per work-group of 2 work-items, 234 against 116
// stack accesses. (With AVX2's 16 registers the 12 accumulators spill instead; there the two orders
// compiled to about the same count, 1311 against 1289, in an earlier form of the step.) Two kernels from one body: `lpv_propagate_blocked` reads the face factors,
// `lpv_propagate_open` uses the unblocked T_f = ΔΩ_f/π (first step — the VPLs sit next to the
// surfaces that lit them — or occlusion off) without loading or computing any factor; the
// blocking is a compile-time constant in each, so neither carries the other's work.
// The accumulated grid is updated every other step (half its memory traffic), by the flags in
// `accumulate`: LPV_ADD_THIS adds this step's result, LPV_ADD_SOURCE the source grid (the previous
// step's result, which that step left out); none leaves this step's result to the next step.
// LPV_WRITE_LOOKUP (the last step of a cascade) also writes the lookup grid from the final sums,
// which saves lpv_lookup_grid's pass over the accumulated grid (lpv_volume.cpp).
#define LPV_ADD_THIS 1
#define LPV_ADD_SOURCE 2
#define LPV_WRITE_LOOKUP 4
inline void lpv_propagate_step(global const float* src, global float* dst, global float* accumulated,
                               global const half* faceFactors, int k, int accumulate, constant float4* cascades,
                               global float4* lookupGrid, const bool blocking) {
  int x0 = get_global_id(0) * LPV_LANES, y = get_global_id(1), z = get_global_id(2);
  size_t row = LPV_PAD + LPV_AT(k, 0, x0, y, z);  // plane 0 of the work-item's first cell
  bool inside[6] = {true, true, y >= 1, y < LPV_N - 1, z >= 1, z < LPV_N - 1};
  const int stride[3] = {1, LPV_ROW, LPV_SLICE};
  floatL maxMain[6], maxSide[6];  // the open step's factors
  if (!blocking) lpv_open_factors(x0, maxMain, maxSide);
  // The source row a work-item touches first is its z + 1 neighbour row: its loads waited on
  // memory (17 % of the blocked step's samples). Prefetched here for the next work-group (y + 1),
  // one line per plane: −13 % CPU time (docs/PERFORMANCE.md).
#pragma unroll
  for (int p = 0; p < 12; ++p) LPV_PREFETCH(src + row + LPV_SLICE + LPV_ROW + p * LPV_N);
  // When a step's working set (3 grids and the face factors, 204 bytes per cell: 53.5 MB at 64³)
  // exceeds the last-level cache (LPV_PREFETCH_STREAMS, set by the host from the device's global
  // memory cache size), every stream comes from DRAM and waits on it: the next work-group's face
  // factors, destination row and accumulated row are prefetched too (−30 to −57 % CPU at 64³,
  // docs/PERFORMANCE.md). Where the grids stay in cache (32³: 6.7 MB) these 54 more prefetches
  // per work-item cost more than they save (+8 %), so they are left out there.
#if LPV_PREFETCH_STREAMS
  if (blocking) {
    global const half* nextFactors = faceFactors + LPV_PAD + LPV_FACTOR_AT(k, 0, x0, y, z) + LPV_FACTOR_ROW;
#pragma unroll
    for (int p = 0; p < 30; ++p) LPV_PREFETCH(nextFactors + p * LPV_N);
  }
#pragma unroll
  for (int p = 0; p < 12; ++p) LPV_PREFETCH_WRITE(dst + row + LPV_ROW + p * LPV_N);
  if (accumulate & LPV_ADD_THIS) {
#pragma unroll
    for (int p = 0; p < 12; ++p) LPV_PREFETCH_WRITE(accumulated + row + LPV_ROW + p * LPV_N);
  }
#endif
  floatL o[3][4];
#pragma unroll
  for (int ch = 0; ch < 3; ++ch) o[ch][0] = o[ch][1] = o[ch][2] = o[ch][3] = (floatL)(0.0f);
#pragma unroll
  for (int dir = 0; dir < 6; ++dir) {
    if (!inside[dir]) continue;  // whole row outside (y, z neighbours)
    floatL t[5];
    if (blocking) {
      global const half* factors = faceFactors + LPV_PAD + LPV_FACTOR_AT(k, dir * 5, x0, y, z);
#pragma unroll
      for (int f = 0; f < 5; ++f) t[f] = lpv_load_factor(factors + f * LPV_N);
    } else {
      t[0] = maxMain[dir];
      t[1] = t[2] = t[3] = t[4] = maxSide[dir];
    }
    // x neighbours past the row are the neighbouring plane's cell or padding: factor 0 there.
    int nb = -(dir % 2 ? -1 : 1) * stride[dir / 2];
#pragma unroll
    for (int ch = 0; ch < 3; ++ch) {
      floatL in[4];
#pragma unroll
      for (int q = 0; q < 4; ++q) in[q] = vloadL(0, src + row + ch * 4 * LPV_N + q * LPV_N + nb);
      lpv_faces(dir, in, t, o[ch]);
    }
  }
#pragma unroll
  for (int ch = 0; ch < 3; ++ch) {
    size_t planes = row + ch * 4 * LPV_N;
    const float lobe[4] = {GI_SH_LOBE0 * LPV_UNIT0, GI_SH_LOBE1 * LPV_UNIT1, GI_SH_LOBE1 * LPV_UNIT1,
                           GI_SH_LOBE1 * LPV_UNIT1};  // re-emitted cosine lobes, in grid units
    floatL total[4];
#pragma unroll
    for (int q = 0; q < 4; ++q) {
      size_t at = planes + q * LPV_N;
      floatL out = lobe[q] * o[ch][q];
      lpv_storeL(out, dst + at);
      if (accumulate & LPV_ADD_THIS) {
        floatL sum = accumulate & LPV_ADD_SOURCE ? vloadL(0, src + at) + out : out;
        total[q] = vloadL(0, accumulated + at) + sum;
        lpv_storeL(total[q], accumulated + at);
      }
    }
    if (accumulate & LPV_WRITE_LOOKUP)
      lpv_store_lookup_cells(total, cascades, k, ch, (z * LPV_N + y) * LPV_N + x0, lookupGrid);
  }
}

kernel void lpv_propagate_blocked(global const float* src, global float* dst, global float* accumulated,
                                  global const half* faceFactors, int k, int accumulate,
                                  constant float4* cascades, global float4* lookupGrid) {
  lpv_propagate_step(src, dst, accumulated, faceFactors, k, accumulate, cascades, lookupGrid, true);
}

kernel void lpv_propagate_open(global const float* src, global float* dst, global float* accumulated, int k,
                               int accumulate, constant float4* cascades, global float4* lookupGrid) {
  lpv_propagate_step(src, dst, accumulated, 0, k, accumulate, cascades, lookupGrid, false);
}

// ---- multiple bounces (lpv.bounces; Kaplanyan & Dachsbacher 2010, "multiple indirect bounces") ----
//
// Light that the geometry volume blocks in a propagation step is not lost: the blocker reflects
// it diffusely with its albedo ρ and it propagates on in the next steps, which gives the orders
// >= 3 of the transport. For light leaving cell c along d towards c + d, the flux the shared face
// blocks is Σ_f (ΔΩ_f/π − T_f) · max(0, I_c(ω_f)) · π over the 5 faces (the step transmits
// T_f · I, the open step ΔΩ_f/π · I; T_f as stored by lpv_face_factors, so the blocked and the
// transmitted flux add up to the open flux exactly). A fraction ρ of it leaves the blocker as a
// Lambertian emitter: coefficients ρ · Φ_b/π · lobe(n) (the VPL injection's form), added to c —
// the side the light came from — with n the normal of the blocker, the direction of the face
// potential's linear part (Σ A·n of its surfels) turned towards c (−d where that part is zero).

// Area-weighted albedo of each cell's 3 lower faces, once per frame: Σ ρ·w / Σ w over the face's 4
// corner nodes (integer sums: exact, in any order); 0 where no camera surfel lies at those nodes
// (the RSM has no albedo). Planes a·4 + ch of the grids' row-block layout (LPV_AT). Global
// (N / LPV_LANES, N, N · 3 · LPV_CASCADES) with z + N·(k·3 + a) along the third axis.
kernel void lpv_face_albedo(global const long* albedoAcc, global float* faceAlbedo) {
  int x0 = get_global_id(0) * LPV_LANES, y = get_global_id(1), z = get_global_id(2) % LPV_N;
  int slab = get_global_id(2) / LPV_N, k = slab / 3, a = slab % 3;  // slab = k·3 + axis
  size_t u = a == 0 ? LPV_M : 1, v = a == 2 ? LPV_M : LPV_M * LPV_M;  // the face's two in-plane axes
  global float* out = faceAlbedo + LPV_PAD + LPV_AT(k, a * 4, x0, y, z);
  for (int l = 0; l < LPV_LANES; ++l) {
    size_t n0 = (size_t)k * LPV_NODES + (size_t)(z * LPV_M + y) * LPV_M + x0 + l;
    long4 sum = vload4(n0, albedoAcc) + vload4(n0 + u, albedoAcc) + vload4(n0 + v, albedoAcc) +
                vload4(n0 + u + v, albedoAcc);
    float4 f = lpv_fixed_to_float4(sum);  // the fixed-point scale cancels in the ratio
    float4 rho = f.w > 0.0f ? f / f.w : (float4)(0.0f);
    out[l] = rho.x;
    out[l + LPV_N] = rho.y;
    out[l + 2 * LPV_N] = rho.z;
  }
}

// LPV_LANES halves from any half-aligned address as floats. The x neighbours' factors lie one half
// off the row's alignment: PoCL's vload_half8 compiled to an aligned 16-byte load there (a crash),
// and clang's __fp16 vectors with 2-byte alignment to much slower code. So the bits are loaded as one unaligned ushort vector and widened
// exactly by integer operations: a normal half (exponent e > 0) is the float with exponent e + 112
// and the mantissa shifted by 13; a subnormal is its mantissa × 2^-24 (the half grid's inputs are
// finite: clamped to ±65504 where they are written).
inline floatL lpv_load_half_unaligned(global const half* p) {
  intL h = convert_intL(vloadL(0, (global const ushort*)p));
  intL sign = (h & 0x8000) << 16, magnitude = h & 0x7fff;
  floatL normal = as_floatL(sign | ((magnitude << 13) + (112 << 23)));
  floatL subnormal = convert_floatL(magnitude) * 0x1.0p-24f;
  return select(normal, select(subnormal, -subnormal, sign != 0), magnitude < 0x400);
}

// The reflection of one blocked step of cascade k (after lpv_propagate_blocked read `src` and wrote
// `dst`): each cell's light that the faces to its 6 neighbours blocked, reflected back into the
// cell and added to `dst` (so the next step propagates it) and, when that step added its result
// to the accumulated grid (`addToAccumulated`), there too. Work-item = LPV_LANES cells of a row,
// as the step. The factors of the faces c → c + d are those lpv_face_factors stored at c + d for
// direction d.
kernel void lpv_reflect_blocked(global const float* src, global float* dst, global float* accumulated,
                                global const half* faceFactors, global const half* faceGeometry,
                                global const float* faceAlbedo, int k, int addToAccumulated) {
  int x0 = get_global_id(0) * LPV_LANES, y = get_global_id(1), z = get_global_id(2);
  size_t row = LPV_PAD + LPV_AT(k, 0, x0, y, z), factorRow = LPV_PAD + LPV_FACTOR_AT(k, 0, x0, y, z);
  // Whether c + d lies in the grid: per row for y and z; per lane for x (open factor 0 there).
  bool rowInside[6] = {true, true, y < LPV_N - 1, y >= 1, z < LPV_N - 1, z >= 1};
  intL x = x0 + LPV_LANE_IDS;
  const float mainWeight = LPV_MAIN_FACE_SOLID_ANGLE * GI_INV_PI, sideWeight = LPV_SIDE_FACE_SOLID_ANGLE * GI_INV_PI;
  floatL openX[2] = {select((floatL)(0.0f), (floatL)(1.0f), x < LPV_N - 1), select((floatL)(0.0f), (floatL)(1.0f), x >= 1)};
  const int stride[3] = {1, LPV_ROW, LPV_SLICE}, factorStride[3] = {1, LPV_FACTOR_ROW, LPV_FACTOR_SLICE};
  // The 12 own coefficients and 12 sums stay in registers over the 6 directions; each direction's
  // 5 blocked factors, normal and albedo are loaded and converted once for the 3 channels (channel
  // after channel instead, reloading them, looked slower in single runs: docs/PERFORMANCE.md).
  floatL own[3][4], o[3][4];
#pragma unroll
  for (int ch = 0; ch < 3; ++ch)
#pragma unroll
    for (int q = 0; q < 4; ++q) {
      own[ch][q] = vloadL(0, src + row + (ch * 4 + q) * LPV_N);
      o[ch][q] = (floatL)(0.0f);
    }
#pragma unroll
  for (int dir = 0; dir < 6; ++dir) {
    if (!rowInside[dir]) continue;
    int a = dir / 2, b1 = (a + 1) % 3, b2 = (a + 2) % 3;
    float s = dir % 2 ? -1.0f : 1.0f;
    int step = dir % 2 ? -1 : 1;
    floatL open = a == 0 ? openX[dir & 1] : (floatL)(1.0f);
    // Blocked factors ΔΩ_f/π − T_f of the faces c → c + d (stored at c + d).
    global const half* factors = faceFactors + factorRow + step * factorStride[a] + dir * 5 * LPV_N;
    floatL blocked[5];
#pragma unroll
    for (int f = 0; f < 5; ++f)
      blocked[f] = fmax(open * (f == 0 ? mainWeight : sideWeight) - lpv_load_half_unaligned(factors + f * LPV_N), 0.0f);
    // The shared face: the lower face along a of c + d (d = +e_a) or of c (d = −e_a).
    size_t face = row + (dir % 2 ? 0 : stride[a]);
    floatL g[4];
#pragma unroll
    for (int q = 1; q < 4; ++q) g[q] = lpv_load_half_unaligned(faceGeometry + face + (a * 4 + q) * LPV_N);
    // Blocker normal (y, z, x order as the coefficients), turned towards c: n·d <= 0.
    floatL l2 = g[1] * g[1] + g[2] * g[2] + g[3] * g[3];
    floatL inv = select((floatL)(0.0f), rsqrt(l2), l2 > 1e-30f) *
                 select((floatL)(1.0f), (floatL)(-1.0f), s * g[LPV_COEF(a)] > 0.0f);
    floatL n[4];  // coefficient order: unused, y, z, x
#pragma unroll
    for (int q = 1; q < 4; ++q) n[q] = g[q] * inv;
    n[LPV_COEF(a)] = select(n[LPV_COEF(a)], (floatL)(-s), l2 <= 1e-30f);
#pragma unroll
    for (int ch = 0; ch < 3; ++ch) {
      const floatL* in = own[ch];
      // I_c(ω_f) in grid units, as lpv_faces evaluates them.
      floatL fMain = fmax(fma(in[LPV_COEF(a)], (floatL)(s / LPV_SIDE_SCALE), in[0]), 0.0f);
      floatL side = fma(in[LPV_COEF(a)], (floatL)(2.0f * s), in[0]);
      floatL flux = blocked[0] * fMain;  // Φ_b/π
      flux = fma(blocked[1], fmax(side + in[LPV_COEF(b1)], 0.0f), flux);
      flux = fma(blocked[2], fmax(side - in[LPV_COEF(b1)], 0.0f), flux);
      flux = fma(blocked[3], fmax(side + in[LPV_COEF(b2)], 0.0f), flux);
      flux = fma(blocked[4], fmax(side - in[LPV_COEF(b2)], 0.0f), flux);
      floatL reflected = vloadL(0, faceAlbedo + face + (a * 4 + ch) * LPV_N) * flux;
      o[ch][0] += reflected;
#pragma unroll
      for (int q = 1; q < 4; ++q) o[ch][q] = fma(reflected, n[q], o[ch][q]);
    }
  }
  const float lobe[4] = {GI_SH_LOBE0 * LPV_UNIT0, GI_SH_LOBE1 * LPV_UNIT1, GI_SH_LOBE1 * LPV_UNIT1,
                         GI_SH_LOBE1 * LPV_UNIT1};  // Lambertian emitter, in grid units
#pragma unroll
  for (int ch = 0; ch < 3; ++ch)
#pragma unroll
    for (int q = 0; q < 4; ++q) {
      size_t at = row + (ch * 4 + q) * LPV_N;
      floatL out = lobe[q] * o[ch][q];
      lpv_storeL(vloadL(0, dst + at) + out, dst + at);
      if (addToAccumulated) lpv_storeL(vloadL(0, accumulated + at) + out, accumulated + at);
    }
}

// ---- lookup ----------------------------------------------------------------------------------

// The lookup grid: per cascade k, cell and channel ch one float4 (LPV_LOOKUP_AT) holding the
// accumulated coefficients times the clamped-cosine convolution and
// 1/s² (radiance = intensity / s²): irradiance coefficients q with E(n) = q.x − q.y·n.y − q.z·n.z −
// q.w·n.x for a surface with normal n (light arriving travels along −n). The lookup interpolates
// them trilinearly; E is linear in q, so this equals the convolution of the interpolated grid.
// LPV_LANES cells of a row per work-item, global (N / LPV_LANES, N, N · 3 · LPV_CASCADES) with
// z + N·(k·3 + ch) along the third axis: the 4 coefficient rows are contiguous loads (one
// work-item per cell and channel compiled to scalar code).
kernel void lpv_lookup_grid(global const float* accumulated, constant float4* cascades, global float4* lookupGrid) {
  int x0 = get_global_id(0) * LPV_LANES, y = get_global_id(1), z = get_global_id(2) % LPV_N;
  int slab = get_global_id(2) / LPV_N, k = slab / 3, ch = slab % 3;  // slab = k·3 + ch
  global const float* c = accumulated + LPV_PAD + LPV_AT(k, ch * 4, x0, y, z);
  floatL coefficients[4] = {vloadL(0, c), vloadL(0, c + LPV_N), vloadL(0, c + 2 * LPV_N), vloadL(0, c + 3 * LPV_N)};
  lpv_store_lookup_cells(coefficients, cascades, k, ch, (z * LPV_N + y) * LPV_N + x0, lookupGrid);
}

// The lookup grid is a 3D image (LPV_N × LPV_N × LPV_N·3·cascades, the slabs stacked along z) on
// devices that filter images in hardware, a float4 buffer otherwise. The sample coordinates are
// clamped to the slab's border cell centres, so the linear filter never mixes two slabs.
#if LPV_IMAGES
#define LPV_LOOKUP_GRID read_only image3d_t
constant sampler_t lpv_trilinear_sampler = CLK_NORMALIZED_COORDS_FALSE | CLK_ADDRESS_CLAMP_TO_EDGE | CLK_FILTER_LINEAR;
#else
#define LPV_LOOKUP_GRID global const float4*
#endif

// The smallest lane of v.
inline int lpv_min_lane(intV v) {
#if GI_VW == 1
  return v;
#else
#if GI_VW == 16
  int8 v8 = min(v.lo, v.hi);
#else
  int8 v8 = v;
#endif
  int4 v4 = min(v8.lo, v8.hi);
  int2 v2 = min(v4.lo, v4.hi);
  return min(v2.x, v2.y);
#endif
}

// Irradiance (W/m² per channel) of GI_VW pixels at p with geometric normal ng and shading normal n
// from cascade k (per lane): trilinear over cell centres at p + ½ cell along ng (clamped at the
// grid's border cells) in the lookup grid, E = Σ_corners weight · (q0 − q·n).
__attribute__((always_inline)) inline void cascade_irradiance(LPV_LOOKUP_GRID grid, constant float4* cascades, intV k, float3V p, float3V ng,
                               float3V n, float offset, floatV* e) {
  // Cell coordinates (p − origin)/s + ½·ng − ½ with 1/s per cascade (a scalar division each, not
  // 3 vector divisions per lane).
  floatV ox = 0.0f, oy = 0.0f, oz = 0.0f, invS = 1.0f;
#pragma unroll
  for (int j = 0; j < LPV_CASCADES; ++j) {
    float4 c = cascades[j];
    intV here = k == j;
    ox = GI_SEL(ox, (floatV)(c.x), here);
    oy = GI_SEL(oy, (floatV)(c.y), here);
    oz = GI_SEL(oz, (floatV)(c.z), here);
    invS = GI_SEL(invS, (floatV)(1.0f / c.w), here);
  }
  floatV ux = clamp(fma(p.x - ox, invS, fma(offset, ng.x, -0.5f)), 0.0f, (float)(LPV_N - 1));
  floatV uy = clamp(fma(p.y - oy, invS, fma(offset, ng.y, -0.5f)), 0.0f, (float)(LPV_N - 1));
  floatV uz = clamp(fma(p.z - oz, invS, fma(offset, ng.z, -0.5f)), 0.0f, (float)(LPV_N - 1));
#if LPV_IMAGES
  // The sampler filters lane by lane: texel centres at integer + ½, slab (k·3 + ch) at depth (k·3 + ch)·N.
  float u[3][GI_VW], q[3][4][GI_VW];
  int slab[GI_VW];
  vstoreV(ux, 0, u[0]);
  vstoreV(uy, 0, u[1]);
  vstoreV(uz, 0, u[2]);
  vstoreV(k * 3, 0, slab);
  for (int l = 0; l < GI_VW; ++l)
#pragma unroll
    for (int ch = 0; ch < 3; ++ch) {
      float4 v = read_imagef(grid, lpv_trilinear_sampler,
                             (float4)(u[0][l] + 0.5f, u[1][l] + 0.5f, (slab[l] + ch) * LPV_N + u[2][l] + 0.5f, 0.0f));
      q[ch][0][l] = v.x;
      q[ch][1][l] = v.y;
      q[ch][2][l] = v.z;
      q[ch][3][l] = v.w;
    }
#pragma unroll
  for (int ch = 0; ch < 3; ++ch)
    e[ch] = vloadV(0, q[ch][0]) - vloadV(0, q[ch][1]) * n.y - vloadV(0, q[ch][2]) * n.z - vloadV(0, q[ch][3]) * n.x;
#else
  intV cx = min(convert_intV(floor(ux)), (intV)(LPV_N - 2)), cy = min(convert_intV(floor(uy)), (intV)(LPV_N - 2)),
       cz = min(convert_intV(floor(uz)), (intV)(LPV_N - 2));
  floatV fx = ux - convert_floatV(cx), fy = uy - convert_floatV(cy), fz = uz - convert_floatV(cz);
  floatV gx = 1.0f - fx, gy = 1.0f - fy, gz = 1.0f - fz;
  const floatV weight[8] = {gx * gy * gz, fx * gy * gz, gx * fy * gz, fx * fy * gz,
                            gx * gy * fz, fx * gy * fz, gx * fy * fz, fx * fy * fz};  // corner bits x, y, z
  const int corner[8] = {0, 1, LPV_N, LPV_N + 1, LPV_N * LPV_N, LPV_N * LPV_N + 1, LPV_N * LPV_N + LPV_N,
                         LPV_N * LPV_N + LPV_N + 1};
  intV cell = k * LPV_CELLS + (cz * LPV_N + cy) * LPV_N + cx;  // the lower corner cell (LPV_LOOKUP_AT)
  e[0] = e[1] = e[2] = 0.0f;
  // Each distinct lower corner cell among the lanes once, in ascending order: its 8 corners are
  // loaded once (uniform loads) and used by the lanes that interpolate from it — usually all of
  // them, as a cell spans many pixels. No per-lane gathers; every lane's sum is the same
  // expression in the same order whichever lanes share its cell.
  intV todo = cell >= 0;  // all lanes
  while (GI_ANY(todo)) {
    int base = lpv_min_lane(GI_SEL((intV)(INT_MAX), cell, todo));
    intV mine = cell == base;
    todo = todo && cell != base;  // not `todo && !mine`: see the top of the file
#pragma unroll
    for (int ch = 0; ch < 3; ++ch) {
      global const float4* g = grid + LPV_LOOKUP_AT(0, ch, base);
      floatV sum = 0.0f;
#pragma unroll
      for (int i = 0; i < 8; ++i) {
        float4 q = g[corner[i] * LPV_LOOKUP_CELL_STRIDE];
        sum += weight[i] * (q.x - q.y * n.y - q.z * n.z - q.w * n.x);  // light arriving travels along −n
      }
      e[ch] = GI_SEL(e[ch], sum, mine);
    }
  }
#endif
}

// Blend factor of seed 003 eq. 3.2: 0 well inside cascade k, rising to 1 over the outer tenth of
// its extent (largest component over the axes).
inline floatV cascade_blend(float4 cascade, float3V p) {
  float extent = cascade.w * LPV_N, w = 0.1f * extent, invW = 1.0f / w;  // one scalar division
  float3 centre = cascade.xyz + 0.5f * extent;
  floatV ax = clamp((fabs(p.x - centre.x) - (0.5f * extent - w)) * invW, 0.0f, 1.0f);
  floatV ay = clamp((fabs(p.y - centre.y) - (0.5f * extent - w)) * invW, 0.0f, 1.0f);
  floatV az = clamp((fabs(p.z - centre.z) - (0.5f * extent - w)) * invW, 0.0f, 1.0f);
  return fmax(ax, fmax(ay, az));
}

// Irradiance at `offset` cells along ng from cascade k, mixed with the next coarser cascade by a.
__attribute__((always_inline)) inline void blended_irradiance(LPV_LOOKUP_GRID grid, constant float4* cascades, intV k, floatV a,
                                                              float3V p, float3V ng, float3V n, float offset, floatV* e) {
  cascade_irradiance(grid, cascades, k, p, ng, n, offset, e);
  if (GI_ANY(a > 0.0f)) {
    floatV coarse[3];
    cascade_irradiance(grid, cascades, min(k + 1, (intV)(LPV_CASCADES - 1)), p, ng, n, offset, coarse);
#pragma unroll
    for (int ch = 0; ch < 3; ++ch) e[ch] = mix(e[ch], coarse[ch], a);
  }
}

// `damping` (lpv.damping; Kaplanyan 2009, self-illumination): the irradiance E(x) a surface
// receives is light travelling along −n, whose sources lie on the n side; where E decreases
// along n (its directional derivative along the normal is negative) the light flows away from
// the surface — its own light, or light bled through it — and is damped. The derivative is
// taken as a forward difference over one cell (the grid's resolution, the heuristic's only
// parameter): E is limited to max(E(x + s·ng), 0), s the cell edge.
// GI_VW pixels of a row per work-item (global (⌈width / GI_VW⌉, height)). `blendCascades` = 0 for
// a single grid fitted to the scene; else per pixel the finest cascade whose blend factor is below
// 1, mixed with the next coarser one by that factor (constant-trip loops only).
kernel void lpv_lookup(int width, int height, global const float* position, global const float* geoNormal,
                       global const float* normal, global const float* albedo, constant float4* cascades,
                       int blendCascades, int damping, LPV_LOOKUP_GRID grid, global float4* out) {
  int x0 = get_global_id(0) * GI_VW, y = get_global_id(1);
  if (x0 >= width || y >= height) return;
  intV x = x0 + GI_LANES;
  intV pixel = y * width + min(x, (intV)(width - 1));  // lanes past the row's end re-read its last pixel, not stored
  float3V p, ng, n, rho;
  floatV pw, unused;
  GI_GATHER_AOS4(float, position, pixel, p.x, p.y, p.z, pw);
  GI_GATHER_AOS4(float, geoNormal, pixel, ng.x, ng.y, ng.z, unused);
  GI_GATHER_AOS4(float, normal, pixel, n.x, n.y, n.z, unused);
  GI_GATHER_AOS4(float, albedo, pixel, rho.x, rho.y, rho.z, unused);
  intV covered = pw > 0.0f;
  p = selV(f3v(0.0f, 0.0f, 0.0f), p, covered);  // empty pixels: any finite point, result dropped
  intV k = 0;
  floatV a = 0.0f;
  if (blendCascades) {
    a = cascade_blend(cascades[0], p);
#pragma unroll
    for (int j = 1; j < LPV_CASCADES; ++j) {
      intV coarser = a >= 1.0f;
      k = GI_SEL(k, (intV)(j), coarser);
      a = GI_SEL(a, cascade_blend(cascades[j], p), coarser);
    }
    a = GI_SEL(a, (floatV)(0.0f), k == LPV_CASCADES - 1);  // the coarsest cascade blends with nothing
  }
  floatV e[3];
  blended_irradiance(grid, cascades, k, a, p, ng, n, 0.5f, e);
  if (damping) {  // Kaplanyan 2009's damping of light that flows away from the surface
    floatV outer[3];
    blended_irradiance(grid, cascades, k, a, p, ng, n, 1.5f, outer);
#pragma unroll
    for (int ch = 0; ch < 3; ++ch) e[ch] = fmin(e[ch], fmax(outer[ch], 0.0f));
  }
  floatV keep = GI_SEL((floatV)(0.0f), (floatV)(GI_INV_PI), covered);
  floatV lr = fmax(rho.x * keep * e[0], 0.0f), lg = fmax(rho.y * keep * e[1], 0.0f), lb = fmax(rho.z * keep * e[2], 0.0f);
#if GI_VW == 1
  out[pixel] = (float4)(lr, lg, lb, 0.0f);
#else
  if (x0 + GI_VW <= width) {
    floatV zero = 0.0f;
    GI_AOS4_STORE((global float*)(out + y * width + x0), lr, lg, lb, zero);
  } else {
    float vals[3][GI_VW];
    vstoreV(lr, 0, vals[0]);
    vstoreV(lg, 0, vals[1]);
    vstoreV(lb, 0, vals[2]);
    for (int l = 0; x0 + l < width; ++l) out[y * width + x0 + l] = (float4)(vals[0][l], vals[1][l], vals[2][l], 0.0f);
  }
#endif
}
