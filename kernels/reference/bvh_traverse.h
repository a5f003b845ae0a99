// Ray traversal of the 8-wide BVH built by src/reference/bvh.cpp (layout documented in bvh.h).
//
// What it computes: trace_closest() finds the nearest triangle hit in (tmin, tmax); trace_any()
// answers whether any hit exists there (shadow / visibility rays). Both skip alpha-masked
// surfaces where material_cut_out() says the hit point is cut away (texture sampled at level 0).
// Triangles are two-sided (no culling). Möller–Trumbore, non-watertight: a ray through a shared
// edge may very rarely slip between two triangles.
//
// How (PoCL on a CPU runs each work-item's loop as scalar code): one node test is 6 float8 loads,
// 6 FMAs and min/max trees, 8 children at once; the nearest hit child is visited next and the
// others pushed far to near with their entry distance, so popped entries farther than the current
// hit are skipped. Leaves hold packs of 4 triangles tested at once with float4 maths.
//
// Use: a kernel that traces takes GI_BVH_ARGS among its parameters (set on the host by
// DeviceBvh::setArgs, 7 arguments), builds `GiBvh bvh = GI_BVH_MAKE;` and calls the functions.
#pragma once
#include "common/material.h"

#define GI_BVH_LEAF_BIT 0x80000000u
#define GI_BVH_EMPTY 0x7FFFFFFFu
#define GI_BVH_ALPHA_BIT 0x80000000u
#define GI_BVH_NODE_FLOATS 64
#define GI_BVH_STACK 128  // entries; a full stack drops children (never seen below ~40)

#define GI_BVH_ARGS                                                                        \
  global const float *bvh_nodes, global const float4 *bvh_tris, global const uint4 *bvh_triangles, \
      global const float2 *bvh_uvs, global const GiMaterial *bvh_materials,                \
      global const GiTexture *bvh_textures, global const uchar4 *bvh_texels
#define GI_BVH_MAKE \
  gi_bvh_make(bvh_nodes, bvh_tris, bvh_triangles, bvh_uvs, bvh_materials, bvh_textures, bvh_texels)

typedef struct {
  global const float* nodes;
  global const float4* tris;       // GiBvhTriPack, 10 float4 each
  global const uint4* triangles;  // scene triangles (i0, i1, i2, material): alpha test
  global const float2* uvs;
  global const GiMaterial* materials;
  global const GiTexture* textures;
  global const uchar4* texels;
} GiBvh;

typedef struct {
  float t;
  float u, v;  // barycentrics of vertex 1 and 2 of the original triangle
  uint prim;   // original triangle index, GI_INVALID_ID on a miss
} GiHit;

inline GiBvh gi_bvh_make(global const float* nodes, global const float4* tris, global const uint4* triangles,
                         global const float2* uvs, global const GiMaterial* materials,
                         global const GiTexture* textures, global const uchar4* texels) {
  GiBvh b;
  b.nodes = nodes; b.tris = tris; b.triangles = triangles; b.uvs = uvs;
  b.materials = materials; b.textures = textures; b.texels = texels;
  return b;
}

// True when the alpha mask cuts the surface away at barycentrics (u, v) of triangle `prim`.
inline bool gi_bvh_cut_out(const GiBvh* b, uint prim, float u, float v) {
  uint4 tri = b->triangles[prim];
  float2 uv = b->uvs[tri.x] * (1.0f - u - v) + b->uvs[tri.y] * u + b->uvs[tri.z] * v;
  return material_cut_out(b->materials + tri.w, b->textures, b->texels, uv, 0.0f);
}

// Möller–Trumbore against the 4 triangles of pack `p` at once (the per-lane operations of
// gi::intersectTriangle on the host). Returns the mask of lanes hit in (tmin, tmax) and their
// t, u, v and tagged ids.
inline int gi_bvh_pack(const GiBvh* b, uint p, float3 o, float3 d, float tmin, float tmax, float4* t, float4* u,
                       float4* v, uint4* id) {
  global const float4* q = b->tris + (size_t)p * 10;
  float4 v0x = q[0], v0y = q[1], v0z = q[2], e1x = q[3], e1y = q[4], e1z = q[5], e2x = q[6], e2y = q[7], e2z = q[8];
  float4 px = d.y * e2z - d.z * e2y, py = d.z * e2x - d.x * e2z, pz = d.x * e2y - d.y * e2x;
  float4 det = e1x * px + e1y * py + e1z * pz;
  float4 inv = 1.0f / det;
  float4 sx = o.x - v0x, sy = o.y - v0y, sz = o.z - v0z;
  float4 uu = (sx * px + sy * py + sz * pz) * inv;
  float4 qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
  float4 vv = (d.x * qx + d.y * qy + d.z * qz) * inv;
  float4 tt = (e2x * qx + e2y * qy + e2z * qz) * inv;
  int4 ok = (fabs(det) >= (float4)(1e-30f)) & (uu >= 0.0f) & (uu <= 1.0f) & (vv >= 0.0f) & (uu + vv <= 1.0f) &
            (tt > tmin) & (tt < tmax);
  int4 bits = ok & (int4)(1, 2, 4, 8);
  *t = tt; *u = uu; *v = vv; *id = as_uint4(q[9]);
  return bits.x | bits.y | bits.z | bits.w;
}

