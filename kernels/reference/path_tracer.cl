// The reference path tracer (ALGORITHMS.md §8): unidirectional, one work-item per pixel, a
// megakernel (on a CPU device work-items run one after another, so divergence costs nothing and a
// wavefront split would only add memory traffic).
//
// Follows: pbrt-v4's PathIntegrator structure. Materials, BRDF, textures, normal maps and
// punctual-light emission come from kernels/common (material.h, brdf.h, lights.h), the same code
// the rasterized techniques use.
//
// Light transport:
// - Punctual lights (directional, point, spot with both falloffs) by next-event estimation only.
//   Lights named "emitter:*" are stand-ins for emissive geometry and are removed on the host.
// - Emissive triangles by NEE (a triangle chosen by power from a CDF, a point uniform on its
//   area) and by BSDF sampling, combined with the power heuristic. Emission is one-sided: the
//   side the vertex normals point to.
// - BSDF sampling: Lambert (cosine) or GGX visible normals, lobe chosen by Fresnel vs albedo.
// - Russian roulette from the 3rd bounce on, survival probability = max throughput component.
// - Surfaces are shaded two-sided (normals flipped towards the incoming ray).
//
// Bounce counting ("order" k = the number of surface reflections of the light before it reaches
// the camera, the visible surface included): emission seen directly has k = 0, direct lighting
// k = 1, one-bounce indirect k = 2. A sample adds only paths with GI_K_MIN <= k <= k_max, so
//   full: 0..max_bounces, direct: 0..1, indirect: 2..max_bounces, one-bounce: exactly 2.
// Both strategies for one path (NEE at vertex k, emission hit at vertex k+1) have the same k, so
// MIS weights stay valid inside every mode.
//
// Output: per pixel, running sum and sum of squares of the per-sample radiance (float4, w
// unused), added in sample order so the result does not depend on how samples are batched into
// launches. Samples with a non-finite value count as 0.
//
// Not handled: transmission, KHR extensions beyond metallic-roughness, texture filtering
// (textures are sampled at level 0, which the pixel supersampling averages), light range.
#include "common/brdf.h"
#include "common/lights.h"
#include "reference/hit_surface.h"

inline uint pt_hash(uint x) {
  uint s = x * 747796405u + 2891336453u;
  uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  return (w >> 22u) ^ w;
}

// PCG-style stream: an LCG state with a hashed output.
inline float pt_rand(uint* state) {
  *state = *state * 747796405u + 2891336453u;
  uint s = *state;
  uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  w = (w >> 22u) ^ w;
  return (float)(w >> 8) * (1.0f / 16777216.0f);
}

inline float3 pt_brdf(SurfaceSample s, float3 n, float3 wo, float3 wi) {
#ifdef PT_DIFFUSE_ONLY
  return dot(n, wi) > 0.0f ? s.diffuse * GI_INV_PI : (float3)(0.0f);
#else
  return brdf_eval(s, n, wo, wi);
#endif
}

