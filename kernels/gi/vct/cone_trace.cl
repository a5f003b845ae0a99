// The cone-traced passes of `vct` (ALGORITHMS.md §5; cone.h for the march and the cone sets).
// Build defines: GI_VCT_CONES (6 or 9), GI_DOWN (diffuse tracing every GI_DOWN-th pixel), GI_VW
// (pixels per work-item of vct_diffuse and vct_specular, common/vector_width.h), GI_VCT_SH
// (1: SH voxels, read from `sh` / `shAniso`; voxel_grid.h), GI_VCT_DIRECTIONAL (1: directional
// voxels, level 0 read from `aniso` too; voxel_grid.h).
// Every kernel takes the four mip chains iso, aniso, sh, shAniso (voxel_grid.h); the unread ones may
// be any buffer.
//
// vct_diffuse   per traced pixel: E from the diffuse cones at its position and shading normal;
//               a tile of GI_VW traced pixels per work-item (VCT_TILE_W × VCT_TILE_H, cone_lanes.h).
//               GI_DOWN = 1 writes L = ρ/π · E (· voxel AO visibility if asked) per pixel;
//               GI_DOWN > 1 writes E for the geometry-aware upsampler (filters/discontinuity.cl).
// vct_specular  per pixel (a tile of GI_VW per work-item, cone_lanes.h): adds F_Schlick(F0, n·ωo) · L_cone
//               along the mirror direction, the cone's half-angle from the GGX width, tan θ = α
//               (α = roughness²). The BRDF's directional albedo is approximated by F(n·ωo) alone
//               (no masking term). The march: level-aligned with sub-steps
//               (vct_cone_levels_varying_lanes, tp.specularLevelSteps) or continuous (vct_cone_lanes;
//               also with footprint in front). emptySpace: for the continuous march, the empty-space
//               map (voxel_light.cl), or null: lookups that read only empty cells are left out
//               (same result).
// vct_bounce    per occupied voxel: its injected direct level-0 radiance plus ρ/π · E_indirect, the
//               diffuse cones from the voxel's surface point along its normal through the current
//               mips. Run k − 1 times (re-mipping in between) for k bounces: each run adds one more
//               order of the light paths (L_k = L_direct + T·L_{k−1}).
// vct_trace_cones  arbitrary cones (tests, debugging), one at a time: the continuous march, or with
//               specularLevelSteps the level-aligned one with sub-steps (vct_specular's references).
// vct_irradiance_points  the one-cone-at-a-time march (cone.h) of the diffuse set at arbitrary
//               points (tests: vct_diffuse's lanes against it).
#include "common/brdf.h"
#include "gi/vct/cone.h"
#include "gi/vct/cone_lanes.h"

typedef struct {
  float startOffset;  // voxels along the normal before the first sample
  float maxDistance;  // voxels
  float stepFactor;
  float aoLambda;     // AO distance falloff, per voxel
  int anisotropic;
  int applyAo;        // multiply the diffuse result by the voxel AO visibility
  int footprintInFront;  // keep the sampled footprint in front of the surface (cone.h)
  int levelSteps;        // diffuse cones: the level-aligned march (cone.h, vct_cone_levels)
  int specularLevelSteps;  // specular cone (and vct_trace_cones): the level-aligned march with sub-steps
} VctTraceParams;

inline float3 vct_to_voxels(GiVoxelGrid g, float3 x) { return (x - vload3(0, g.origin)) / g.voxel_size; }

inline VoxelMips vct_mips(GiVoxelGrid g, VctTraceParams tp, global const float4* iso, global const float4* aniso,
                          global const float4* sh, global const float4* shAniso) {
  VoxelMips m;
  m.iso = iso;
  m.aniso = aniso;
  m.sh = sh;
  m.shAniso = shAniso;
  m.N = g.resolution;
  m.levels = g.levels;
  m.anisotropic = tp.anisotropic;
  return m;
}

#define VCT_MIP_ARGS global const float4 *iso, global const float4 *aniso, global const float4 *sh, global const float4 *shAniso

// vct_diffuse's and vct_specular's lanes are a tile of VCT_TILE_W × VCT_TILE_H (traced) pixels (4×4
// for 16 lanes, 4×2 for 8): neighbouring pixels' diffuse cones read the same cells of the coarse
// levels more often than those of a row of GI_VW pixels, and such lookups are shared
// (vox_level_sample_uniform_lanes); neighbouring specular cones have more similar apertures and
// lengths. The host launches ⌈width / VCT_TILE_W⌉ × ⌈height / VCT_TILE_H⌉ work-items
// (vctLaneTileWidth in src/gi/vct/vct_technique.h).
#if GI_VW >= 8
#define VCT_TILE_W 4
#else
#define VCT_TILE_W 1
#endif
#define VCT_TILE_H (GI_VW / VCT_TILE_W)

