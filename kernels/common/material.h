// Material evaluation shared by the rasterized passes and the path tracer (ALGORITHMS.md §0):
// glTF metallic-roughness. Diffuse albedo ρ = baseColor·(1 − metallic); specular F0 =
// mix(0.04, baseColor, metallic); GGX α = roughness². Textures are multiplied into the factors.
#pragma once
#include "common/math.h"
#include "common/shared_types.h"
#include "common/texture.h"

typedef struct {
  float3 diffuse;    // ρ, linear
  float3 f0;         // specular reflectance at normal incidence
  float roughness;   // perceptual roughness (GGX α = roughness²)
  float metallic;
  float3 emission;   // emitted radiance, W/(m²·sr) per channel
  float alpha;       // coverage (alpha mask)
} SurfaceSample;

inline float4 material_base_color(global const GiMaterial* m, global const GiTexture* textures,
                                  global const uchar4* texels, float2 uv, float lod) {
  float4 c = vload4(0, m->base_color);
  if (m->base_color_tex >= 0) c *= sample_texture(textures, texels, m->base_color_tex, uv, lod);
  return c;
}

// Alpha-mask test: true when the surface is cut away at this uv.
inline bool material_cut_out(global const GiMaterial* m, global const GiTexture* textures,
                             global const uchar4* texels, float2 uv, float lod) {
  if (m->alpha_mode != GI_ALPHA_MASK) return false;
  return material_base_color(m, textures, texels, uv, lod).w < m->alpha_cutoff;
}

inline SurfaceSample eval_material(global const GiMaterial* m, global const GiTexture* textures,
                                   global const uchar4* texels, float2 uv, float lod) {
  SurfaceSample s;
  float4 base = material_base_color(m, textures, texels, uv, lod);
  float metallic = m->metallic, roughness = m->roughness;
  if (m->metallic_roughness_tex >= 0) {
    float4 mr = sample_texture(textures, texels, m->metallic_roughness_tex, uv, lod);
    roughness *= mr.y;  // glTF: green = roughness, blue = metalness
    metallic *= mr.z;
  }
  s.metallic = clamp(metallic, 0.0f, 1.0f);
  s.roughness = clamp(roughness, 0.0f, 1.0f);
  s.diffuse = base.xyz * (1.0f - s.metallic);
  s.f0 = mix((float3)(0.04f), base.xyz, s.metallic);
  s.emission = vload3(0, m->emissive);
  if (m->emissive_tex >= 0) s.emission *= sample_texture(textures, texels, m->emissive_tex, uv, lod).xyz;
  s.alpha = base.w;
  return s;
}

// Shading normal with the material's normal map applied (glTF tangent space: tangent.w is the
// bitangent sign). Returns the interpolated normal when there is no map or no tangent.
inline float3 apply_normal_map(global const GiMaterial* m, global const GiTexture* textures,
                               global const uchar4* texels, float2 uv, float lod, float3 n, float4 tangent) {
  if (m->normal_tex < 0 || dot(tangent.xyz, tangent.xyz) < 1e-12f) return n;
  float3 t = safe_normalize(tangent.xyz - n * dot(n, tangent.xyz), (float3)(1.0f, 0.0f, 0.0f));
  float3 b = cross(n, t) * (tangent.w < 0.0f ? -1.0f : 1.0f);
  float3 tn = sample_texture(textures, texels, m->normal_tex, uv, lod).xyz * 2.0f - 1.0f;
  tn.xy *= m->normal_scale;
  return safe_normalize(t * tn.x + b * tn.y + n * tn.z, n);
}
