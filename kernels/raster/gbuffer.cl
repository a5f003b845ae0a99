// Resolve passes: from a visibility buffer (raster.cl) to attribute planes.
//   gbuffer_resolve  camera G-buffer planes (ALGORITHMS.md §1), structure of arrays;
//   rsm_resolve      reflective shadow map: world position, normal, reflected flux per texel.
// Barycentrics come from intersecting the pixel's ray with the source triangle: exact and
// perspective-correct for any view, and independent of how the rasterizer clipped it.
#include "common/lights.h"
#include "common/material.h"
#include "raster/view.h"
#include "common/vector_width.h"
#include "common/texture_lanes.h"
#include "common/lights_lanes.h"

// Both kernels handle GI_VW adjacent pixels of a row per work-item (16 lanes on CPU devices, 1 on
// GPUs). Per pixel: ray through the pixel centre (view_pixel_ray), ray-plane barycentrics with the
// source triangle (ray_triangle_barycentrics), interpolated attributes, ray-cone texture level of
// detail (texture_lod), then sample_texture(), eval_material() and apply_normal_map() of common/,
// all written over floatV lanes with gathers for per-triangle, per-material and per-texel data.

typedef struct {
  float3V position, geoNormal, normal, shading, diffuse, f0, emission;
  floatV metallic, roughness;
  uintV triangle;  // t with background lanes replaced by 0
} SurfaceV;

