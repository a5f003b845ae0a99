// Direct lighting of the camera G-buffer (ALGORITHMS.md §0): every punctual light (directional,
// point, spot, and the spot stand-ins of emissive surfaces) through Lambert + GGX, with 3×3 PCF
// shadow maps, plus the surface's own emission. Output: linear radiance towards the camera.
//
// One work-item shades GI_VW adjacent pixels of a row (structure of arrays in floatV: 16 lanes on
// CPU devices, 1 on GPUs; PERFORMANCE_FACTS.md). The formulas are those of common/brdf.h,
// common/lights.h and common/shadow.h written lane-wise; lights are uniform across lanes.
#include "common/brdf.h"
#include "common/lights_lanes.h"

kernel void direct_lighting(GiView camera, global const float4* gPosition, global const float4* gGeoNormal,
                            global const float4* gNormal, global const float4* gAlbedo,
                            global const float4* gSpecular, global const float4* gEmission,
                            global const GiLight* lights, int lightCount, global const GiView* shadowViews,
                            global const uint* shadowOffsets, global const float* shadowDepths,
                            global float4* outRadiance) {
  int px0 = get_global_id(0) * GI_VW, py = get_global_id(1);
  if (px0 >= camera.width || py >= camera.height) return;
  size_t i = (size_t)py * camera.width + px0;
  int valid = min(GI_VW, camera.width - px0);
  // Planes in SoA form. A partial group at the right border reads its last pixel repeatedly.
  float tmp[4 * GI_VW];
#define GI_LOAD_PLANE(plane, X, Y, Z, W)                                                   \
  if (valid == GI_VW) {                                                                    \
    GI_AOS4_LOAD((global const float*)(plane + i), X, Y, Z, W)                             \
  } else {                                                                                 \
    for (int l = 0; l < GI_VW; ++l) vstore4(plane[i + min(l, valid - 1)], l, tmp);         \
    GI_AOS4_LOAD(tmp, X, Y, Z, W)                                                          \
  }
  floatV pw, unused;
  float3V x, ng, n, alb, spec, em;
  floatV metallic, roughness;
  GI_LOAD_PLANE(gPosition, x.x, x.y, x.z, pw)
  GI_LOAD_PLANE(gGeoNormal, ng.x, ng.y, ng.z, unused)
  GI_LOAD_PLANE(gNormal, n.x, n.y, n.z, unused)
  GI_LOAD_PLANE(gAlbedo, alb.x, alb.y, alb.z, metallic)
  GI_LOAD_PLANE(gSpecular, spec.x, spec.y, spec.z, roughness)
  GI_LOAD_PLANE(gEmission, em.x, em.y, em.z, unused)
#undef GI_LOAD_PLANE
  intV surface = pw != 0.0f;
  float3V wo;
  if (camera.orthographic) {
    float3 w = -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz);
    wo = f3v((floatV)(w.x), (floatV)(w.y), (floatV)(w.z));
  } else {
    wo = f3v(camera.eye[0] - x.x, camera.eye[1] - x.y, camera.eye[2] - x.z);
    floatV inv = rsqrt(dotV(wo, wo));
    wo = f3v(wo.x * inv, wo.y * inv, wo.z * inv);
  }
  floatV nv = dotV(n, wo);
  floatV a = fmax(roughness * roughness, GI_MIN_GGX_ALPHA);
  floatV a2 = a * a;
  float3V L = em;
  for (int li = 0; li < lightCount; ++li) {
    global const GiLight* l = &lights[li];
    float3V wi;
    float3V E = light_incidentV(l, x, &wi);
    floatV cosTheta = dotV(n, wi);
    intV lit = surface & (cosTheta > 0.0f) & (dotV(ng, wi) > 0.0f) & (E.x + E.y + E.z > 0.0f);
    if (!GI_ANY(lit)) continue;
    floatV visibility = shadow_visibilityV(l, shadowViews, shadowOffsets, shadowDepths, x, ng);
    // brdf_eval(): Lambert + GGX (ggx_D, smith_visibility, fresnel_schlick).
    float3V h = f3v(wo.x + wi.x, wo.y + wi.y, wo.z + wi.z);
    floatV hinv = rsqrt(dotV(h, h));
    h = f3v(h.x * hinv, h.y * hinv, h.z * hinv);
    floatV nh = fmax(dotV(n, h), 0.0f);
    floatV dd = nh * nh * (a2 - 1.0f) + 1.0f;
    floatV D = a2 / (GI_PI * dd * dd);
    floatV nl = cosTheta;
    floatV gv = nl * sqrt(nv * nv * (1.0f - a2) + a2);
    floatV gl = nv * sqrt(nl * nl * (1.0f - a2) + a2);
    floatV V = 0.5f / fmax(gv + gl, 1e-12f);
    floatV m = clamp(1.0f - dotV(wi, h), 0.0f, 1.0f);
    floatV m2 = m * m, m5 = m2 * m2 * m;
    floatV DV = GI_SEL((floatV)(0.0f), D * V, nv > 0.0f);
    floatV k = cosTheta * visibility;
    floatV fr = (alb.x * GI_INV_PI + DV * (spec.x + (1.0f - spec.x) * m5)) * E.x * k;
    floatV fg = (alb.y * GI_INV_PI + DV * (spec.y + (1.0f - spec.y) * m5)) * E.y * k;
    floatV fb = (alb.z * GI_INV_PI + DV * (spec.z + (1.0f - spec.z) * m5)) * E.z * k;
    L.x += GI_SEL((floatV)(0.0f), fr, lit);
    L.y += GI_SEL((floatV)(0.0f), fg, lit);
    L.z += GI_SEL((floatV)(0.0f), fb, lit);
  }
  floatV zero = (floatV)(0.0f);
  floatV rx = GI_SEL(zero, L.x, surface), ry = GI_SEL(zero, L.y, surface), rz = GI_SEL(zero, L.z, surface);
  floatV rw = GI_SEL(zero, (floatV)(1.0f), surface);
  if (valid == GI_VW) {
    GI_AOS4_STORE((global float*)(outRadiance + i), rx, ry, rz, rw)
  } else {
    GI_AOS4_STORE(tmp, rx, ry, rz, rw)
    for (int l = 0; l < valid; ++l) outRadiance[i + l] = vload4(l, tmp);
  }
}

// Final radiance = direct + indirect (the technique's output), both linear.
kernel void compose(global const float4* direct, global const float4* indirect, global float4* out, uint count) {
  uint i = get_global_id(0);
  if (i < count) out[i] = (float4)(direct[i].xyz + indirect[i].xyz, 1.0f);
}
