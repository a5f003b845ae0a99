// VPL visibility (`vpl.visibility=rays`, kernels/gi/vpl/vpl_visibility.h) for the VPL techniques:
//   - the device gather with rays equals a host sum whose pair visibility comes from a brute-force
//     test of the segment against every scene triangle (no BVH), on the Cornell box with blocks;
//   - rays darken the full Cornell box where the blocks occlude and never brighten a pixel, and in
//     the empty (convex) box they change nothing: every receiver sees every VPL there;
//   - igi (1×1) and splat (cut-off beyond the scene) with rays equal vpl with rays.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "gi/vpl/vpl_lights.h"
#include "reference/bvh.h"
#include "render/renderer.h"
#include "accuracy_support.h"
#include "test_support.h"

using namespace gi;

namespace {

constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kEpsilon = 1e-3f;  // vpl.ray_epsilon default


Image renderIndirect(const Scene& s, const std::string& technique, int w, int h, std::vector<std::string> sets) {
  Renderer r(test::context(), s, test::smallRenderSettings(technique, w, h, std::move(sets)));
  r.renderFrame();
  return r.indirectRadiance();
}

// Any scene triangle on the segment o + t·d, t in (tmin, tmax)? Every triangle, no BVH.
bool hostOccluded(const Scene& s, glm::vec3 o, glm::vec3 d, float tmin, float tmax) {
  for (const glm::uvec3& tri : s.triangles) {
    glm::vec3 v0 = s.positions[tri.x];
    float t, u, v;
    if (intersectTriangle(o, d, v0, s.positions[tri.y] - v0, s.positions[tri.z] - v0, tmin, tmax, t, u, v)) return true;
  }
  return false;
}

double meanOf(const Image& im) {
  double s = 0;
  for (float v : im.pixels) s += v;
  return s / double(im.pixels.size());
}

}  // namespace

TEST(VplVisibility, RaysMatchBruteForceHostVisibility) {
  cl::Context& ctx = test::context();
  Scene s = test::cornellWithSpot(true);
  const int W = 24, H = 24, N = 48;
  Renderer r(ctx, s, test::smallRenderSettings("vpl", W, H, {"vpl.count=48", "vpl.visibility=rays"}));
  r.renderFrame();
  Image ind = r.indirectRadiance();
  VplGenerator gen(ctx);
  VplSet v;
  gen.generate(r.rsms(), N, 0.0f, v);
  auto raw = ctx.download<glm::vec4>(v.vpls);
  auto pos = ctx.download<glm::vec4>(r.gbuffer().position), nrm = ctx.download<glm::vec4>(r.gbuffer().normal),
       alb = ctx.download<glm::vec4>(r.gbuffer().albedo);
  ctx.profiler().discard();
  int pairs = 0, occluded = 0, matching = 0, lit = 0;
  for (int p = 0; p < W * H; ++p) {
    glm::vec3 e(0.0f);
    if (pos[p].w > 0) {
      glm::vec3 x(pos[p]), n(nrm[p]);
      for (int k = 0; k < N; ++k) {
        glm::vec3 xp(raw[3 * k]), np(raw[3 * k + 1]), flux(raw[3 * k + 2]);
        glm::vec3 d = xp - x;
        float d2 = glm::dot(d, d);
        float g = std::max(-glm::dot(np, d), 0.0f) * std::max(glm::dot(n, d), 0.0f) /
                  (std::max(d2, 1e-20f) * std::max(d2, raw[3 * k].w));
        if (!(g > 0.0f)) continue;
        ++pairs;
        float t0 = kEpsilon / std::sqrt(d2);
        if (t0 < 0.5f && hostOccluded(s, x, d, t0, 1.0f - t0)) {
          ++occluded;
          continue;
        }
        e += flux * g;
      }
    }
    glm::vec3 expected = glm::vec3(alb[p]) * e * (kInvPi * kInvPi);
    bool same = true;
    for (int c = 0; c < 3; ++c) same &= std::abs(ind.pixels[p * 3 + c] - expected[c]) <= 1e-4f * expected[c] + 1e-7f;
    matching += same;
    lit += expected.y > 0;
  }
  std::printf("%d lit pairs, %d occluded (%.1f %%); %d of %d pixels match the brute-force host sum\n", pairs,
              occluded, 100.0 * occluded / pairs, matching, W * H);
  EXPECT_GT(occluded, pairs / 20) << "the blocks must occlude a fair share of the pairs, or the test proves nothing";
  EXPECT_GT(lit, W * H / 2);
  // A ray grazing a triangle edge may go either way in float maths: allow 1 % of the pixels.
  EXPECT_GE(matching, W * H * 99 / 100);
}

TEST(VplVisibility, RaysDarkenOccludedPixelsAndChangeNothingInTheConvexBox) {
  const int W = 32, H = 32;
  for (bool blocks : {true, false}) {
    Scene s = test::cornellWithSpot(blocks);
    Image none = renderIndirect(s, "vpl", W, H, {"vpl.count=64"});
    Image rays = renderIndirect(s, "vpl", W, H, {"vpl.count=64", "vpl.visibility=rays"});
    int darker = 0, brighter = 0, changed = 0;
    for (size_t i = 0; i < none.pixels.size(); ++i) {
      float a = none.pixels[i], b = rays.pixels[i];
      darker += b < 0.8f * a;
      brighter += b > a * (1.0f + 1e-6f) + 1e-9f;
      changed += std::abs(b - a) > 1e-6f * a + 1e-9f;
    }
    std::printf("%s Cornell box: mean indirect %.5f without visibility, %.5f with rays; %d values darker by > 20 %%, "
                "%d changed\n", blocks ? "full" : "empty", meanOf(none), meanOf(rays), darker, changed);
    EXPECT_EQ(brighter, 0) << "a shadow ray can only remove light";
    if (blocks) {
      EXPECT_GT(darker, int(none.pixels.size()) / 20) << "the blocks' shadows must show";
      EXPECT_LT(meanOf(rays), 0.95 * meanOf(none));
    } else {
      EXPECT_EQ(changed, 0) << "in a convex room every receiver sees every VPL";
    }
  }
}

TEST(VplVisibility, IgiAndSplatTraceTheSameRaysAsVpl) {
  Scene s = test::cornellWithSpot(true);
  const int W = 29, H = 22;
  Image vpl = renderIndirect(s, "vpl", W, H, {"vpl.count=40", "vpl.visibility=rays"});
  Image igi = renderIndirect(s, "igi", W, H, {"igi.count=40", "igi.n=1", "igi.m=1", "vpl.visibility=rays"});
  Image splat = renderIndirect(s, "splat", W, H, {"splat.count=40", "splat.epsilon=1e-12", "vpl.visibility=rays"});
  Image splatNone = renderIndirect(s, "splat", W, H, {"splat.count=40", "splat.epsilon=1e-12"});
  ASSERT_EQ(vpl.pixels.size(), igi.pixels.size());
  EXPECT_EQ(0, std::memcmp(vpl.pixels.data(), igi.pixels.data(), vpl.pixels.size() * sizeof(float)));
  for (size_t i = 0; i < vpl.pixels.size(); ++i)
    ASSERT_NEAR(splat.pixels[i], vpl.pixels[i], 1e-4f * vpl.pixels[i] + 1e-7f) << "value " << i;
  EXPECT_LT(meanOf(splat), 0.95 * meanOf(splatNone));
}
