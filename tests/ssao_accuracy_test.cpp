// `ssao` alone (bleeding auto = on: the screen-space one-bounce colour bleeding of seed 003
// eq. 3.5, ALGORITHMS.md §6, docs/techniques/ssao.md) against the reference path tracer.
//   - empty Cornell box lit by the downward punctual spot (as the vpl/lpv/probes/rsm accuracy
//     tests), 128×128 (rendered at 256×256 and box-filtered down, tests/accuracy_support.h),
//     indirect only, 16 samples, against the stored one-bounce diffuse reference
//     `cornell_empty_spot_one_bounce_diffuse_128`.
//     Why the empty box: every surface the spot lights (the senders) is on screen and unhidden
//     from the camera, so what is left of the error is the method's own — only senders within the
//     hemisphere radius R of a receiver contribute, and only with the radiance the camera sees on
//     them — not the screen-space visibility limit that blocks (hiding parts of the lit floor and
//     their own back faces) would add.
// The technique is far from the reference by design (near-field bleeding only, within R of the
// receiver), so the bounds are the measured values (2026-12-02, PoCL, GI_VW 16/8/1 alike) with a
// stated margin: the test documents the numbers and fails when a change moves them (or switches
// the bleeding off: the mean ratio is then 0, SSIM 0.0038, relMSE 0.2911). Measured / asserted:
//   - default R (5 % of the scene diagonal, 0.048 m): mean ratio 0.0168 (−98.3 %) / within ±10 %
//     of that; SSIM 0.0192 / >= 0.015; relMSE 0.2832 / <= 0.287.
//   - R = 0.3 m (about half the 0.55 m box: floor and walls exchange light): mean ratio 0.1160
//     (−88.4 %) / ±10 %; SSIM 0.1597 / >= 0.15; relMSE 0.2404 / <= 0.245.
// The ratio must move in neither direction unnoticed: an improvement updates the numbers here and
// in docs/techniques/ssao.md ("Accuracy").
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "accuracy_support.h"
#include "metrics/metrics.h"
#include "test_support.h"

using namespace gi;

TEST(SsaoAccuracy, CornellBoxColourBleedingAgainstOneBounceReference) {
  Scene s = test::cornellWithSpot(false);
  struct Config {
    const char* name;
    std::vector<std::string> sets;
    double measuredRatio, minSsim, maxRelMse;
  };
  const Config configs[] = {
      {"default R (0.048 m)", {"ssao.bleeding=on"}, 0.0168, 0.015, 0.287},
      {"R = 0.3 m", {"ssao.bleeding=on", "ssao.radius=0.3"}, 0.1160, 0.15, 0.245},
  };
  for (const Config& c : configs) {
    test::AccuracyPair p = test::renderAgainstReference(s, "ssao", 128, 128, c.sets, true, ReferenceMode::OneBounce,
                                                        true, "cornell_empty_spot_one_bounce_diffuse_128", 1024);
    double mr = test::meanOf(p.raster), mp = test::meanOf(p.reference);
    double ratio = mr / mp;
    double ssim =
        metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
    double relMse = metrics::relMse(p.reference, p.raster);
    std::printf("empty Cornell box, one-bounce indirect, ssao colour bleeding, 16 samples, %s: mean %.5f vs "
                "reference %.5f (ratio %.4f, %+.1f %%; bound %.4f +- 10 %%), SSIM %.4f (bound >= %.3f), relMSE %.4f "
                "(bound <= %.3f)\n",
                c.name, mr, mp, ratio, 100.0 * (ratio - 1.0), c.measuredRatio, ssim, c.minSsim, relMse, c.maxRelMse);
    EXPECT_NEAR(ratio, c.measuredRatio, 0.10 * c.measuredRatio) << c.name;
    EXPECT_GE(ssim, c.minSsim) << c.name;
    EXPECT_LE(relMse, c.maxRelMse) << c.name;
  }
}
