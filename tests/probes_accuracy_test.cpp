// Light-field probes accuracy against the reference path tracer (issue 8). Bounds are stated here
// and in docs/techniques/probes.md; numbers and the seed's findings in docs/results/probes.md.
//   - empty Cornell box lit by the downward punctual spot (as the vpl/vct accuracy tests), 128×128:
//     `probes` without multi-bounce (one bounce) against the one-bounce-indirect diffuse reference.
//     Asserted: mean indirect radiance within 10 % (measured +4.1 %) and SSIM ≥ 0.95 (measured 0.982).
//   - Cornell box with its blocks, same spot, full image (direct + probes, multi-bounce) against the
//     full reference: asserted SSIM ≥ 0.85, the target (measured 0.936).
//   - Sponza (small, 96×54) with its sun, full image: asserted SSIM ≥ 0.79 (measured 0.814 with
//     the default DDGI weighting since 3 Dec's fitted sun shadow map, 0.811 before; 0.775 with seed 004's eq. 7; the 0.85 is
//     NOT met at the seed's grid, docs/results/probes.md). Skipped without media.
//   - the same Sponza frame with a denser grid, 32×16×32 probes (1.6 × 1.3 × 1.0 m apart instead of
//     6.4 × 5.3 × 3.9 m), everything else the default: asserted SSIM ≥ 0.85, the target
//     (measured 0.863; 0.860 before the fitted shadow map). The grid is the only change, so this says
//     at what probe spacing the technique reaches the target at this size; at 640×480 the same
//     grid scores 0.74, and against 1024-spp references at 320×240 an exact diffuse indirect term
//     scores 0.80 (docs/results/probes.md, "Probe density"; docs/ACCURACY.md). Skipped without media.
// References: the stored converged images (tests/reference_store.h).
// All use the static full rebuild (probes.update=static), so one frame shows the converged field.
#include <gtest/gtest.h>

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "accuracy_support.h"
#include "metrics/metrics.h"
#include "test_support.h"

using namespace gi;
using test::cornellWithSpot;
using test::meanOf;

namespace {

double displaySsim(const test::AccuracyPair& p, const Scene& s) {
  return metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
}

// Sponza 96×54 with its sun, static rebuild (8 × 128 rays), full image against the stored converged
// reference; `grid` adds probes.grid_* settings (none: the automatic 8×4×8).
test::AccuracyPair sponzaAgainstReference(const Scene& sponza, std::vector<std::string> grid) {
  std::vector<std::string> sets = {"probes.update=static", "probes.rebuild_updates=8", "probes.rays=128",
                                   "shadow.resolution=1024"};
  sets.insert(sets.end(), grid.begin(), grid.end());
  return test::renderAgainstReference(sponza, "probes", 96, 54, sets, false, ReferenceMode::Full, false,
                                      "sponza_sun_full_96x54", 16);
}

}  // namespace

TEST(ProbesAccuracy, EmptyCornellBoxOneBounceMean) {
  Scene s = cornellWithSpot(false);
  test::AccuracyPair p = test::renderAgainstReference(
      s, "probes", 128, 128, {"probes.update=static", "probes.rebuild_updates=16", "probes.rays=128", "probes.multibounce=0"},
      true, ReferenceMode::OneBounce, true, "cornell_empty_spot_one_bounce_diffuse_128", 512);
  double mr = meanOf(p.raster), mp = meanOf(p.reference);
  std::printf("empty Cornell box, one-bounce indirect, probes 8x8x4 (16 x 128 rays): mean %.5f vs reference %.5f "
              "(%+.1f %%, bound 10 %%), SSIM %.4f (bound 0.95)\n", mr, mp, 100.0 * (mr / mp - 1.0), displaySsim(p, s));
  EXPECT_NEAR(mr / mp, 1.0, 0.10);
  EXPECT_GE(displaySsim(p, s), 0.95);
}

TEST(ProbesAccuracy, FullCornellBoxFullImageSsim) {
  Scene s = cornellWithSpot(true);
  test::AccuracyPair p = test::renderAgainstReference(
      s, "probes", 128, 128, {"probes.update=static", "probes.rebuild_updates=16", "probes.rays=128"}, false,
      ReferenceMode::Full, false, "cornell_spot_full_128", 512);
  double ssim = displaySsim(p, s);
  std::printf("Cornell box (blocks), spot light, direct + probes 8x8x4 (multi-bounce) vs full reference: SSIM %.4f "
              "(bound 0.85, the issue's target), mean %.5f vs %.5f\n", ssim, meanOf(p.raster), meanOf(p.reference));
  EXPECT_GE(ssim, 0.85);
}

TEST(ProbesAccuracy, SponzaSmallFullImageSsim) {
  std::string why;
  std::optional<Scene> sponza = test::loadSponza(why);
  if (!sponza) GTEST_SKIP() << why;
  const Scene& s = *sponza;
  test::AccuracyPair p = sponzaAgainstReference(s, {});
  double ssim = displaySsim(p, s);
  std::printf("Sponza 96x54, sun, direct + probes 8x8x4 vs full reference: SSIM %.4f (bound 0.79; issue "
              "target 0.85 not met), mean %.5f vs %.5f\n", ssim,
              meanOf(p.raster), meanOf(p.reference));
  EXPECT_GE(ssim, 0.79);
}

TEST(ProbesAccuracy, SponzaDenseGridFullImageSsim) {
  std::string why;
  std::optional<Scene> sponza = test::loadSponza(why);
  if (!sponza) GTEST_SKIP() << why;
  const Scene& s = *sponza;
  test::AccuracyPair p = sponzaAgainstReference(s, {"probes.grid_x=32", "probes.grid_y=16", "probes.grid_z=32"});
  double ssim = displaySsim(p, s);
  std::printf("Sponza 96x54, sun, direct + probes 32x16x32 vs full reference: SSIM %.4f (bound 0.85, the issue's "
              "target), mean %.5f vs %.5f\n", ssim, meanOf(p.raster), meanOf(p.reference));
  EXPECT_GE(ssim, 0.85);
}