// Shared traversal. any_hit: stop at the first (unmasked) hit.
inline bool gi_bvh_trace(const GiBvh* b, float3 o, float3 d, float tmin, float tmax, bool any_hit, GiHit* hit) {
  float3 inv;
  inv.x = fabs(d.x) > 1e-20f ? 1.0f / d.x : copysign(1e20f, d.x);
  inv.y = fabs(d.y) > 1e-20f ? 1.0f / d.y : copysign(1e20f, d.y);
  inv.z = fabs(d.z) > 1e-20f ? 1.0f / d.z : copysign(1e20f, d.z);
  float3 oi = o * inv;
  // Near/far planes by direction sign: offsets of lo/hi arrays in the node (lo_x at 0, hi_x at 8...).
  int nx = inv.x >= 0.0f ? 0 : 8, ny = inv.y >= 0.0f ? 16 : 24, nz = inv.z >= 0.0f ? 32 : 40;
  int fx = nx ^ 8, fy = ny ^ 8, fz = nz ^ 8;

  uint stack[GI_BVH_STACK];
  float stackT[GI_BVH_STACK];
  int sp = 0;
  uint node = 0;
  bool found = false;
  hit->prim = GI_INVALID_ID;
  hit->t = tmax;
  const int8 bitv = (int8)(1, 2, 4, 8, 16, 32, 64, 128);

  for (;;) {
    if ((node & GI_BVH_LEAF_BIT) == 0) {
      global const float* n = b->nodes + (size_t)node * GI_BVH_NODE_FLOATS;
      float8 tnx = vload8(0, n + nx) * inv.x - oi.x;
      float8 tny = vload8(0, n + ny) * inv.y - oi.y;
      float8 tnz = vload8(0, n + nz) * inv.z - oi.z;
      float8 tfx = vload8(0, n + fx) * inv.x - oi.x;
      float8 tfy = vload8(0, n + fy) * inv.y - oi.y;
      float8 tfz = vload8(0, n + fz) * inv.z - oi.z;
      float8 tn = max(max(tnx, tny), max(tnz, (float8)(tmin)));
      float8 tf = min(min(tfx, tfy), min(tfz, (float8)(tmax)));
      int8 bits = (tn <= tf) & bitv;
      int4 b4 = bits.lo | bits.hi;
      int2 b2 = b4.lo | b4.hi;
      uint mask = (uint)(b2.x | b2.y);
      if (mask != 0) {
        global const uint* ch = (global const uint*)(n + 48);
        if ((mask & (mask - 1)) == 0) {  // one child: no stack traffic
          node = ch[31 - clz(mask)];
          continue;
        }
        float tarr[8];
        vstore8(tn, 0, tarr);
        if (any_hit) {
          // Order does not matter for occlusion: visit the lowest child, push the rest.
          int first = 31 - clz(mask & (0u - mask));
          uint m = mask & (mask - 1);
          while (m && sp < GI_BVH_STACK) {
            int i = 31 - clz(m & (0u - m));
            m &= m - 1;
            stack[sp] = ch[i];
            stackT[sp] = tarr[i];
            ++sp;
          }
          node = ch[first];
          continue;
        }
        // Closest hit: push the hit children sorted far to near (insertion sort into the stack
        // top, at most 8 entries) and visit the nearest, so nearer boxes are popped first.
        int base = sp;
        uint m = mask;
        while (m && sp < GI_BVH_STACK) {
          int i = 31 - clz(m & (0u - m));
          m &= m - 1;
          float t = tarr[i];
          uint c = ch[i];
          int k = sp;
          while (k > base && stackT[k - 1] < t) {
            stack[k] = stack[k - 1];
            stackT[k] = stackT[k - 1];
            --k;
          }
          stack[k] = c;
          stackT[k] = t;
          ++sp;
        }
        --sp;
        node = stack[sp];
        continue;
      }
    } else {
      uint first = node & 0x07FFFFFFu, count = ((node >> 27) & 15u) + 1u;
      for (uint p = first; p < first + count; ++p) {
        float4 t4, u4, v4;
        uint4 id4;
        int m = gi_bvh_pack(b, p, o, d, tmin, tmax, &t4, &u4, &v4, &id4);
        if (m == 0) continue;
        float ta[4], ua[4], va[4];
        uint ia[4];
        vstore4(t4, 0, ta); vstore4(u4, 0, ua); vstore4(v4, 0, va); vstore4(id4, 0, ia);
        // Nearest lane first; an alpha-masked lane that is cut away gives way to the next.
        while (m) {
          int best = 31 - clz(m & -m);
          for (int l = 0; l < 4; ++l)
            if ((m >> l & 1) && ta[l] < ta[best]) best = l;
          m &= ~(1 << best);
          uint prim = ia[best] & ~GI_BVH_ALPHA_BIT;
          if ((ia[best] & GI_BVH_ALPHA_BIT) && gi_bvh_cut_out(b, prim, ua[best], va[best])) continue;
          tmax = ta[best];
          hit->t = ta[best]; hit->u = ua[best]; hit->v = va[best]; hit->prim = prim;
          found = true;
          break;
        }
        if (found && any_hit) return true;
      }
    }
    // Pop the next entry that can still hold a nearer hit.
    bool next = false;
    while (sp > 0) {
      --sp;
      if (stackT[sp] <= tmax) { node = stack[sp]; next = true; break; }
    }
    if (!next) break;
  }
  return found;
}

// Nearest hit in (tmin, tmax). d need not be unit length (t is in units of |d|).
inline bool trace_closest(const GiBvh* b, float3 o, float3 d, float tmin, float tmax, GiHit* hit) {
  return gi_bvh_trace(b, o, d, tmin, tmax, false, hit);
}

// Any hit in (tmin, tmax): true = occluded.
inline bool trace_any(const GiBvh* b, float3 o, float3 d, float tmin, float tmax) {
  GiHit h;
  return gi_bvh_trace(b, o, d, tmin, tmax, true, &h);
}
