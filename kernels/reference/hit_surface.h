// The surface at a BVH hit: position, normals, texture coordinates, material and emission of the
// original triangle, interpolated with the hit's barycentrics. Shared by everything that shades
// ray hits (the reference path tracer, the probe updates of kernels/gi/probes/).
#pragma once
#include "common/material.h"
#include "reference/bvh_traverse.h"

typedef struct {
  float3 p, ng, n;  // position, geometric normal (oriented like the vertex normals), shading normal
  float2 uv;
  uint material;
  float area;
} PtSurface;

inline PtSurface pt_surface(global const float4* positions, global const float4* normals,
                            global const float4* tangents, const GiBvh* bvh, uint prim, float u, float v,
                            bool normalMap) {
  PtSurface s;
  uint4 tri = bvh->triangles[prim];
  float3 p0 = positions[tri.x].xyz, p1 = positions[tri.y].xyz, p2 = positions[tri.z].xyz;
  float w = 1.0f - u - v;
  s.p = p0 * w + p1 * u + p2 * v;
  float3 c = cross(p1 - p0, p2 - p0);
  s.area = 0.5f * length(c);
  float3 ng = safe_normalize(c, (float3)(0.0f, 0.0f, 1.0f));
  float3 n = normals[tri.x].xyz * w + normals[tri.y].xyz * u + normals[tri.z].xyz * v;
  n = safe_normalize(n, ng);
  if (dot(ng, n) < 0.0f) ng = -ng;
  s.ng = ng;
  s.uv = bvh->uvs[tri.x] * w + bvh->uvs[tri.y] * u + bvh->uvs[tri.z] * v;
  s.material = tri.w;
  if (normalMap) {
    float4 t = tangents[tri.x] * w + tangents[tri.y] * u + tangents[tri.z] * v;
    t.w = tangents[tri.x].w;
    n = apply_normal_map(bvh->materials + tri.w, bvh->textures, bvh->texels, s.uv, 0.0f, n, t);
  }
  s.n = n;
  return s;
}

inline float3 pt_emission(const GiBvh* bvh, uint material, float2 uv) {
  global const GiMaterial* m = bvh->materials + material;
  float3 e = vload3(0, m->emissive);
  if (m->emissive_tex >= 0 && (e.x > 0.0f || e.y > 0.0f || e.z > 0.0f))
    e *= sample_texture(bvh->textures, bvh->texels, m->emissive_tex, uv, 0.0f).xyz;
  return e;
}

inline float pt_offset_scale(float3 p) {
  float m = fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z)));
  return 1e-5f + 4e-6f * m;
}
