// Direct lighting of the camera G-buffer (ALGORITHMS.md §0): every punctual light (directional,
// point, spot, and the spot stand-ins of emissive surfaces) through Lambert + GGX, with 3×3 PCF
// shadow maps, plus the surface's own emission. Output: linear radiance towards the camera.
#include "common/brdf.h"
#include "common/lights.h"
#include "common/shadow.h"

kernel void direct_lighting(GiView camera, global const float4* gPosition, global const float4* gGeoNormal,
                            global const float4* gNormal, global const float4* gAlbedo,
                            global const float4* gSpecular, global const float4* gEmission,
                            global const GiLight* lights, int lightCount, global const GiView* shadowViews,
                            global const uint* shadowOffsets, global const float* shadowDepths,
                            global float4* outRadiance) {
  int px = get_global_id(0), py = get_global_id(1);
  if (px >= camera.width || py >= camera.height) return;
  size_t i = (size_t)py * camera.width + px;
  float4 pos = gPosition[i];
  if (pos.w == 0.0f) {
    outRadiance[i] = (float4)(0.0f);
    return;
  }
  float3 x = pos.xyz;
  float3 ng = gGeoNormal[i].xyz, n = gNormal[i].xyz;
  float4 alb = gAlbedo[i], spec = gSpecular[i];
  SurfaceSample s;
  s.diffuse = alb.xyz;
  s.metallic = alb.w;
  s.f0 = spec.xyz;
  s.roughness = spec.w;
  float3 wo = camera.orthographic ? -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz)
                                  : normalize(vload3(0, camera.eye) - x);
  float3 radiance = gEmission[i].xyz;
  for (int li = 0; li < lightCount; ++li) {
    global const GiLight* l = &lights[li];
    float3 wi;
    float dist;
    float3 E = light_incident(l, x, &wi, &dist);
    float cosTheta = dot(n, wi);
    if (cosTheta <= 0.0f || dot(ng, wi) <= 0.0f) continue;
    if (E.x + E.y + E.z <= 0.0f) continue;
    float visibility = shadow_visibility(l, shadowViews, shadowOffsets, shadowDepths, x, ng);
    radiance += brdf_eval(s, n, wo, wi) * E * (cosTheta * visibility);
  }
  outRadiance[i] = (float4)(radiance, 1.0f);
}

// Final radiance = direct + indirect (the technique's output), both linear.
kernel void compose(global const float4* direct, global const float4* indirect, global float4* out, uint count) {
  uint i = get_global_id(0);
  if (i < count) out[i] = (float4)(direct[i].xyz + indirect[i].xyz, 1.0f);
}
