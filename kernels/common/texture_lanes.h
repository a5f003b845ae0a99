// sample_texture() of common/texture.h over GI_VW lanes, each lane with its own texture, level of
// detail and uv (texel data by gathers): the G-buffer pass (raster/gbuffer.cl) and the voxelization
// (gi/vct/voxelize.cl) use it. The level choice (texture_levelV) is separate from the bilinear
// lookup (sample_texture_levelV) so that a caller whose level is constant over many lookups (the
// voxelization: one level per triangle column) chooses it once.
#pragma once
#include "common/texture.h"
#include "common/vector_width.h"

// One mip level of a texture per lane: sample_texture()'s level choice. Every lane steps up to the
// largest level among the lanes.
typedef struct {
  uintV offset;
  intV w, h, srgb;
} GiTexLevelV;

inline GiTexLevelV texture_levelV(global const GiTexture* table, intV index, floatV lod) {
  global const int* tab = (global const int*)table;
  intV ti = max(index, (intV)(0)) * 8;  // GiTexture: 8 ints (offset, width, height, levels, srgb, pad)
  GiTexLevelV r;
  intV offsetBits, levels;
  GI_GATHER_SPAN4(int, tab, ti, offsetBits, r.w, r.h, levels)
  r.offset = as_uintV(offsetBits);
  r.srgb = GI_GATHER(intV, tab, ti + 4);
  intV level = clamp(convert_intV(lod + 0.5f), 0, levels - 1);
  int top = lane_max_int(level);
  for (int l = 0; l < top; ++l) {
    intV m = (intV)(l) < level;
    r.offset += as_uintV(GI_SEL((intV)(0), r.w * r.h, m));
    r.w = GI_SEL(r.w, max(1, r.w >> 1), m);
    r.h = GI_SEL(r.h, max(1, r.h >> 1), m);
  }
  return r;
}

// sample_texture()'s bilinear lookup at the lanes' chosen levels.
inline float4V sample_texture_levelV(global const uchar4* texels, GiTexLevelV t, floatV u, floatV v) {
  floatV wf = convert_floatV(t.w), hf = convert_floatV(t.h);
  floatV fx = u * wf - 0.5f, fy = v * hf - 0.5f;
  intV bad = !isfinite(fx) | !isfinite(fy);  // sample_texture: texel (0, 0)
  fx = GI_SEL(fx, (floatV)(0.0f), bad);
  fy = GI_SEL(fy, (floatV)(0.0f), bad);
  fx -= floor(fx / wf) * wf;
  fy -= floor(fy / hf) * hf;
  floatV x0f = floor(fx), y0f = floor(fy);
  floatV ax = GI_SEL(fx - x0f, (floatV)(0.0f), bad), ay = GI_SEL(fy - y0f, (floatV)(0.0f), bad);
  intV x0 = min(convert_intV(x0f), t.w - 1), y0 = min(convert_intV(y0f), t.h - 1);
  intV x1 = GI_SEL(x0 + 1, (intV)(0), x0 + 1 == t.w), y1 = GI_SEL(y0 + 1, (intV)(0), y0 + 1 == t.h);
  global const uint* px = (global const uint*)texels;
  uintV c00 = GI_GATHER(uintV, px, t.offset + as_uintV(y0 * t.w + x0));
  uintV c10 = GI_GATHER(uintV, px, t.offset + as_uintV(y0 * t.w + x1));
  uintV c01 = GI_GATHER(uintV, px, t.offset + as_uintV(y1 * t.w + x0));
  uintV c11 = GI_GATHER(uintV, px, t.offset + as_uintV(y1 * t.w + x1));
  intV isSrgb = t.srgb != 0;
  bool anySrgb = GI_ANY(isSrgb);
  float4V r;
#define GI_CH(c, sh) convert_intV(((c) >> (sh)) & 0xFFu)
#define GI_DECODE(c, sh) \
  (anySrgb ? GI_SEL(convert_floatV(GI_CH(c, sh)) * (1.0f / 255.0f), GI_GATHER(floatV, GI_SRGB_TO_LINEAR, GI_CH(c, sh)), isSrgb) \
           : convert_floatV(GI_CH(c, sh)) * (1.0f / 255.0f))
#define GI_LINEAR(c, sh) (convert_floatV(GI_CH(c, sh)) * (1.0f / 255.0f))
#define GI_BILERP(out, sh, DEC) out = mix(mix(DEC(c00, sh), DEC(c10, sh), ax), mix(DEC(c01, sh), DEC(c11, sh), ax), ay);
  GI_BILERP(r.x, 0, GI_DECODE)
  GI_BILERP(r.y, 8, GI_DECODE)
  GI_BILERP(r.z, 16, GI_DECODE)
  GI_BILERP(r.w, 24, GI_LINEAR)
#undef GI_CH
#undef GI_DECODE
#undef GI_LINEAR
#undef GI_BILERP
  return r;
}

// sample_texture() lane-wise (lanes with index < 0 read texture 0; callers discard them).
inline float4V sample_textureV(global const GiTexture* table, global const uchar4* texels, intV index, floatV u,
                               floatV v, floatV lod) {
  return sample_texture_levelV(texels, texture_levelV(table, index, lod), u, v);
}