kernel void vct_diffuse(GiVoxelGrid grid, VctTraceParams tp, VCT_MIP_ARGS, int width, int height, int lowWidth,
                        int lowHeight, global const float4* gPosition, global const float4* gNormal,
                        global const float4* gAlbedo, global float4* out) {
  int u0 = get_global_id(0) * VCT_TILE_W, v0 = get_global_id(1) * VCT_TILE_H;
  if (u0 >= lowWidth || v0 >= lowHeight) return;
  // min(vector, (intV)(scalar)), not min(vector, scalar): oclgrind evaluates the mixed form wrongly
  // (garbage gather addresses at 8 and 16 lanes); PoCL gives the same code either way.
  intV u = min(u0 + GI_LANES % VCT_TILE_W, (intV)(lowWidth - 1)), v = min(v0 + GI_LANES / VCT_TILE_W, (intV)(lowHeight - 1));
  intV q = min(v * GI_DOWN, (intV)(height - 1)) * width + min(u * GI_DOWN, (intV)(width - 1));
  floatV px, py, pz, pw, nx, ny, nz, nw;
  GI_GATHER_AOS4(float, (global const float*)gPosition, q, px, py, pz, pw)
  GI_GATHER_AOS4(float, (global const float*)gNormal, q, nx, ny, nz, nw)
  intV covered = pw != 0.0f;
  floatV er = (floatV)(0.0f), eg = er, eb = er;
  if (GI_ANY(covered)) {
    float3 origin = vload3(0, grid.origin);
    float3V p = f3v((px - origin.x) / grid.voxel_size, (py - origin.y) / grid.voxel_size,
                    (pz - origin.z) / grid.voxel_size);
    RgbaV e = vct_diffuse_irradiance_lanes(vox_mips_lanes(vct_mips(grid, tp, iso, aniso, sh, shAniso)), p,
                                           f3v(nx, ny, nz), tp.startOffset, tp.maxDistance, tp.stepFactor,
                                           tp.aoLambda, tp.footprintInFront, tp.levelSteps);
    floatV scale = tp.applyAo ? e.a : (floatV)(1.0f);
#if GI_DOWN == 1
    floatV ar, ag, ab, aw;
    GI_GATHER_AOS4(float, (global const float*)gAlbedo, q, ar, ag, ab, aw)
    scale *= GI_INV_PI;
    er = ar * e.r * scale;
    eg = ag * e.g * scale;
    eb = ab * e.b * scale;
#else
    er = e.r * scale;
    eg = e.g * scale;
    eb = e.b * scale;
#endif
    er = GI_SEL((floatV)(0.0f), er, covered);
    eg = GI_SEL((floatV)(0.0f), eg, covered);
    eb = GI_SEL((floatV)(0.0f), eb, covered);
  }
  float vals[3][GI_VW];
  vstoreV(er, 0, vals[0]);
  vstoreV(eg, 0, vals[1]);
  vstoreV(eb, 0, vals[2]);
  for (int l = 0; l < GI_VW; ++l) {
    int ul = u0 + l % VCT_TILE_W, vl = v0 + l / VCT_TILE_W;
    if (ul < lowWidth && vl < lowHeight) out[(size_t)vl * lowWidth + ul] = (float4)(vals[0][l], vals[1][l], vals[2][l], 0.0f);
  }
}

