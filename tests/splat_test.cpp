// `splat` (ALGORITHMS.md §2.4): the tiled culling loses nothing inside the influence radius —
// it equals the host all-pairs sum restricted to pairs with d² < d_min²/ε — and with the cut-off
// pushed out of the scene (ε = 1e-12) it equals `vpl`.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "gi/vpl/vpl_lights.h"
#include "render/renderer.h"
#include "scene/cornell_box.h"
#include "accuracy_support.h"
#include "test_support.h"

using namespace gi;

namespace {

using test::cornellWithSpot;

}  // namespace

TEST(Splat, EqualsVplWhenTheCutOffIsBeyondTheScene) {
  Scene s = cornellWithSpot(true);
  auto run = [&](const std::string& tech, std::vector<std::string> sets) {
    Renderer r(test::context(), s, test::smallRenderSettings(tech, 45, 38, std::move(sets)));
    r.renderFrame();
    return r.indirectRadiance();
  };
  Image a = run("vpl", {"vpl.count=200"});
  Image b = run("splat", {"splat.count=200", "splat.epsilon=1e-12"});
  for (size_t i = 0; i < a.pixels.size(); ++i)
    ASSERT_NEAR(b.pixels[i], a.pixels[i], 1e-5f * std::abs(a.pixels[i]) + 1e-9f) << "value " << i;
}

TEST(Splat, EqualsAllPairsWithinItsEpsilonCutOff) {
  cl::Context& ctx = test::context();
  Scene s = cornellWithSpot(true);
  const int W = 45, H = 38, N = 200;
  for (float eps : {1.0f / 256.0f, 1e-4f}) {
    Renderer r(ctx, s, test::smallRenderSettings("splat", W, H, {"splat.count=200", "splat.epsilon=" + std::to_string(eps)}));
    r.renderFrame();
    Image ind = r.indirectRadiance();
    VplGenerator gen(ctx);
    VplSet v;
    gen.generate(r.rsms(), N, 0.0f, v);
    auto raw = ctx.download<glm::vec4>(v.vpls);
    ctx.profiler().discard();
    auto pos = ctx.download<glm::vec4>(r.gbuffer().position), nrm = ctx.download<glm::vec4>(r.gbuffer().normal),
         alb = ctx.download<glm::vec4>(r.gbuffer().albedo);
    double kept = 0, all = 0;
    for (int p = 0; p < W * H; ++p) {
      glm::vec3 e(0.0f), eAll(0.0f);
      if (pos[p].w > 0) {
        glm::vec3 x(pos[p]), n(nrm[p]);
        for (int k = 0; k < N; ++k) {
          glm::vec3 vx = glm::vec3(raw[3 * k]) - x;
          float d2 = glm::dot(vx, vx), dmin2 = raw[3 * k].w;
          float cp = -glm::dot(glm::vec3(raw[3 * k + 1]), vx), cr = glm::dot(n, vx);
          float g = std::max(cp, 0.0f) * std::max(cr, 0.0f) / (std::max(d2, 1e-20f) * std::max(d2, dmin2));
          eAll += glm::vec3(raw[3 * k + 2]) * g;
          if (d2 * eps < dmin2) e += glm::vec3(raw[3 * k + 2]) * g;
        }
      }
      glm::vec3 expected = glm::vec3(alb[p]) * e * (0.31830988618379067154f * 0.31830988618379067154f);
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(ind.pixels[p * 3 + c], expected[c], 1e-4f * expected[c] + 1e-9f) << "eps " << eps << " pixel " << p;
      kept += e.y;
      all += eAll.y;
    }
    std::printf("splat eps=%g: %.2f %% of the all-pairs irradiance kept (Cornell box, RSM 64, N=%d)\n", eps,
                100.0 * kept / all, N);
  }
}

TEST(Splat, InterleavedEqualsIgiWhenTheCutOffIsBeyondTheScene) {
  // Same sets (VPL k -> set k mod n·m, weights × n·m), same discontinuity filter: the same image.
  Scene s = cornellWithSpot(true);
  auto run = [&](const std::string& tech, std::vector<std::string> sets) {
    Renderer r(test::context(), s, test::smallRenderSettings(tech, 45, 38, std::move(sets)));
    r.renderFrame();
    return r.indirectRadiance();
  };
  Image a = run("igi", {"igi.count=200", "igi.n=3", "igi.m=2"});
  Image b = run("splat", {"splat.count=200", "splat.epsilon=1e-12", "splat.n=3", "splat.m=2"});
  for (size_t i = 0; i < a.pixels.size(); ++i)
    ASSERT_NEAR(b.pixels[i], a.pixels[i], 1e-5f * std::abs(a.pixels[i]) + 1e-9f) << "value " << i;
}
