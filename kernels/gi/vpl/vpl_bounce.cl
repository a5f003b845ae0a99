// Further generations of VPLs (Keller 1997, "Instant radiosity"; ALGORITHMS.md §2;
// docs/techniques/vpl.md "Bounces"): quasi-random walks continued from the RSM's VPLs.
//
// A parent is a cosine emitter of power Φ_p, so a direction drawn with pdf cos θ / π carries all
// of Φ_p; the ray through the scene's BVH lands on y, which reflects Φ_p · ρ(y). Generation g + 1
// has N_{g+1} slots per light, shared by the A parents of generation g that carry flux (walks
// that left the scene or started without flux are dead; in Sponza most RSM VPLs sit on the roof
// and their rays leave through the sky):
//   vpl_alive   one work-item per light: the indices of its live parents, in order (their
//               Halton order, so any prefix is stratified), and their number A;
//   vpl_bounce  one work-item per slot j: parent of rank r = j mod A, child k = j / A of its
//               m = ⌊N/A⌋ (+1 for r < N mod A) children. Flux
//                 Φ_child = Φ_p · ρ(y) / m          when N ≥ A (every live walk continues, split m ways)
//                 Φ_child = Φ_p · ρ(y) · A / N      when N < A (the first N live walks continue)
//               an unbiased estimate of the power of order g + 2 either way.
// Directions: the walk's own point of the next two Halton dimensions after those of its earlier
// vertices (bases 2, 3 picked the RSM texel; then 5, 7; 11, 13; ...; scrambled,
// gi/vpl/vpl_sequence.h), index = the parent's slot p + 1 — Keller's quasi-random walk — and for
// the m children of one parent that point shifted by (k/m, Φ_2(k)) mod 1 (a rotated Hammersley
// set: the split directions are stratified over the hemisphere).
//
// The child sits at the hit (position and vertex normal of the triangle, turned towards the
// incoming ray since surfaces are two-sided), with ρ = the diffuse albedo of its material and
// texture (level 0) and the parent's d_min². A slot without a live parent or whose ray leaves the
// scene holds a VPL without flux (zero normal and flux), so the layout stays fixed.
// Deterministic: no atomics, every output written by one work-item.
#include "common/math.h"
#include "gi/vpl/vpl_sequence.h"
#include "reference/hit_surface.h"

inline bool vpl_alive_at(global const float4* vpl) {
  float3 n = vpl[1].xyz, f = vpl[2].xyz;
  return (f.x > 0.0f || f.y > 0.0f || f.z > 0.0f) && dot(n, n) > 0.0f;
}

kernel void vpl_alive(global const float4* vpls, int lights, int parentFirst, int parentPerLight,
                      global int* alive, global int* aliveCount) {
  int l = get_global_id(0);
  if (l >= lights) return;
  int a = 0;
  for (int p = 0; p < parentPerLight; ++p)
    if (vpl_alive_at(vpls + (size_t)(parentFirst + l * parentPerLight + p) * 3)) alive[l * parentPerLight + a++] = p;
  aliveCount[l] = a;
}

kernel void vpl_bounce(GI_BVH_ARGS, global const float4* positions, global const float4* normals,
                       global const float4* tangents, int lights, int parentFirst, int parentPerLight,
                       global const int* alive, global const int* aliveCount, int childFirst,
                       int childPerLight, uint baseU, uint multiplierU, uint baseV, uint multiplierV,
                       float rayEpsilon, global float4* vpls) {
  int i = get_global_id(0);
  if (i >= lights * childPerLight) return;
  int l = i / childPerLight, j = i - l * childPerLight;
  global float4* child = vpls + (size_t)(childFirst + l * childPerLight + j) * 3;
  int A = aliveCount[l], N = childPerLight;
  child[1] = (float4)(0.0f);
  child[2] = (float4)(0.0f);
  if (A == 0 || (N < A && j >= N)) {
    child[0] = (float4)(0.0f);
    return;
  }
  int r = j % A, k = j / A;
  int m = N >= A ? N / A + (r < N % A ? 1 : 0) : 1;
  float weight = N >= A ? 1.0f / (float)m : (float)A / (float)N;
  int p = alive[l * parentPerLight + r];
  global const float4* parent = vpls + (size_t)(parentFirst + l * parentPerLight + p) * 3;
  float4 pa = parent[0];
  float3 np = parent[1].xyz, flux = parent[2].xyz;
  child[0] = pa;

  float u = scrambled_radical_inverse((uint)p + 1u, baseU, multiplierU) + (float)k / (float)m;
  float v = scrambled_radical_inverse((uint)p + 1u, baseV, multiplierV) + radical_inverse((uint)k, 2u);
  u -= floor(u);
  v -= floor(v);
  float3 t, b;
  orthonormal_basis(np, &t, &b);
  float rad = sqrt(u), phi = 2.0f * GI_PI * v;
  float3 d = t * (rad * cos(phi)) + b * (rad * sin(phi)) + np * sqrt(fmax(0.0f, 1.0f - u));

  GiBvh bvh = GI_BVH_MAKE;
  GiHit hit;
  if (!trace_closest(&bvh, pa.xyz + np * rayEpsilon, d, 0.0f, INFINITY, &hit)) return;
  PtSurface sf = pt_surface(positions, normals, tangents, &bvh, hit.prim, hit.u, hit.v, false);
  float3 n = dot(sf.ng, d) > 0.0f ? -sf.n : sf.n;
  SurfaceSample s = eval_material(bvh.materials + sf.material, bvh.textures, bvh.texels, sf.uv, 0.0f);
  child[0] = (float4)(sf.p, pa.w);
  child[1] = (float4)(n, 0.0f);
  child[2] = (float4)(flux * s.diffuse * weight, 0.0f);
}
