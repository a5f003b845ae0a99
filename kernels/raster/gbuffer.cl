// Resolve passes: from a visibility buffer (raster.cl) to attribute planes.
//   gbuffer_resolve  camera G-buffer planes (ALGORITHMS.md §1), structure of arrays;
//   rsm_resolve      reflective shadow map: world position, normal, reflected flux per texel.
// Barycentrics come from intersecting the pixel's ray with the source triangle: exact and
// perspective-correct for any view, and independent of how the rasterizer clipped it.
#include "common/lights.h"
#include "common/material.h"
#include "raster/view.h"

typedef struct {
  float3 position;
  float3 geoNormal;     // face normal, turned towards the viewer
  float3 normal;        // interpolated vertex normal, same side as geoNormal
  float4 tangent;
  float2 uv;
  float lod;            // texture level of detail (ray-cone footprint of the pixel)
  float cosView;        // |cos| between the view ray and the face
  uint material;
} SurfaceHit;

inline SurfaceHit resolve_hit(const GiView* view, int px, int py, uint triangle, global const float4* positions,
                              global const float4* normals, global const float4* tangents, global const float2* uvs,
                              global const uint4* triangles, global const GiMaterial* materials,
                              global const GiTexture* textures) {
  SurfaceHit h;
  uint4 tri = triangles[triangle];
  float3 p0 = positions[tri.x].xyz, p1 = positions[tri.y].xyz, p2 = positions[tri.z].xyz;
  float3 o, d;
  view_pixel_ray(view, (float)px + 0.5f, (float)py + 0.5f, &o, &d);
  float3 tuv = ray_triangle_barycentrics(o, d, p0, p1, p2);
  float b1 = tuv.y, b2 = tuv.z, b0 = 1.0f - b1 - b2;
  h.position = o + d * tuv.x;
  float3 fn = cross(p1 - p0, p2 - p0);
  float worldArea2 = length(fn);
  h.geoNormal = worldArea2 > 0.0f ? fn / worldArea2 : (float3)(0.0f, 0.0f, 1.0f);
  h.normal = safe_normalize(b0 * normals[tri.x].xyz + b1 * normals[tri.y].xyz + b2 * normals[tri.z].xyz, h.geoNormal);
  if (dot(h.normal, h.geoNormal) < 0.0f) h.normal = -h.normal;  // mirrored instances, bad files
  if (dot(h.geoNormal, d) > 0.0f) {  // seen from the back (double-sided or shadow views)
    h.geoNormal = -h.geoNormal;
    h.normal = -h.normal;
  }
  h.tangent = b0 * tangents[tri.x] + b1 * tangents[tri.y] + b2 * tangents[tri.z];
  float2 uv0 = uvs[tri.x], uv1 = uvs[tri.y], uv2 = uvs[tri.z];
  h.uv = b0 * uv0 + b1 * uv1 + b2 * uv2;
  h.material = tri.w;
  h.cosView = fabs(dot(h.geoNormal, d));
  // Level of detail: texels per pixel footprint. The footprint side at view depth z is
  // z·texel_world_size (perspective) or texel_world_size (orthographic), stretched by 1/cos on
  // the surface. Textures of one material are assumed to share a size (the base colour's, else
  // the normal map's, decides).
  float2 du1 = uv1 - uv0, du2 = uv2 - uv0;
  float uvArea2 = fabs(du1.x * du2.y - du2.x * du1.y);
  float z = -mat4_mul(view->view, (float4)(h.position, 1.0f)).z;
  float footprint = view->orthographic ? view->texel_world_size : view->texel_world_size * z;
  float pixelArea2 = worldArea2 * fmax(h.cosView, 1e-3f) / fmax(footprint * footprint, 1e-30f);
  global const GiMaterial* m = &materials[tri.w];
  int lodTexture = m->base_color_tex >= 0 ? m->base_color_tex : m->normal_tex;
  h.lod = texture_lod(textures, lodTexture, uvArea2, pixelArea2);
  return h;
}