kernel void vct_specular(GiVoxelGrid grid, VctTraceParams tp, VCT_MIP_ARGS, global const uchar* emptySpace, GiView camera,
                         global const float4* gPosition, global const float4* gNormal,
                         global const float4* gSpecular, global float4* out) {
  int x0 = get_global_id(0) * VCT_TILE_W, y0 = get_global_id(1) * VCT_TILE_H;
  if (x0 >= camera.width || y0 >= camera.height) return;
  intV q = min(y0 + GI_LANES / VCT_TILE_W, (intV)(camera.height - 1)) * camera.width +
           min(x0 + GI_LANES % VCT_TILE_W, (intV)(camera.width - 1));  // (intV): see vct_diffuse
  floatV px, py, pz, pw, nx, ny, nz, nw, f0r, f0g, f0b, roughness;
  GI_GATHER_AOS4(float, (global const float*)gPosition, q, px, py, pz, pw)
  GI_GATHER_AOS4(float, (global const float*)gNormal, q, nx, ny, nz, nw)
  float3V n = f3v(nx, ny, nz), wo;
  if (camera.orthographic) {
    float3 w = -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz);
    wo = f3v((floatV)(w.x), (floatV)(w.y), (floatV)(w.z));
  } else {
    wo = f3v(camera.eye[0] - px, camera.eye[1] - py, camera.eye[2] - pz);
    wo = scaleV(wo, rsqrt(dotV(wo, wo)));
  }
  floatV nv = dotV(n, wo);
  intV active = pw != 0.0f && nv > 0.0f;
  if (!GI_ANY(active)) return;
  GI_GATHER_AOS4(float, (global const float*)gSpecular, q, f0r, f0g, f0b, roughness)
  float3V r = subV(scaleV(n, 2.0f * nv), wo);
  floatV tanHalf = fmax(roughness * roughness, GI_MIN_GGX_ALPHA);  // ggx_alpha
  float3 origin = vload3(0, grid.origin);
  float3V p = f3v((px - origin.x) / grid.voxel_size, (py - origin.y) / grid.voxel_size,
                  (pz - origin.z) / grid.voxel_size);
  floatV occ;
  VoxelMipsV m = vox_mips_lanes(vct_mips(grid, tp, iso, aniso, sh, shAniso));
  float3V o = addV(p, scaleV(n, (floatV)(tp.startOffset)));
  RgbaV c = tp.specularLevelSteps && !tp.footprintInFront
                ? vct_cone_levels_varying_lanes(m, o, r, tanHalf, tp.maxDistance, tp.stepFactor, tp.aoLambda, &occ)
                : vct_cone_lanes(m, emptySpace, o, r, tanHalf, tp.maxDistance, tp.stepFactor, tp.aoLambda,
                                 tp.footprintInFront ? tp.startOffset : INFINITY, dotV(r, n), &occ);
  // fresnel_schlick(F0, n·ωo) lane-wise
  floatV mm = clamp(1.0f - nv, 0.0f, 1.0f), m5 = mm * mm * mm * mm * mm;
  float vals[4][GI_VW];
  vstoreV((f0r + (1.0f - f0r) * m5) * c.r, 0, vals[0]);
  vstoreV((f0g + (1.0f - f0g) * m5) * c.g, 0, vals[1]);
  vstoreV((f0b + (1.0f - f0b) * m5) * c.b, 0, vals[2]);
  vstoreV(GI_SEL((floatV)(0.0f), (floatV)(1.0f), active), 0, vals[3]);
  for (int l = 0; l < GI_VW; ++l) {
    int xl = x0 + l % VCT_TILE_W, yl = y0 + l / VCT_TILE_W;
    if (vals[3][l] != 0.0f && xl < camera.width && yl < camera.height)
      out[(size_t)yl * camera.width + xl].xyz += (float3)(vals[0][l], vals[1][l], vals[2][l]);
  }
}

kernel void vct_bounce(GiVoxelGrid grid, VctTraceParams tp, global const uint* acc, global const float4* direct,
                       VCT_MIP_ARGS, global float4* level0Out) {
  int N = grid.resolution;
  size_t v = get_global_id(0);
  if (v >= (size_t)N * N * N) return;
  float4 own = direct[v];
  if (acc[v * GI_VOX_RECORD + GI_VOX_OPACITY] == 0u) {
    level0Out[v] = own;
    return;
  }
  VoxelSurface s = vox_resolve(grid, acc, v);
  float4 e = vct_diffuse_irradiance(vct_mips(grid, tp, iso, aniso, sh, shAniso), vct_to_voxels(grid, s.position),
                                    s.normal, tp.startOffset, tp.maxDistance, tp.stepFactor, tp.aoLambda,
                                    tp.footprintInFront, tp.levelSteps);
  level0Out[v] = own + (float4)(s.albedo * GI_INV_PI * e.xyz * s.alpha, 0.0f);
}

// cones[i] = (origin in voxels, tan of the half-angle), dirs[i] = (unit direction, max distance in
// voxels); out[i] = (radiance, opacity a), occlusion[i].
kernel void vct_trace_cones(GiVoxelGrid grid, VctTraceParams tp, VCT_MIP_ARGS, global const float4* cones, global const float4* dirs, int count, global float4* out,
                            global float* occlusion) {
  int i = get_global_id(0);
  if (i >= count) return;
  float4 c = cones[i], d = dirs[i];
  VoxelMips m = vct_mips(grid, tp, iso, aniso, sh, shAniso);
  ConeResult r = tp.specularLevelSteps ? vct_cone_levels(m, c.xyz, d.xyz, c.w, d.w, tp.stepFactor, tp.aoLambda)
                                       : vct_cone(m, c.xyz, d.xyz, c.w, d.w, tp.stepFactor, tp.aoLambda, INFINITY, 0.0f);
  out[i] = r.radiance;
  occlusion[i] = r.occlusion;
}

// points[i]: world position (w unused), normals[i]: unit normal; out[i] = (E, AO visibility).
kernel void vct_irradiance_points(GiVoxelGrid grid, VctTraceParams tp, VCT_MIP_ARGS, global const float4* points,
                                  global const float4* normals, int count, global float4* out) {
  int i = get_global_id(0);
  if (i >= count) return;
  out[i] = vct_diffuse_irradiance(vct_mips(grid, tp, iso, aniso, sh, shAniso), vct_to_voxels(grid, points[i].xyz),
                                  normals[i].xyz, tp.startOffset, tp.maxDistance, tp.stepFactor, tp.aoLambda,
                                  tp.footprintInFront, tp.levelSteps);
}
