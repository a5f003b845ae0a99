// Light propagation volume accuracy against the reference path tracer at 128×128 (issue 6), and
// the thin-wall leak measurement. Bounds are stated here and in docs/techniques/lpv.md; where the
// issue's target is not met the bound asserted is the measured value with a small margin, so a
// change that makes things worse fails:
//   - empty Cornell box lit by the downward punctual spot (as the vpl test): `lpv`, one grid of
//     32³ over the box, 32 iterations, lpv.bounces off (the default: the reference holds one
//     bounce; with bounces the LPV adds the orders >= 3, +47 %), against the one-bounce-indirect
//     diffuse reference (256 spp).
//     Asserted: mean indirect radiance within 25 % of the reference (the bound; measured
//     +21.4 %). SSIM printed (0.358 against the converged reference: LPV light stays near the floor).
//   - full Cornell box (blocks), same spot, full image (direct + lpv) vs the full reference:
//     measured SSIM 0.470 against the stored converged reference (4096 spp; 0.422 against an in-test
//     256-spp render); asserted >= 0.44. Issue target
//     0.85: NOT met. It is within reach of one bounce: direct + the converged path-traced one-bounce
//     indirect scores 0.875 (both 4096 spp; 0.70 with a 256-spp one-bounce image, its noise).
//     The LPV's own error: light stays within ~8 cells of the surfaces that reflected it (the box
//     is 32 cells high), so the ceiling quarter of the image gets 0.2 % of its one-bounce light and
//     the floor quarter 2.3x. Also at 16^3 x 64 iterations (light reaches the ceiling): measured
//     0.710 (0.577 against 256 spp), asserted >= 0.67. With lpv.bounces (blocked light reflected,
//     orders >= 3; docs/techniques/lpv.md, "Extensions") at 32³ x 32: measured 0.476, asserted >= 0.45.
//   - Sponza 96×54 with its sun, default 3 cascades of 32³, full image vs the stored converged
//     reference (2048 spp): measured SSIM 0.763, asserted >= 0.72 (it was 0.486 against a 16-spp
//     render: most of that gap was reference noise); direct + path-traced one-bounce scores 0.878
//     (docs/ACCURACY.md); the LPV indirect
//     is 2.3x the one-bounce light (the sunlit floor lights itself). Skipped without media.
//   - thin wall (builtin:thin_wall, 2 cm wall, 6.25 cm cells): indirect light in the dark room B
//     over that in the lit room A, without / with the geometry volume: measured 0.0270 / 0.0048
//     (the reference has none); asserted: the geometry volume removes at least half of the leak,
//     also with lpv.bounces and with lpv.damping (measured: see the printed line and lpv.md).
// The decomposition (direct vs direct reference, one-bounce ceiling, noise, per-region ratios):
// tests/lpv_accuracy_diagnosis_test.cpp and docs/techniques/lpv.md, "Accuracy".
#include <gtest/gtest.h>

#include <cstdio>

#include "accuracy_support.h"
#include "metrics/metrics.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "test_support.h"

using namespace gi;