// Camera G-buffer, one work-item per pixel. Planes (structure of arrays, see src/raster/gbuffer.h):
// position (w = 1 surface, 0 background), geometric and shading normals, diffuse albedo with
// metallic in w, specular F0 with roughness in w, emission, instance id.
kernel void gbuffer_resolve(GiView view, global const uint* visTriangle, global const float4* positions,
                            global const float4* normals, global const float4* tangents, global const float2* uvs,
                            global const uint4* triangles, global const uint* triangleInstance,
                            global const GiMaterial* materials, global const GiTexture* textures,
                            global const uchar4* texels, global float4* outPosition, global float4* outGeoNormal,
                            global float4* outNormal, global float4* outAlbedo, global float4* outSpecular,
                            global float4* outEmission, global uint* outInstance) {
  int px = get_global_id(0), py = get_global_id(1);
  if (px >= view.width || py >= view.height) return;
  size_t i = (size_t)py * view.width + px;
  uint t = visTriangle[i];
  if (t == GI_INVALID_ID) {
    outPosition[i] = (float4)(0.0f);
    outGeoNormal[i] = (float4)(0.0f);
    outNormal[i] = (float4)(0.0f);
    outAlbedo[i] = (float4)(0.0f);
    outSpecular[i] = (float4)(0.0f);
    outEmission[i] = (float4)(0.0f);
    outInstance[i] = GI_INVALID_ID;
    return;
  }
  SurfaceHit h = resolve_hit(&view, px, py, t, positions, normals, tangents, uvs, triangles, materials, textures);
  global const GiMaterial* m = &materials[h.material];
  SurfaceSample s = eval_material(m, textures, texels, h.uv, h.lod);
  float3 n = apply_normal_map(m, textures, texels, h.uv, h.lod, h.normal, h.tangent);
  outPosition[i] = (float4)(h.position, 1.0f);
  outGeoNormal[i] = (float4)(h.geoNormal, 0.0f);
  outNormal[i] = (float4)(n, 0.0f);
  outAlbedo[i] = (float4)(s.diffuse, s.metallic);
  outSpecular[i] = (float4)(s.f0, s.roughness);
  outEmission[i] = (float4)(s.emission, 0.0f);
  outInstance[i] = triangleInstance[t];
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
  int px = get_global_id(0), py = get_global_id(1);
  if (px >= view.width || py >= view.height) return;
  size_t i = (size_t)py * view.width + px;
  uint t = visTriangle[i];
  if (t == GI_INVALID_ID) {
    outPosition[i] = (float4)(0.0f);
    outNormal[i] = (float4)(0.0f);
    outFlux[i] = (float4)(0.0f);
    return;
  }
  SurfaceHit h = resolve_hit(&view, px, py, t, positions, normals, tangents, uvs, triangles, materials, textures);
  SurfaceSample s = eval_material(&materials[h.material], textures, texels, h.uv, h.lod);
  global const GiLight* l = &lights[lightIndex];
  float3 flux;
  if (l->type == GI_LIGHT_DIRECTIONAL) {
    bool facing = dot(h.geoNormal, -vload3(0, l->direction)) > 0.0f;
    float a = view.texel_world_size * view.texel_world_size;
    flux = facing ? s.diffuse * vload3(0, l->intensity) * a : (float3)(0.0f);
  } else {
    float3 toSurface = h.position - vload3(0, l->position);
    float3 w = normalize(toSurface);
    // Solid angle of a texel of a perspective view: s²·cos³θ, s the texel size on the image
    // plane at distance 1 and θ the angle between w and the view axis.
    float3 axis = -(float3)(view.view[2], view.view[6], view.view[10]);
    float c = dot(w, axis);
    float omega = view.texel_world_size * view.texel_world_size * c * c * c;
    bool facing = dot(h.geoNormal, -w) > 0.0f;
    flux = facing ? s.diffuse * light_intensity_towards(l, w) * omega : (float3)(0.0f);
  }
  outPosition[i] = (float4)(h.position, 1.0f);
  outNormal[i] = (float4)(h.normal, 0.0f);
  outFlux[i] = (float4)(flux, 0.0f);
}