kernel void pt_render(GI_BVH_ARGS,
                      global const float4* positions, global const float4* normals, global const float4* tangents,
                      global const GiLight* lights, uint lightCount,
                      global const uint* emitTri, global const float* emitCdf, uint emitCount,
                      global const float* triLightPmf,
                      GiView view, uint width, uint height,
                      uint firstSample, uint sampleCount, uint seed, uint kMin, uint kMax,
                      global float4* sum, global float4* sumSq) {
  uint pixel = get_global_id(0);
  if (pixel >= width * height) return;
  GiBvh bvh = GI_BVH_MAKE;
  uint px = pixel % width, py = pixel / width;
  float4 acc = sum[pixel], acc2 = sumSq[pixel];
  float3 eye = vload3(0, view.eye);

  for (uint si = 0; si < sampleCount; ++si) {
    uint rng = pt_hash(pixel ^ pt_hash((firstSample + si) ^ pt_hash(seed * 0x9E3779B9u + 0x7F4A7C15u)));
    // Camera ray through a uniformly jittered point of the pixel (box filter).
    float jx = pt_rand(&rng), jy = pt_rand(&rng);
    float ndcX = ((float)px + jx) / (float)width * 2.0f - 1.0f;
    float ndcY = 1.0f - ((float)py + jy) / (float)height * 2.0f;
    float4 far4 = mat4_mul(view.inv_view_proj, (float4)(ndcX, ndcY, 1.0f, 1.0f));
    float3 o = eye;
    float3 d = normalize(far4.xyz / far4.w - eye);

    float3 L = (float3)(0.0f), beta = (float3)(1.0f);
    float prevPdf = 0.0f;  // BSDF pdf of the direction that reached this vertex (0: camera ray)
    float3 prevP = o;

    for (uint j = 1;; ++j) {
      GiHit hit;
      if (!trace_closest(&bvh, o, d, 0.0f, INFINITY, &hit)) break;
      PtSurface sf = pt_surface(positions, normals, tangents, &bvh, hit.prim, hit.u, hit.v, true);
      float3 wo = -d;
      global const GiMaterial* mat = bvh.materials + sf.material;

      // Emission seen along d: path order k = j - 1, one-sided (front = vertex-normal side).
      if (j - 1 >= kMin && j - 1 <= kMax && triLightPmf[hit.prim] > 0.0f && dot(sf.ng, wo) > 0.0f) {
        float3 Le = pt_emission(&bvh, sf.material, sf.uv);
        float w = 1.0f;
        if (prevPdf > 0.0f) {
          float cosL = dot(sf.ng, wo);
          float dist2 = hit.t * hit.t;  // d is unit length
          float lightPdf = triLightPmf[hit.prim] / sf.area * dist2 / cosL;
          w = prevPdf * prevPdf / (prevPdf * prevPdf + lightPdf * lightPdf);
        }
        L += beta * Le * w;
      }
      if (j > kMax) break;

      // Two-sided shading: face the normals towards the incoming ray.
      float3 ng = sf.ng, n = sf.n;
      if (dot(ng, wo) < 0.0f) { ng = -ng; n = -n; }
      SurfaceSample s = eval_material(mat, bvh.textures, bvh.texels, sf.uv, 0.0f);
#ifdef PT_DIFFUSE_ONLY
      float pspec = 0.0f;
#else
      float pspec = brdf_specular_probability(s, n, wo);
#endif
      float3 x = sf.p + ng * pt_offset_scale(sf.p);

      if (j >= kMin) {
        // NEE, punctual lights: one light chosen uniformly.
        if (lightCount > 0) {
          uint li = min((uint)(pt_rand(&rng) * (float)lightCount), lightCount - 1);
          float3 wi;
          float dist;
          float3 E = light_incident(lights + li, x, &wi, &dist);
          float cosI = dot(n, wi);
          if (cosI > 0.0f && dot(ng, wi) > 0.0f && (E.x > 0.0f || E.y > 0.0f || E.z > 0.0f)) {
            float tmax = isinf(dist) ? INFINITY : dist * (1.0f - 1e-4f);
            if (!trace_any(&bvh, x, wi, 0.0f, tmax))
              L += beta * pt_brdf(s, n, wo, wi) * E * cosI * (float)lightCount;
          }
        }
        // NEE, emissive triangles: triangle by power, point uniform on it.
        if (emitCount > 0) {
          float ul = pt_rand(&rng), ua = pt_rand(&rng), ub = pt_rand(&rng);
          uint lo = 0, hi = emitCount - 1;
          while (lo < hi) {
            uint mid = (lo + hi) >> 1;
            if (emitCdf[mid] <= ul) lo = mid + 1; else hi = mid;
          }
          uint lt = emitTri[lo];
          float su = sqrt(ua);
          PtSurface ls = pt_surface(positions, normals, tangents, &bvh, lt, su * (1.0f - ub), su * ub, false);
          float3 toL = ls.p - x;
          float dist2 = dot(toL, toL);
          float dist = sqrt(dist2);
          float3 wi = toL / dist;
          float cosL = -dot(ls.ng, wi);
          float cosI = dot(n, wi);
          if (cosL > 0.0f && cosI > 0.0f && dot(ng, wi) > 0.0f) {
            float3 Le = pt_emission(&bvh, ls.material, ls.uv);
            float lightPdf = triLightPmf[lt] / ls.area * dist2 / cosL;
            float3 f = pt_brdf(s, n, wo, wi);
            float bsdfPdf = brdf_pdf(s, n, wo, wi, pspec);
            float w = lightPdf * lightPdf / (lightPdf * lightPdf + bsdfPdf * bsdfPdf);
            if (lightPdf > 0.0f && !trace_any(&bvh, x, wi, 0.0f, dist * (1.0f - 1e-4f) - pt_offset_scale(ls.p)))
              L += beta * f * Le * (cosI * w / lightPdf);
          }
        }
      }
      // At j == kMax the path continues only for the emission found at vertex j + 1 (order j):
      // without emissive triangles that ray cannot add anything.
      if (j >= kMax && emitCount == 0) break;
      // BSDF sampling for the next direction.
      float3 u3 = (float3)(pt_rand(&rng), pt_rand(&rng), pt_rand(&rng));
      float3 wi;
      if (!brdf_sample(s, n, wo, pspec, u3, &wi)) break;
      if (dot(ng, wi) <= 0.0f) break;
      float pdf = brdf_pdf(s, n, wo, wi, pspec);
      if (!(pdf > 0.0f)) break;
      beta *= pt_brdf(s, n, wo, wi) * (dot(n, wi) / pdf);
      // Russian roulette from the third bounce on.
      if (j >= 3) {
        float q = fmin(1.0f, fmax(beta.x, fmax(beta.y, beta.z)));
        if (pt_rand(&rng) >= q) break;
        beta /= q;
      }
      if (!(beta.x > 0.0f || beta.y > 0.0f || beta.z > 0.0f)) break;
      prevPdf = pdf;
      o = x;
      d = wi;
    }
    float3 Lc = isfinite(L.x) && isfinite(L.y) && isfinite(L.z) ? L : (float3)(0.0f);
    acc.xyz += Lc;
    acc2.xyz += Lc * Lc;
  }
  sum[pixel] = acc;
  sumSq[pixel] = acc2;
}
