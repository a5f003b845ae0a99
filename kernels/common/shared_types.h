// Structures shared by the host (C++) and the kernels (OpenCL C 1.2).
// Only 4-byte scalars and arrays of them, so both compilers give the same layout without
// packing pragmas. Units follow ALGORITHMS.md §0 (linear Rec.709, W/sr, W/m², radiance).
#pragma once

#ifdef __OPENCL_VERSION__
#define GI_U32 uint
#define GI_I32 int
#else
#include <cstdint>
#define GI_U32 uint32_t
#define GI_I32 int32_t
namespace gi {
#endif

#define GI_NO_TEXTURE (-1)
#define GI_INVALID_ID 0xFFFFFFFFu

#define GI_ALPHA_OPAQUE 0
#define GI_ALPHA_MASK 1
#define GI_ALPHA_BLEND 2  // rendered as opaque (no order-independent transparency yet)

typedef struct {
  float base_color[4];  // linear RGBA factor (multiplies the texture)
  float emissive[3];    // emitted radiance factor, KHR_materials_emissive_strength applied
  float metallic;
  float roughness;      // perceptual roughness; GGX alpha = roughness²
  float alpha_cutoff;   // alpha-mask threshold (used when alpha_mode == GI_ALPHA_MASK)
  float normal_scale;
  GI_I32 alpha_mode;
  GI_I32 base_color_tex;  // index into the texture table, or GI_NO_TEXTURE
  GI_I32 metallic_roughness_tex;
  GI_I32 normal_tex;
  GI_I32 emissive_tex;
  GI_I32 double_sided;
  GI_I32 pad[3];
} GiMaterial;  // 80 bytes

// One texture in the texture atlas (one buffer of RGBA8 texels). Mip level l of size
// max(1, width >> l) × max(1, height >> l) starts at `offset` plus the sizes of levels 0..l-1.
// Colour textures (base colour, emissive) are stored sRGB-encoded and decoded on sampling;
// data textures (normal, metallic-roughness) linearly.
typedef struct {
  GI_U32 offset;  // first texel of level 0
  GI_I32 width;
  GI_I32 height;
  GI_I32 levels;
  GI_I32 srgb;    // 1: texels are sRGB-encoded colour
  GI_I32 pad[3];
} GiTexture;  // 32 bytes

#define GI_LIGHT_DIRECTIONAL 0
#define GI_LIGHT_POINT 1
#define GI_LIGHT_SPOT 2

#define GI_SPOT_FALLOFF_GLTF 0    // KHR_lights_punctual smooth step between inner and outer cone
#define GI_SPOT_FALLOFF_COSINE 1  // I(θ) = I0·cos θ over the hemisphere (emissive-area stand-in)
// Spot lights with a cone wider than this (cos of the outer half angle below it) get cube shadow
// maps (6 faces) like point lights; narrower ones one perspective map.
#define GI_SPOT_CUBE_COS 0.5f

typedef struct {
  float position[3];  // world (point, spot)
  GI_I32 type;        // GI_LIGHT_*
  float direction[3]; // unit vector the light shines along (directional, spot)
  float range;        // 0 = infinite
  float intensity[3]; // W/sr (point, spot: I0 on the axis) or W/m² irradiance (directional), per channel
  float cos_inner;    // spot cones (cosines of the half angles)
  float cos_outer;
  GI_I32 falloff;     // GI_SPOT_FALLOFF_*
  GI_I32 shadow_map;  // first shadow view of this light (6 consecutive for point lights), -1 = none
  GI_I32 pad;
} GiLight;  // 64 bytes

// A rasterized view: camera, shadow-map face or RSM. Matrices column-major (glm layout).
typedef struct {
  float view_proj[16];      // world -> clip
  float inv_view_proj[16];  // clip -> world
  float view[16];           // world -> view (right-handed, camera looks down -z)
  float eye[3];             // camera position (perspective) or a point on the near plane (ortho)
  GI_I32 orthographic;
  GI_I32 width;
  GI_I32 height;
  GI_I32 cull_backfaces;    // 1: cull back faces of single-sided materials
  float texel_world_size;   // ortho: world size of one texel; perspective: 2·tan(fov/2)/height at distance 1
  float znear;              // view-space distances of the clip planes (positive)
  float zfar;
  GI_I32 pad[2];
} GiView;  // 240 bytes

#ifndef __OPENCL_VERSION__
}  // namespace gi
static_assert(sizeof(gi::GiMaterial) == 80, "GiMaterial layout");
static_assert(sizeof(gi::GiTexture) == 32, "GiTexture layout");
static_assert(sizeof(gi::GiLight) == 64, "GiLight layout");
static_assert(sizeof(gi::GiView) == 240, "GiView layout");
#endif
