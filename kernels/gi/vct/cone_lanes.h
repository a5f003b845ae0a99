// The cone march of cone.h with GI_VW pixels per work-item (common/vector_width.h;
// PERFORMANCE_FACTS.md points 1-2: a data-dependent loop over one pixel per work-item runs as
// scalar code on PoCL, explicit lanes do not).
//
// Each lane marches its own cone (aperture, angle to its normal, hence its own distances, levels
// and footprint caps); for the diffuse set these are the same in every lane, so the lanes step in
// lockstep. A lane that leaves the grid, passes the maximum distance or saturates is masked from
// then on (vct_cone breaks there); the march ends when every lane is done. Same formulas as
// vct_cone, term for term, with log2/exp2 lane-wise (log2V, pow01V).
#pragma once
#include "common/vector_width.h"
#include "gi/vct/cone.h"

typedef struct {
  floatV r, g, b, a;
} RgbaV;

// The chains of VoxelMips as float arrays (4 floats per record; SH: 12 per voxel).
typedef struct {
  global const float* iso;
  global const float* aniso;
  global const float* sh;
  global const float* shAniso;
  int N, levels, anisotropic;
} VoxelMipsV;

inline VoxelMipsV vox_mips_lanes(VoxelMips m) {
  VoxelMipsV r;
  r.iso = (global const float*)m.iso;
  r.aniso = (global const float*)m.aniso;
  r.sh = (global const float*)m.sh;
  r.shAniso = (global const float*)m.shAniso;
  r.N = m.N;
  r.levels = m.levels;
  r.anisotropic = m.anisotropic;
  return r;
}

// acc += weight × the trilinear lookup at p of the volume of n³ voxels (scale = n / N) starting at
// voxel `base` (all per lane) of `vol` (radiance, α) or, with SH voxels, of `shVol` evaluated against basis
// (Y0, Y1y, Y1z, Y1x) with α from `vol` (vox_trilinear / vox_trilinear_sh).
inline void vox_trilinear_lanes(global const float* vol, global const float* shVol, intV base, intV n, float3V p,
                                floatV scale, floatV weight, floatV Y0, floatV Y1y, floatV Y1z, floatV Y1x, RgbaV* acc) {
  floatV ux = p.x * scale - 0.5f, uy = p.y * scale - 0.5f, uz = p.z * scale - 0.5f;
  floatV flx = floor(ux), fly = floor(uy), flz = floor(uz);
  floatV fx = ux - flx, fy = uy - fly, fz = uz - flz;
  intV ix = convert_intV(flx), iy = convert_intV(fly), iz = convert_intV(flz);
  for (int k = 0; k < 8; ++k) {
    intV x = ix + (k & 1), y = iy + ((k >> 1) & 1), z = iz + (k >> 2);
    intV inside = x >= 0 && x < n && y >= 0 && y < n && z >= 0 && z < n;
    floatV w = ((k & 1) ? fx : 1.0f - fx) * (((k >> 1) & 1) ? fy : 1.0f - fy) * ((k >> 2) ? fz : 1.0f - fz);
    w = GI_SEL((floatV)(0.0f), w * weight, inside);
    intV idx = base + GI_SEL((intV)(0), (z * n + y) * n + x, inside);
#if GI_VCT_SH
    floatV r0, r1, r2, r3, g0, g1, g2, g3, b0, b1, b2, b3;
    GI_GATHER_SPAN4(float, shVol, idx * 12, r0, r1, r2, r3)
    GI_GATHER_SPAN4(float, shVol, idx * 12 + 4, g0, g1, g2, g3)
    GI_GATHER_SPAN4(float, shVol, idx * 12 + 8, b0, b1, b2, b3)
    acc->r += w * (r0 * Y0 + r1 * Y1y + r2 * Y1z + r3 * Y1x);
    acc->g += w * (g0 * Y0 + g1 * Y1y + g2 * Y1z + g3 * Y1x);
    acc->b += w * (b0 * Y0 + b1 * Y1y + b2 * Y1z + b3 * Y1x);
    acc->a += w * GI_GATHER(floatV, vol + 3, idx * 4);
#else
    floatV r, g, b, a;
    GI_GATHER_AOS4(float, vol, idx, r, g, b, a)
    acc->r += w * r;
    acc->g += w * g;
    acc->b += w * b;
    acc->a += w * a;
#endif
  }
}