// Surface attributes + eval_material() (+ apply_normal_map() when normalMap) for GI_VW pixels of row
// py starting at px0, lane-wise. Lanes where surface is false are computed on triangle 0 and must
// be discarded by the caller.
inline SurfaceV resolve_surfaceV(const GiView* viewp, int px0, int py, uintV t, intV surface, bool normalMap,
                                 global const float4* positions, global const float4* normals,
                                 global const float4* tangents, global const float2* uvs,
                                 global const uint4* triangles, global const GiMaterial* materials,
                                 global const GiTexture* textures, global const uchar4* texels) {
  GiView view = *viewp;
  floatV zero = (floatV)(0.0f);
  SurfaceV out;
  // Background lanes take triangle 0 for the gathers (their results are discarded).
  uintV tg = GI_SEL((uintV)(0), t, surface);
  // Records of 4 words (triangles, positions, normals, tangents, materials) are fetched with one
  // 128-bit load per lane (GI_GATHER_AOS4), uvs with one 64-bit load.
  global const uint* triU = (global const uint*)triangles;
  uintV i0, i1, i2, mat;
  GI_GATHER_AOS4(uint, triU, tg, i0, i1, i2, mat)
#define GI_FETCH3(out, buf, idx)                              \
  {                                                           \
    floatV w_;                                                \
    GI_GATHER_AOS4(float, buf, idx, out.x, out.y, out.z, w_) \
  }
  global const float* posF = (global const float*)positions;
  global const float* nrmF = (global const float*)normals;
  global const float* tanF = (global const float*)tangents;
  global const float* uvF = (global const float*)uvs;
  float3V p0, p1, p2;
  GI_FETCH3(p0, posF, i0)
  GI_FETCH3(p1, posF, i1)
  GI_FETCH3(p2, posF, i2)

  // view_pixel_ray() per lane.
  floatV pxf = convert_floatV(px0 + GI_LANES) + 0.5f;
  floatV nx = pxf / (float)view.width * 2.0f - 1.0f;
  float ny = 1.0f - ((float)py + 0.5f) / (float)view.height * 2.0f;
  const float* M = view.inv_view_proj;
  // mat4_mul(M, (nx, ny, ±1, 1)) = col0·nx + col1·ny + col2·(±1) + col3.
#define GI_INV(r, zs) (M[r] * nx + M[4 + r] * ny + M[8 + r] * (zs) + M[12 + r])
  floatV anw = GI_INV(3, -1.0f), afw = GI_INV(3, 1.0f);
  float3V a = f3v(GI_INV(0, -1.0f) / anw, GI_INV(1, -1.0f) / anw, GI_INV(2, -1.0f) / anw);
  float3V b = f3v(GI_INV(0, 1.0f) / afw, GI_INV(1, 1.0f) / afw, GI_INV(2, 1.0f) / afw);
#undef GI_INV
  float3V o = view.orthographic ? a : f3v((floatV)(view.eye[0]), (floatV)(view.eye[1]), (floatV)(view.eye[2]));
  float3V d = subV(b, a);
  d = scaleV(d, rsqrt(dotV(d, d)));

  // ray_triangle_barycentrics() per lane.
  float3V e1 = subV(p1, p0), e2 = subV(p2, p0);
  float3V pv = crossV(d, e2);
  floatV det = dotV(e1, pv);
  floatV inv = GI_SEL((floatV)(0.0f), 1.0f / det, fabs(det) > 1e-30f);
  float3V tv = subV(o, p0);
  floatV b1 = dotV(tv, pv) * inv;
  float3V qv = crossV(tv, e1);
  floatV b2 = dotV(d, qv) * inv;
  floatV th = dotV(e2, qv) * inv;
  floatV b0 = 1.0f - b1 - b2;
  float3V position = addV(o, scaleV(d, th));
  float3V fn = crossV(e1, e2);
  floatV worldArea2 = sqrt(dotV(fn, fn));
  float3V geoN = selV(f3v(zero, zero, (floatV)(1.0f)), f3v(fn.x / worldArea2, fn.y / worldArea2, fn.z / worldArea2), worldArea2 > 0.0f);
  float3V n0, n1, n2;
  GI_FETCH3(n0, nrmF, i0)
  GI_FETCH3(n1, nrmF, i1)
  GI_FETCH3(n2, nrmF, i2)
  float3V nrm = safe_normalizeV(addV(addV(scaleV(n0, b0), scaleV(n1, b1)), scaleV(n2, b2)), geoN);
  nrm = selV(nrm, negV(nrm), dotV(nrm, geoN) < 0.0f);
  intV back = dotV(geoN, d) > 0.0f;
  geoN = selV(geoN, negV(geoN), back);
  nrm = selV(nrm, negV(nrm), back);
  float4V tg0, tg1, tg2;
  GI_GATHER_AOS4(float, tanF, i0, tg0.x, tg0.y, tg0.z, tg0.w)
  GI_GATHER_AOS4(float, tanF, i1, tg1.x, tg1.y, tg1.z, tg1.w)
  GI_GATHER_AOS4(float, tanF, i2, tg2.x, tg2.y, tg2.z, tg2.w)
  float4V tng;
  tng.x = b0 * tg0.x + b1 * tg1.x + b2 * tg2.x;
  tng.y = b0 * tg0.y + b1 * tg1.y + b2 * tg2.y;
  tng.z = b0 * tg0.z + b1 * tg1.z + b2 * tg2.z;
  tng.w = b0 * tg0.w + b1 * tg1.w + b2 * tg2.w;
  floatV u0, v0, u1, v1, u2, v2;
  GI_GATHER_AOS2(float, uvF, i0, u0, v0)
  GI_GATHER_AOS2(float, uvF, i1, u1, v1)
  GI_GATHER_AOS2(float, uvF, i2, u2, v2)
  floatV u = b0 * u0 + b1 * u1 + b2 * u2, v = b0 * v0 + b1 * v1 + b2 * v2;
  floatV cosView = fabs(dotV(geoN, d));
  // Level of detail: texels per pixel footprint. The footprint side at view depth z is
  // z·texel_world_size (perspective) or texel_world_size (orthographic), stretched by 1/cos on
  // the surface. Textures of one material are assumed to share a size (the base colour's, else
  // the normal map's, decides).
  floatV du1x = u1 - u0, du1y = v1 - v0, du2x = u2 - u0, du2y = v2 - v0;
  floatV uvArea2 = fabs(du1x * du2y - du2x * du1y);
  const float* Vm = view.view;
  floatV z = -(Vm[2] * position.x + Vm[6] * position.y + Vm[10] * position.z + Vm[14]);
  floatV footprint = view.orthographic ? (floatV)(view.texel_world_size) : view.texel_world_size * z;
  floatV pixelArea2 = worldArea2 * fmax(cosView, 1e-3f) / fmax(footprint * footprint, 1e-30f);
  // Material fields: GiMaterial is 20 words = five 4-word records; the first four are used:
  // base colour | emissive, metallic | roughness, alpha cutoff, normal scale, alpha mode | textures.
  global const float* mf = (global const float*)materials;
  global const int* mi = (global const int*)materials;
  uintV m5 = mat * 5u;
  float4V base;
  float3V emission;
  floatV metallic, roughness, normalScale, unusedCutoff, unusedMode;
  intV baseTex, mrTex, normalTex, emTex;
  GI_GATHER_AOS4(float, mf, m5, base.x, base.y, base.z, base.w)
  GI_GATHER_AOS4(float, mf, m5 + 1u, emission.x, emission.y, emission.z, metallic)
  GI_GATHER_AOS4(float, mf, m5 + 2u, roughness, unusedCutoff, normalScale, unusedMode)
  GI_GATHER_AOS4(int, mi, m5 + 3u, baseTex, mrTex, normalTex, emTex)
  intV lodTex = GI_SEL(normalTex, baseTex, baseTex >= 0);
  // texture_lod() per lane.
  floatV lod;
  {
    global const int* tab = (global const int*)textures;
    intV hasLod = (lodTex >= 0) & (pixelArea2 > 0.0f) & surface;
    floatV tw = (floatV)(1.0f), tht = (floatV)(1.0f);
    if (GI_ANY(hasLod)) {
      intV unusedOffset, w, h, unusedLevels;
      GI_GATHER_AOS4(int, tab, max(lodTex, 0) * 2, unusedOffset, w, h, unusedLevels)  // GiTexture: 2 records
      tw = convert_floatV(w);
      tht = convert_floatV(h);
    }
    floatV texelArea = uvArea2 * tw * tht;
    lod = GI_SEL((floatV)(0.0f), 0.5f * log2(fmax(texelArea / pixelArea2, 1e-8f)), hasLod);
  }
  // eval_material() per lane.
  intV hasBase = (baseTex >= 0) & surface;
  if (GI_ANY(hasBase)) {
    float4V c = sample_textureV(textures, texels, GI_SEL((intV)(-1), baseTex, hasBase), u, v, lod);
    base.x *= GI_SEL((floatV)(1.0f), c.x, hasBase);
    base.y *= GI_SEL((floatV)(1.0f), c.y, hasBase);
    base.z *= GI_SEL((floatV)(1.0f), c.z, hasBase);
    base.w *= GI_SEL((floatV)(1.0f), c.w, hasBase);
  }
  intV hasMr = (mrTex >= 0) & surface;
  if (GI_ANY(hasMr)) {
    float4V mr = sample_textureV(textures, texels, mrTex, u, v, lod);
    roughness = GI_SEL(roughness, roughness * mr.y, hasMr);
    metallic = GI_SEL(metallic, metallic * mr.z, hasMr);
  }
  metallic = clamp(metallic, 0.0f, 1.0f);
  roughness = clamp(roughness, 0.0f, 1.0f);
  float3V diffuse = f3v(base.x * (1.0f - metallic), base.y * (1.0f - metallic), base.z * (1.0f - metallic));
  float3V f0 = f3v(mix((floatV)(0.04f), base.x, metallic), mix((floatV)(0.04f), base.y, metallic),
                   mix((floatV)(0.04f), base.z, metallic));
  intV hasEm = (emTex >= 0) & surface;
  if (GI_ANY(hasEm)) {
    float4V e = sample_textureV(textures, texels, emTex, u, v, lod);
    emission = selV(emission, f3v(emission.x * e.x, emission.y * e.y, emission.z * e.z), hasEm);
  }
  // apply_normal_map() per lane.
  float3V shading = nrm;
  float3V t3 = f3v(tng.x, tng.y, tng.z);
  intV hasNormalMap = (intV)(normalMap ? -1 : 0) & (normalTex >= 0) & (dotV(t3, t3) >= 1e-12f) & surface;
  if (GI_ANY(hasNormalMap)) {
    float3V tt = safe_normalizeV(subV(t3, scaleV(nrm, dotV(nrm, t3))), f3v((floatV)(1.0f), zero, zero));
    float3V bt = scaleV(crossV(nrm, tt), GI_SEL((floatV)(1.0f), (floatV)(-1.0f), tng.w < 0.0f));
    float4V tn4 = sample_textureV(textures, texels, normalTex, u, v, lod);
    floatV tnx = (tn4.x * 2.0f - 1.0f) * normalScale, tny = (tn4.y * 2.0f - 1.0f) * normalScale;
    floatV tnz = tn4.z * 2.0f - 1.0f;
    float3V mapped = safe_normalizeV(addV(addV(scaleV(tt, tnx), scaleV(bt, tny)), scaleV(nrm, tnz)), nrm);
    shading = selV(nrm, mapped, hasNormalMap);
  }
#undef GI_FETCH3
  out.position = position;
  out.geoNormal = geoN;
  out.normal = nrm;
  out.shading = shading;
  out.diffuse = diffuse;
  out.f0 = f0;
  out.emission = emission;
  out.metallic = metallic;
  out.roughness = roughness;
  out.triangle = tg;
  return out;
}

