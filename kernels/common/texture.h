// Sampling the texture atlas (see GiTexture in shared_types.h): RGBA8 texels, full mip chains,
// repeat wrapping (glTF's default; per-texture sampler modes are not honoured yet), bilinear
// filtering inside one mip level chosen by the caller's level of detail. sRGB-encoded colour
// textures are decoded to linear here, so every caller gets linear values.
#pragma once
#include "common/shared_types.h"
#include "common/srgb_table.h"

// Texel (x, y) of one level, 0 <= x < w, 0 <= y < h; decoded to linear.
inline float4 gi_texel(global const uchar4* texels, GiTexture t, uint levelOffset, int w, int x, int y) {
  uchar4 c = texels[levelOffset + (uint)(y * w + x)];
  if (t.srgb)
    return (float4)(GI_SRGB_TO_LINEAR[c.x], GI_SRGB_TO_LINEAR[c.y], GI_SRGB_TO_LINEAR[c.z], c.w * (1.0f / 255.0f));
  return convert_float4(c) * (1.0f / 255.0f);
}

// lod: log2 of texels per pixel footprint at level 0 (0 = full resolution).
inline float4 sample_texture(global const GiTexture* table, global const uchar4* texels, int index, float2 uv, float lod) {
  GiTexture t = table[index];
  int level = clamp((int)(lod + 0.5f), 0, t.levels - 1);
  uint offset = t.offset;
  int w = t.width, h = t.height;
  for (int l = 0; l < level; ++l) {
    offset += (uint)(w * h);
    w = max(1, w >> 1);
    h = max(1, h >> 1);
  }
  // Texel centres at half-integers. Wrap once with floor() (keeps far-away UVs precise and
  // negative ones correct); the right/bottom neighbour wraps to 0 at the border.
  float fx = uv.x * (float)w - 0.5f, fy = uv.y * (float)h - 0.5f;
  if (!isfinite(fx) || !isfinite(fy)) return gi_texel(texels, t, offset, w, 0, 0);
  fx -= floor(fx / (float)w) * (float)w;
  fy -= floor(fy / (float)h) * (float)h;
  float x0f = floor(fx), y0f = floor(fy);
  float ax = fx - x0f, ay = fy - y0f;
  int x0 = min((int)x0f, w - 1), y0 = min((int)y0f, h - 1);
  int x1 = x0 + 1 == w ? 0 : x0 + 1, y1 = y0 + 1 == h ? 0 : y0 + 1;
  float4 c00 = gi_texel(texels, t, offset, w, x0, y0);
  float4 c10 = gi_texel(texels, t, offset, w, x1, y0);
  float4 c01 = gi_texel(texels, t, offset, w, x0, y1);
  float4 c11 = gi_texel(texels, t, offset, w, x1, y1);
  return mix(mix(c00, c10, ax), mix(c01, c11, ax), ay);
}

// Level of detail for a triangle from its UV-space and screen-space (pixel) areas: the
// per-triangle estimate used by ray-cone texture filtering, constant over the triangle.
inline float texture_lod(global const GiTexture* table, int index, float uvArea, float pixelArea) {
  if (index < 0 || pixelArea <= 0.0f) return 0.0f;
  GiTexture t = table[index];
  float texelArea = uvArea * (float)t.width * (float)t.height;
  return 0.5f * log2(fmax(texelArea / pixelArea, 1e-8f));
}
