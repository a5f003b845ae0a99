// The cone-traced passes of `vct` (ALGORITHMS.md §5; cone.h for the march and the cone sets).
// Build defines: GI_VCT_CONES (6 or 9), GI_DOWN (diffuse tracing every GI_DOWN-th pixel).
//
// vct_diffuse   per traced pixel: E from the diffuse cones at its position and shading normal.
//               GI_DOWN = 1 writes L = ρ/π · E (· voxel AO visibility if asked) per pixel;
//               GI_DOWN > 1 writes E for the geometry-aware upsampler (filters/discontinuity.cl).
// vct_specular  per pixel: adds F_Schlick(F0, n·ωo) · L_cone along the mirror direction, the cone's
//               half-angle from the GGX width, tan θ = α (α = roughness²). The BRDF's directional
//               albedo is approximated by F(n·ωo) alone (no masking term).
// vct_bounce    per occupied voxel: its injected direct level-0 radiance plus ρ/π · E_indirect, the
//               diffuse cones from the voxel's surface point along its normal through the current
//               mips. Run k − 1 times (re-mipping in between) for k bounces: each run adds one more
//               order of the light paths (L_k = L_direct + T·L_{k−1}).
// vct_trace_cones  arbitrary cones (tests, debugging).
#include "common/brdf.h"
#include "gi/vct/cone.h"

typedef struct {
  float startOffset;  // voxels along the normal before the first sample
  float maxDistance;  // voxels
  float stepFactor;
  float aoLambda;     // AO distance falloff, per voxel
  int anisotropic;
  int applyAo;        // multiply the diffuse result by the voxel AO visibility
  int footprintInFront;  // keep the sampled footprint in front of the surface (cone.h)
  int pad;
} VctTraceParams;

inline float3 vct_to_voxels(GiVoxelGrid g, float3 x) { return (x - vload3(0, g.origin)) / g.voxel_size; }

kernel void vct_diffuse(GiVoxelGrid grid, VctTraceParams tp, global const float4* iso, global const float4* aniso,
                        int width, int height, int lowWidth, int lowHeight, global const float4* gPosition,
                        global const float4* gNormal, global const float4* gAlbedo, global float4* out) {
  int u = get_global_id(0), v = get_global_id(1);
  if (u >= lowWidth || v >= lowHeight) return;
  size_t q = (size_t)min(v * GI_DOWN, height - 1) * width + min(u * GI_DOWN, width - 1);
  size_t o = (size_t)v * lowWidth + u;
  float4 pos = gPosition[q];
  if (pos.w == 0.0f) {
    out[o] = (float4)(0.0f);
    return;
  }
  float4 e = vct_diffuse_irradiance(iso, aniso, grid.resolution, grid.levels, vct_to_voxels(grid, pos.xyz),
                                    gNormal[q].xyz, tp.startOffset, tp.maxDistance, tp.stepFactor, tp.aoLambda,
                                    tp.anisotropic, tp.footprintInFront);
  float3 E = tp.applyAo ? e.xyz * e.w : e.xyz;
#if GI_DOWN == 1
  out[o] = (float4)(gAlbedo[q].xyz * GI_INV_PI * E, 0.0f);
#else
  out[o] = (float4)(E, 0.0f);
#endif
}

kernel void vct_specular(GiVoxelGrid grid, VctTraceParams tp, global const float4* iso, global const float4* aniso,
                         GiView camera, global const float4* gPosition, global const float4* gNormal,
                         global const float4* gSpecular, global float4* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= camera.width || y >= camera.height) return;
  size_t i = (size_t)y * camera.width + x;
  float4 pos = gPosition[i];
  if (pos.w == 0.0f) return;
  float3 n = gNormal[i].xyz;
  float3 wo = camera.orthographic
                  ? -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz)
                  : normalize(vload3(0, camera.eye) - pos.xyz);
  float nv = dot(n, wo);
  if (nv <= 0.0f) return;
  float4 spec = gSpecular[i];
  float3 r = 2.0f * nv * n - wo;
  float tanHalf = ggx_alpha(spec.w);
  ConeResult c = vct_cone(iso, aniso, grid.resolution, grid.levels, vct_to_voxels(grid, pos.xyz) + n * tp.startOffset,
                          r, tanHalf, tp.maxDistance, tp.stepFactor, tp.aoLambda, tp.anisotropic, tp.footprintInFront ? tp.startOffset : INFINITY, dot(r, n));
  out[i].xyz += fresnel_schlick(spec.xyz, nv) * c.radiance.xyz;
}

kernel void vct_bounce(GiVoxelGrid grid, VctTraceParams tp, global const uint* acc, global const float4* direct,
                       global const float4* iso, global const float4* aniso, global float4* level0Out) {
  int N = grid.resolution;
  size_t v = get_global_id(0);
  if (v >= (size_t)N * N * N) return;
  float4 own = direct[v];
  if (acc[GI_VOX_OPACITY * (size_t)N * N * N + v] == 0u) {
    level0Out[v] = own;
    return;
  }
  VoxelSurface s = vox_resolve(grid, acc, v);
  float4 e = vct_diffuse_irradiance(iso, aniso, N, grid.levels, vct_to_voxels(grid, s.position), s.normal,
                                    tp.startOffset, tp.maxDistance, tp.stepFactor, tp.aoLambda, tp.anisotropic,
                                    tp.footprintInFront);
  level0Out[v] = own + (float4)(s.albedo * GI_INV_PI * e.xyz * s.alpha, 0.0f);
}

// cones[i] = (origin in voxels, tan of the half-angle), dirs[i] = (unit direction, max distance in
// voxels); out[i] = (radiance, opacity a), occlusion[i].
kernel void vct_trace_cones(GiVoxelGrid grid, VctTraceParams tp, global const float4* iso, global const float4* aniso,
                            global const float4* cones, global const float4* dirs, int count, global float4* out,
                            global float* occlusion) {
  int i = get_global_id(0);
  if (i >= count) return;
  float4 c = cones[i], d = dirs[i];
  ConeResult r = vct_cone(iso, aniso, grid.resolution, grid.levels, c.xyz, d.xyz, c.w, d.w, tp.stepFactor,
                          tp.aoLambda, tp.anisotropic, INFINITY, 0.0f);
  out[i] = r.radiance;
  occlusion[i] = r.occlusion;
}