// The visible-triangle ids of the `valid` pixels (or texels) of a row from i, the lanes past the
// row's end set to GI_INVALID_ID (no surface).
inline uintV gbuffer_load_row(global const uint* visTriangle, size_t i, int valid) {
  if (valid == GI_VW) return vloadV(0, visTriangle + i);
  uint ids[GI_VW];
  for (int l = 0; l < GI_VW; ++l) ids[l] = l < valid ? visTriangle[i + l] : GI_INVALID_ID;
  return vloadV(0, ids);
}

// One float4 plane of the `valid` pixels of a row from i, from four lane vectors (X, Y, Z, W).
inline void gbuffer_store_row(global float4* plane, size_t i, int valid, floatV X, floatV Y, floatV Z, floatV W) {
  if (valid == GI_VW) {
    GI_AOS4_STORE((global float*)(plane + i), X, Y, Z, W)
  } else {
    float rows[4 * GI_VW];
    GI_AOS4_STORE(rows, X, Y, Z, W)
    for (int l = 0; l < valid; ++l) plane[i + l] = vload4(l, rows);
  }
}

// Camera G-buffer, GI_VW pixels of a row per work-item. Planes (structure of arrays, see
// src/raster/gbuffer.h): position (w = 1 surface, 0 background), geometric and shading normals,
// diffuse albedo with metallic in w, specular F0 with roughness in w, emission, instance id.
kernel void gbuffer_resolve(GiView view, global const uint* visTriangle, global const float4* positions,
                            global const float4* normals, global const float4* tangents, global const float2* uvs,
                            global const uint4* triangles, global const uint* triangleInstance,
                            global const GiMaterial* materials, global const GiTexture* textures,
                            global const uchar4* texels, global float4* outPosition, global float4* outGeoNormal,
                            global float4* outNormal, global float4* outAlbedo, global float4* outSpecular,
                            global float4* outEmission, global uint* outInstance) {
  int px0 = get_global_id(0) * GI_VW, py = get_global_id(1);
  if (px0 >= view.width || py >= view.height) return;
  size_t i = (size_t)py * view.width + px0;
  int valid = min(GI_VW, view.width - px0);
  uintV t = gbuffer_load_row(visTriangle, i, valid);
  intV surface = t != (uintV)(GI_INVALID_ID);
  floatV zero = (floatV)(0.0f);
  if (!GI_ANY(surface)) {
    gbuffer_store_row(outPosition, i, valid, zero, zero, zero, zero);
    gbuffer_store_row(outGeoNormal, i, valid, zero, zero, zero, zero);
    gbuffer_store_row(outNormal, i, valid, zero, zero, zero, zero);
    gbuffer_store_row(outAlbedo, i, valid, zero, zero, zero, zero);
    gbuffer_store_row(outSpecular, i, valid, zero, zero, zero, zero);
    gbuffer_store_row(outEmission, i, valid, zero, zero, zero, zero);
    for (int l = 0; l < valid; ++l) outInstance[i + l] = GI_INVALID_ID;
    return;
  }
  SurfaceV sv = resolve_surfaceV(&view, px0, py, t, surface, true, positions, normals, tangents, uvs, triangles,
                                 materials, textures, texels);
  uintV tg = sv.triangle;
  float3V position = sv.position, geoN = sv.geoNormal, shading = sv.shading, diffuse = sv.diffuse, f0 = sv.f0,
          emission = sv.emission;
  floatV metallic = sv.metallic, roughness = sv.roughness;
  floatV one = (floatV)(1.0f);
#define GI_S(x) GI_SEL(zero, x, surface)
  gbuffer_store_row(outPosition, i, valid, GI_S(position.x), GI_S(position.y), GI_S(position.z), GI_S(one));
  gbuffer_store_row(outGeoNormal, i, valid, GI_S(geoN.x), GI_S(geoN.y), GI_S(geoN.z), zero);
  gbuffer_store_row(outNormal, i, valid, GI_S(shading.x), GI_S(shading.y), GI_S(shading.z), zero);
  gbuffer_store_row(outAlbedo, i, valid, GI_S(diffuse.x), GI_S(diffuse.y), GI_S(diffuse.z), GI_S(metallic));
  gbuffer_store_row(outSpecular, i, valid, GI_S(f0.x), GI_S(f0.y), GI_S(f0.z), GI_S(roughness));
  gbuffer_store_row(outEmission, i, valid, GI_S(emission.x), GI_S(emission.y), GI_S(emission.z), zero);
#undef GI_S
  uintV inst = GI_SEL((uintV)(GI_INVALID_ID), GI_GATHER(uintV, triangleInstance, tg), surface);
  GI_STORE_LANES(uint, inst, outInstance, i, valid)
}

