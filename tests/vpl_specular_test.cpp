// `vpl.specular` (kernels/gi/vpl/vpl_brdf_gather.cl; docs/techniques/vpl.md, "Specular receivers"):
// the gather with the receivers' full BRDF. Its image minus the diffuse gather's is the GGX lobe
// lit by the VPLs: against a host mirror of that formula on a small image of the Cornell box made
// glossy (roughness 0.3, F0 0.04 and a metallic block), with bounces, with and without visibility
// rays; it only adds light, and nothing on the background.
#include <gtest/gtest.h>

#include <cstring>

#include "accuracy_support.h"
#include "vpl_bounce_support.h"
#include "gi/vpl/vpl_lights.h"
#include "render/renderer.h"
#include "test_support.h"

using namespace gi;

TEST(VplSpecular, AddsTheHostGgxSumOverTheVpls) {
  cl::Context& ctx = test::context();
  Scene s = test::cornellWithSpot(true);
  for (GiMaterial& m : s.materials) m.roughness = 0.3f;
  s.materials.back().metallic = 1.0f;  // one fully specular-coloured material
  const int W = 23, H = 19, N = 48;
  for (bool rays : {false, true}) {
    std::vector<std::string> sets = {"vpl.count=" + std::to_string(N), "vpl.bounces=1"};
    if (rays) sets.push_back("vpl.visibility=rays");
    Renderer diffuse(ctx, s, test::smallRenderSettings("vpl", W, H, sets));
    diffuse.renderFrame();
    sets.push_back("vpl.specular=true");
    Renderer r(ctx, s, test::smallRenderSettings("vpl", W, H, sets));
    r.renderFrame();
    Image a = diffuse.indirectRadiance(), b = r.indirectRadiance();
    std::vector<HostVpl> vpls = test::generatedVpls(ctx, s, r, N, 1);  // the same settings' list
    const GBuffer& g = r.gbuffer();
    auto pos = ctx.download<glm::vec4>(g.position), nrm = ctx.download<glm::vec4>(g.normal),
         spec = ctx.download<glm::vec4>(g.specular);
    ctx.profiler().discard();
    glm::vec3 eye(g.view.eye[0], g.view.eye[1], g.view.eye[2]);
    int glossy = 0, compared = 0;
    for (int p = 0; p < W * H; ++p) {
      glm::vec3 d(b.pixels[size_t(p) * 3] - a.pixels[size_t(p) * 3], b.pixels[size_t(p) * 3 + 1] - a.pixels[size_t(p) * 3 + 1],
                  b.pixels[size_t(p) * 3 + 2] - a.pixels[size_t(p) * 3 + 2]);
      // The diffuse terms agree to float rounding (same sum, other kernel).
      glm::vec3 eps(1e-5f * a.pixels[size_t(p) * 3], 1e-5f * a.pixels[size_t(p) * 3 + 1], 1e-5f * a.pixels[size_t(p) * 3 + 2]);
      for (int c = 0; c < 3; ++c) ASSERT_GE(d[c], -eps[c] - 1e-9f) << "pixel " << p;
      if (pos[p].w <= 0) {
        EXPECT_EQ(d, glm::vec3(0.0f));
        continue;
      }
      glm::vec3 x(pos[p]);
      if (rays) {  // the host has no visibility: compare only where the pass saw no occluder at all
        glm::vec3 all = hostSpecularRadiance(vpls, x, glm::vec3(nrm[p]), glm::normalize(eye - x), glm::vec3(spec[p]),
                                             spec[p].w);
        EXPECT_LE(d.y, all.y * (1.0f + 1e-4f) + eps.y + 1e-9f) << "pixel " << p << ": rays added light";
        continue;
      }
      glm::vec3 expected =
          hostSpecularRadiance(vpls, x, glm::vec3(nrm[p]), glm::normalize(eye - x), glm::vec3(spec[p]), spec[p].w);
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(d[c], expected[c], 2e-4f * expected[c] + eps[c] + 1e-9f) << "pixel " << p;
      ++compared;
      glossy += expected.y > 1e-3f * a.pixels[size_t(p) * 3 + 1];
    }
    if (!rays) {
      EXPECT_GT(compared, W * H / 2);
      EXPECT_GT(glossy, compared / 2) << "the glossy lobe should light most pixels";
    }
  }
}