namespace {

using test::cornellWithSpot;

const std::vector<std::string> kBoxSettings = {"lpv.cascades=0", "lpv.resolution=32"};

double ssimOf(const test::AccuracyPair& p, float exposure) {
  return metrics::ssim(displayTransform(p.reference, exposure), displayTransform(p.raster, exposure)).mean;
}

TEST(LpvAccuracy, EmptyCornellBoxIndirectMeanWithin25Percent) {
  Scene s = cornellWithSpot(false);
  test::AccuracyPair p =
      test::renderAgainstReference(s, "lpv", 128, 128, kBoxSettings, true, ReferenceMode::OneBounce, true,
                                   "cornell_empty_spot_one_bounce_diffuse_128", 256);
  double mr = test::meanOf(p.raster), mp = test::meanOf(p.reference);
  std::printf("empty Cornell box, one-bounce indirect, lpv 32^3 x 32 iterations: mean %.5f vs reference %.5f "
              "(%+.1f %%, bound 25 %%), SSIM %.4f\n", mr, mp, 100.0 * (mr / mp - 1.0), ssimOf(p, s.exposure));
  EXPECT_NEAR(mr / mp, 1.0, 0.25);
}

TEST(LpvAccuracy, FullCornellBoxFullImageSsim) {
  Scene s = cornellWithSpot(true);
  struct Config {
    std::vector<std::string> sets;
    double bound;
  };
  const Config configs[] = {{kBoxSettings, 0.44},
                            {{"lpv.cascades=0", "lpv.resolution=16", "lpv.iterations=64"}, 0.67},
                            {{"lpv.cascades=0", "lpv.resolution=32", "lpv.bounces=true"}, 0.45}};
  for (const Config& c : configs) {
    test::AccuracyPair p = test::renderAgainstReference(s, "lpv", 128, 128, c.sets, false, ReferenceMode::Full, false,
                                                        "cornell_spot_full_128", 256);
    double ssim = ssimOf(p, s.exposure);
    std::printf("Cornell box (blocks), spot, direct + lpv (%s %s) vs full reference: SSIM %.4f (bound %.2f; issue "
                "target 0.85 not met), mean %.5f vs %.5f\n", c.sets[1].c_str(), c.sets.size() > 2 ? c.sets[2].c_str() : "",
                ssim, c.bound, test::meanOf(p.raster), test::meanOf(p.reference));
    EXPECT_GE(ssim, c.bound) << c.sets[1];
  }
}

TEST(LpvAccuracy, SponzaSmallFullImageSsim) {
  std::string why;
  std::optional<Scene> sponza = test::loadSponza(why);
  if (!sponza) GTEST_SKIP() << why;
  const Scene& s = *sponza;
  test::AccuracyPair p = test::renderAgainstReference(s, "lpv", 96, 54, {"rsm.resolution=256"}, false,
                                                      ReferenceMode::Full, false, "sponza_sun_full_96x54", 16);
  double ssim = ssimOf(p, s.exposure);
  std::printf("Sponza 96x54, sun, direct + lpv (3 cascades of 32^3) vs full reference: SSIM %.4f "
              "(bound 0.72; issue target 0.85 not met)\n", ssim);
  EXPECT_GE(ssim, 0.72);
}

// Mean indirect radiance of the columns that see only room B (the image's left half; +x points
// left) over that of the columns that see only room A (the right half).
double leakRatio(const Image& indirect) {
  double a = 0.0, b = 0.0;
  int na = 0, nb = 0, margin = indirect.width / 32;
  for (int y = 0; y < indirect.height; ++y)
    for (int x = 0; x < indirect.width; ++x) {
      const float* px = indirect.at(x, y);
      double v = (px[0] + px[1] + px[2]) / 3.0;
      if (x >= indirect.width / 2 + margin) a += v, ++na;
      if (x < indirect.width / 2 - margin) b += v, ++nb;
    }
  return (b / nb) / (a / na);
}

TEST(LpvLeak, ThinWallWithAndWithoutGeometryVolume) {
  Scene s = makeBuiltinScene("thin_wall");
  auto leakWith = [&](const std::vector<std::string>& extra) {
    RenderSettings rs;
    rs.width = 128;
    rs.height = 64;
    rs.technique = "lpv";
    rs.sets = {"lpv.cascades=0", "lpv.resolution=32"};
    rs.sets.insert(rs.sets.end(), extra.begin(), extra.end());
    Renderer r(test::context(), s, rs);
    r.renderFrame();
    Image indirect = r.indirectRadiance(), direct = r.directRadiance();
    // The direct light stays in room A (shadow maps), so all light in room B is leak.
    EXPECT_LT(leakRatio(direct), 1e-6);
    return leakRatio(indirect);
  };
  double open = leakWith({"lpv.occlusion=0"}), blocked = leakWith({}), bounces = leakWith({"lpv.bounces=true"}),
         damping = leakWith({"lpv.damping=true"});
  std::printf("thin wall (2 cm, cells 6.25 cm), lpv 32^3: room B / room A indirect = %.4f without the geometry "
              "volume, %.4f with it, %.4f with it and lpv.bounces, %.4f with it and lpv.damping (reference: 0)\n",
              open, blocked, bounces, damping);
  EXPECT_GT(open, 0.0);  // the leak is there to be measured, not hidden
  EXPECT_LT(blocked, 0.5 * open);
  // The extensions keep the geometry volume's effect (bounces reflect the blocked light back into
  // room A; damping acts at the lookup only).
  EXPECT_LT(bounces, 0.5 * open);
  EXPECT_LT(damping, 0.5 * open);
}

}  // namespace