// Reflective shadow map (ALGORITHMS.md §1), one work-item per texel of the light's view:
//   directional light, irradiance E, texel area a:  Φ = ρ·E·a
//   spot/point light, intensity I(ω), texel solid angle Ω:  Φ = ρ·I(ω)·Ω
// (the view's projected area or solid angle already contains the receiver cosine). Surfaces
// facing away from the light reflect nothing. The stored normal is the interpolated vertex normal
// (normal maps are not applied at RSM resolution).
kernel void rsm_resolve(GiView view, global const GiLight* lights, int lightIndex, global const uint* visTriangle,
                        global const float4* positions, global const float4* normals, global const float4* tangents,
                        global const float2* uvs, global const uint4* triangles, global const GiMaterial* materials,
                        global const GiTexture* textures, global const uchar4* texels, global float4* outPosition,
                        global float4* outNormal, global float4* outFlux) {
  // GI_VW texels of a row per work-item (lane-wise, as gbuffer_resolve).
  int px0 = get_global_id(0) * GI_VW, py = get_global_id(1);
  if (px0 >= view.width || py >= view.height) return;
  size_t i = (size_t)py * view.width + px0;
  int valid = min(GI_VW, view.width - px0);
  uintV t = gbuffer_load_row(visTriangle, i, valid);
  intV surface = t != (uintV)(GI_INVALID_ID);
  floatV zero = (floatV)(0.0f), one = (floatV)(1.0f);
  if (!GI_ANY(surface)) {
    gbuffer_store_row(outPosition, i, valid, zero, zero, zero, zero);
    gbuffer_store_row(outNormal, i, valid, zero, zero, zero, zero);
    gbuffer_store_row(outFlux, i, valid, zero, zero, zero, zero);
    return;
  }
  SurfaceV sv = resolve_surfaceV(&view, px0, py, t, surface, false, positions, normals, tangents, uvs, triangles,
                                 materials, textures, texels);
  global const GiLight* l = &lights[lightIndex];
  float3V I = f3v((floatV)(l->intensity[0]), (floatV)(l->intensity[1]), (floatV)(l->intensity[2]));
  float3V flux;
  if (l->type == GI_LIGHT_DIRECTIONAL) {
    floatV facing = dotV(sv.geoNormal, f3v((floatV)(-l->direction[0]), (floatV)(-l->direction[1]),
                                           (floatV)(-l->direction[2])));
    float a = view.texel_world_size * view.texel_world_size;
    intV f = facing > 0.0f;
    flux = selV(f3v(zero, zero, zero), scaleV(f3v(sv.diffuse.x * I.x, sv.diffuse.y * I.y, sv.diffuse.z * I.z), a), f);
  } else {
    float3V toSurface = f3v(sv.position.x - l->position[0], sv.position.y - l->position[1], sv.position.z - l->position[2]);
    float3V w = scaleV(toSurface, rsqrt(dotV(toSurface, toSurface)));
    // Solid angle of a texel of a perspective view: s²·cos³θ (see the scalar form's comment).
    float ax = -view.view[2], ay = -view.view[6], az = -view.view[10];
    floatV c = w.x * ax + w.y * ay + w.z * az;
    floatV omega = view.texel_world_size * view.texel_world_size * c * c * c;
    intV f = dotV(sv.geoNormal, negV(w)) > 0.0f;
    floatV s = light_spot_factorV(l, w.x * l->direction[0] + w.y * l->direction[1] + w.z * l->direction[2]);
    float3V Iw = l->type == GI_LIGHT_SPOT ? scaleV(I, s) : I;
    flux = selV(f3v(zero, zero, zero), scaleV(f3v(sv.diffuse.x * Iw.x, sv.diffuse.y * Iw.y, sv.diffuse.z * Iw.z), omega), f);
  }
#define GI_S(x) GI_SEL(zero, x, surface)
  gbuffer_store_row(outPosition, i, valid, GI_S(sv.position.x), GI_S(sv.position.y), GI_S(sv.position.z), GI_S(one));
  gbuffer_store_row(outNormal, i, valid, GI_S(sv.normal.x), GI_S(sv.normal.y), GI_S(sv.normal.z), zero);
  gbuffer_store_row(outFlux, i, valid, GI_S(flux.x), GI_S(flux.y), GI_S(flux.z), zero);
#undef GI_S
}