// acc += weight × level `level` (per lane) seen along d (vox_level_sample). Level offsets in closed
// form: Σ_{l<L} (N >> l)³ = 8·(N³ − n³)/7 with n = N >> L.
inline void vox_level_sample_lanes(VoxelMipsV m, intV level, float3V p, float3V d, floatV weight, RgbaV* acc) {
  intV n = (intV)(m.N) >> level;
  floatV scale = convert_floatV(n) * (1.0f / (float)m.N);
  int N3 = m.N * m.N * m.N;
  intV n3 = n * n * n;
  intV offset = 8 * (N3 - n3) / 7;
  // Light arriving at the apex travels along −d: the SH basis at −d.
  floatV Y0 = (floatV)(GI_SH_Y0), Y1y = -GI_SH_Y1 * d.y, Y1z = -GI_SH_Y1 * d.z, Y1x = -GI_SH_Y1 * d.x;
  intV isoLanes = level == 0;
  if (!m.anisotropic) isoLanes = (intV)(-1);
  // Lanes masked out of a volume (weight 0) read its first voxel only (n = 1, base 0): the
  // isotropic levels ≥ 1 are not built with anisotropic mips, and level 0 has no directional
  // volumes; unwritten memory could hold NaN, and NaN·0 is NaN.
  if (GI_ANY(isoLanes))
    vox_trilinear_lanes(m.iso, m.sh, GI_SEL((intV)(0), offset, isoLanes), GI_SEL((intV)(1), n, isoLanes), p, scale,
                        GI_SEL((floatV)(0.0f), weight, isoLanes), Y0, Y1y, Y1z, Y1x, acc);
  if (!m.anisotropic || GI_ALL(isoLanes)) return;
  floatV da[3] = {d.x, d.y, d.z};
  intV nDirectional = GI_SEL(n, (intV)(1), isoLanes);
  for (int axis = 0; axis < 3; ++axis) {
    // Directional volume 2·axis (+) or 2·axis + 1 (−) of the level (vox_aniso_offset).
    intV dir = 2 * axis + GI_SEL((intV)(1), (intV)(0), da[axis] >= 0.0f);
    intV base = 6 * (offset - N3) + dir * n3;
    vox_trilinear_lanes(m.aniso, m.shAniso, GI_SEL(base, (intV)(0), isoLanes), nDirectional, p, scale,
                        GI_SEL(weight * da[axis] * da[axis], (floatV)(0.0f), isoLanes), Y0, Y1y, Y1z, Y1x, acc);
  }
}

// vox_sample for the lanes: quadrilinear at a fractional level per lane.
inline RgbaV vox_sample_lanes(VoxelMipsV m, float3V p, float3V d, floatV level) {
  level = clamp(level, 0.0f, (float)(m.levels - 1));
  floatV fl = floor(level);
  intV l0 = convert_intV(fl);
  floatV f = level - fl;
  intV second = f > 0.0f && l0 + 1 < m.levels;
  floatV w1 = GI_SEL((floatV)(0.0f), f, second);
  RgbaV c;
  c.r = c.g = c.b = c.a = (floatV)(0.0f);
  vox_level_sample_lanes(m, l0, p, d, 1.0f - w1, &c);
  if (GI_ANY(second)) vox_level_sample_lanes(m, min(l0 + 1, m.levels - 1), p, d, w1, &c);
#if GI_VCT_SH
  c.r = fmax(c.r, 0.0f);
  c.g = fmax(c.g, 0.0f);
  c.b = fmax(c.b, 0.0f);
#endif
  return c;
}

// log2(x) for positive normal x, lane-wise without library calls (PERFORMANCE_FACTS point 4):
// the exponent bits plus the atanh series of the mantissa scaled into [√½, √2); absolute error
// below 1e-7.
inline floatV log2V(floatV x) {
  uintV bits = as_uintV(x);
  intV e = convert_intV(bits >> 23) - 127;
  floatV m = as_floatV((bits & 0x007fffffu) | 0x3f800000u);  // [1, 2)
  intV high = m > 1.41421356f;
  m = GI_SEL(m, 0.5f * m, high);
  e = GI_SEL(e, e + 1, high);
  floatV s = (m - 1.0f) / (m + 1.0f), s2 = s * s;
  return convert_floatV(e) + 2.88539008f * s * (1.0f + s2 * (1.0f / 3.0f + s2 * (0.2f + s2 * (1.0f / 7.0f))));
}

// x^r for x in [0, 1] and r > 0 lane-wise: exp2(r·log2V(x)), exp2 from the exponent bits and a
// Taylor polynomial on [−½, ½]; relative error below 1e-6 (x = 0 gives 2^(−127·r), not 0).
inline floatV pow01V(floatV x, floatV r) {
  floatV y = fmax(r * log2V(x), -126.0f);
  floatV i = floor(y + 0.5f);
  floatV f = (y - i) * 0.693147181f;
  floatV p = 1.0f + f * (1.0f + f * (0.5f + f * (1.0f / 6.0f + f * (1.0f / 24.0f + f * (1.0f / 120.0f + f * (1.0f / 720.0f))))));
  return p * as_floatV(convert_uintV(convert_intV(i) + 127) << 23);
}

// vct_footprint lane-wise; the largest power of two ≤ the bound by clearing its mantissa.
inline floatV vct_footprint_lanes(floatV tanHalf, floatV t, float h0, floatV cosN) {
  floatV bound = (h0 + t * cosN - 1.0f) * (1.0f / 1.5f);
  floatV cap = GI_SEL((floatV)(1.0f), as_floatV(as_uintV(bound) & 0xff800000u), bound >= 1.0f);
  return fmax(1.0f, fmin(2.0f * tanHalf * t, cap));
}

// vct_cone for GI_VW cones from o along d, of half-angle tan tanHalf, whose axes make cosine cosN
// with their surfaces' normals: radiance (r, g, b) and opacity a arriving along them, and the AO
// occlusion.
inline RgbaV vct_cone_lanes(VoxelMipsV m, float3V o, float3V d, floatV tanHalf, float maxDistance, float stepFactor,
                            float aoLambda, float h0, floatV cosN, floatV* occlusion) {
  RgbaV c;
  c.r = c.g = c.b = c.a = (floatV)(0.0f);
  floatV occ = (floatV)(0.0f);
  intV done = (intV)(0);
  floatV t = (floatV)(0.0f);
  float limit = (float)m.N;
  for (;;) {
    // vct_cone_advance
    floatV step = fmax(0.5f, stepFactor * vct_footprint_lanes(tanHalf, t, h0, cosN));
    t += step;
    floatV diameter = vct_footprint_lanes(tanHalf, t, h0, cosN);
    floatV margin = 0.5f * diameter;
    float3V p = addV(o, scaleV(d, t));
    done = done || t > maxDistance || p.x < -margin || p.y < -margin || p.z < -margin || p.x > limit + margin ||
           p.y > limit + margin || p.z > limit + margin;
    if (GI_ALL(done)) break;
    // Footprint in front: nothing sampled below h = 2.5 voxels.
    intV sampled = !done && h0 + t * cosN - 1.0f >= 1.5f;
    if (!GI_ANY(sampled)) continue;
    RgbaV s = vox_sample_lanes(m, p, d, log2V(diameter));
    intV live = sampled && s.a > 1e-6f;
    floatV alpha = fmin(s.a, 1.0f);
    floatV corrected = 1.0f - pow01V(1.0f - alpha, step / diameter);
    floatV k = GI_SEL((floatV)(0.0f), (1.0f - c.a) * (corrected / s.a), live);
    c.r += k * s.r;
    c.g += k * s.g;
    c.b += k * s.b;
    occ += GI_SEL((floatV)(0.0f), (1.0f - occ) * corrected / (1.0f + aoLambda * t), live);
    c.a += GI_SEL((floatV)(0.0f), (1.0f - c.a) * corrected, live);
    done = done || c.a >= 0.99f;
  }
  *occlusion = occ;
  return c;
}

#ifdef VCT_CONE_COUNT
// vct_diffuse_irradiance for GI_VW surface points p with normals n: irradiance (r, g, b) and, in
// a, the AO visibility.
inline RgbaV vct_diffuse_irradiance_lanes(VoxelMipsV m, float3V p, float3V n, float startOffset, float maxDistance,
                                          float stepFactor, float aoLambda, int footprintInFront) {
  // orthonormal_basis (common/math.h) lane-wise.
  floatV s = GI_SEL((floatV)(-1.0f), (floatV)(1.0f), n.z >= 0.0f);
  floatV a = -1.0f / (s + n.z);
  floatV c = n.x * n.y * a;
  float3V t = f3v(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
  float3V b = f3v(c, s + n.y * n.y * a, -n.y);
  float3V o = addV(p, scaleV(n, (floatV)(startOffset)));
  RgbaV E;
  E.r = E.g = E.b = (floatV)(0.0f);
  floatV occlusion = (floatV)(0.0f);
  for (int i = 0; i < VCT_CONE_COUNT; ++i) {
    float4 cone = VCT_CONES[i];
    float3V d = addV(addV(scaleV(t, (floatV)(cone.x)), scaleV(b, (floatV)(cone.y))), scaleV(n, (floatV)(cone.z)));
    d = scaleV(d, rsqrt(dotV(d, d)));
    floatV occ;
    RgbaV r = vct_cone_lanes(m, o, d, (floatV)(VCT_DIFFUSE_TAN_HALF), maxDistance, stepFactor, aoLambda,
                             footprintInFront ? startOffset : INFINITY, (floatV)(cone.z), &occ);
    E.r += cone.w * r.r;
    E.g += cone.w * r.g;
    E.b += cone.w * r.b;
    occlusion += cone.w * GI_INV_PI * occ;
  }
  E.a = 1.0f - occlusion;
  return E;
}
#endif
