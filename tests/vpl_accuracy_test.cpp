// Instant-radiosity accuracy against the reference path tracer at 128×128 (issue 4). Bounds are
// stated here and in docs/techniques/vpl.md. References are the stored converged images of
// tests/reference_store.h; the technique's image is deterministic, so the measured values repeat.
//   - empty Cornell box (convex: every point sees every other, so "no visibility" is exact) lit by
//     a downward punctual spot light under the ceiling (the RSM and the path tracer see the same
//     light): `vpl`, N = 1024, against the one-bounce-indirect reference (k = 2, diffuse only,
//     since the RSM and the VPL receivers are Lambertian), 16384 spp.
//     Asserted = the bounds: mean radiance within 5 % (measured +0.39 %) and SSIM ≥ 0.95 on
//     the display-transformed indirect image (measured 0.9557).
//   - full Cornell box (blocks) under the same spot, full image (direct + `vpl` indirect) against
//     the full reference (4096 spp): asserted SSIM ≥ 0.90 = the bound (measured 0.9039;
//     one-bounce VPLs miss the higher bounces: image mean 0.149 vs 0.205).
//   - the same box with multi-bounce VPLs (vpl.bounces=6, Keller's further generations) and
//     visibility rays: asserted SSIM ≥ 0.91 (measured 0.9214) and mean within 10 % of the
//     reference (measured −6.8 %: the GGX lobe of the indirect light, which VPLs do not carry).
//   - Sponza (small, 96×54) with its sun, full image, 2048-spp reference, `vpl` N = 1024 with 3
//     further generations (vpl.bounces=3) and visibility rays: the diffuse gather alone asserted
//     ≥ 0.88 (measured 0.8930; 0.8945 before 3 Dec's fitted sun shadow map; an exact diffuse
//     indirect term on our direct pass scores 0.892, so no diffuse gather reaches 0.9); with the
//     receivers' GGX lobe (vpl.specular=true) asserted ≥ 0.90 = the target (measured
//     0.9177; 0.9169 before). One-bounce `vpl` N = 256 scored 0.791
//     (docs/techniques/vpl.md). Skipped without media.
// The rasterized images are rendered at 2×2 the size and box-filtered down (the path tracer
// integrates over each pixel's area). References come from tests/reference_store.h (stored, converged,
// re-validated each run); GI_TEST_SAVE_IMAGES=<dir> writes the images (tests/accuracy_support.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "metrics/metrics.h"
#include "reference/path_tracer.h"
#include "render/renderer.h"
#include "render/views.h"
#include "scene/cornell_box.h"
#include "scene/media_path.h"
#include "scene/scene_loader.h"
#include "accuracy_support.h"
#include "test_support.h"

using namespace gi;

namespace {

using Pair = test::AccuracyPair;
using test::meanOf;

Pair renderPair(const Scene& scene, int W, int H, std::vector<std::string> sets, bool indirectOnly, ReferenceMode mode,
                bool diffuseOnly, const std::string& referenceKey, int fallbackSpp) {
  return test::renderAgainstReference(scene, "vpl", W, H, std::move(sets), indirectOnly, mode, diffuseOnly,
                                      referenceKey, fallbackSpp);
}

}  // namespace

TEST(VplAccuracy, EmptyCornellBoxOneBounceMatchesPathTracer) {
  CornellOptions o;
  o.withBlocks = false;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  o.spotLight->intensity = glm::vec3(1.2f, 1.0f, 0.8f);
  Scene s = makeCornellBox(o);
  Pair p = renderPair(s, 128, 128, {"vpl.count=1024"}, true, ReferenceMode::OneBounce, true,
                      "cornell_empty_spot_one_bounce_diffuse_128", 1024);
  double mr = meanOf(p.raster), mp = meanOf(p.reference);
  double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
  std::printf("empty Cornell box, one-bounce indirect, vpl N=1024: mean %.5f vs reference %.5f (%+.2f %%, bound 5 %%), "
              "SSIM %.4f (bound 0.95 = issue target)\n", mr, mp, 100.0 * (mr / mp - 1.0), ssim);
  EXPECT_NEAR(mr / mp, 1.0, 0.05);
  EXPECT_GE(ssim, 0.95);
}

TEST(VplAccuracy, FullCornellBoxFullImageSsim) {
  CornellOptions o;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  o.spotLight->intensity = glm::vec3(1.2f, 1.0f, 0.8f);
  Scene s = makeCornellBox(o);
  Pair p = renderPair(s, 128, 128, {"vpl.count=1024"}, false, ReferenceMode::Full, false, "cornell_spot_full_128", 1024);
  double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
  std::printf("Cornell box (blocks), spot light, direct + vpl N=1024 vs full reference: SSIM %.4f (bound 0.90 = issue target), "
              "mean %.5f vs %.5f\n", ssim, meanOf(p.raster), meanOf(p.reference));
  EXPECT_GE(ssim, 0.90);
}

// Issue 5: what VPL visibility does to the same comparison. One-bounce VPLs still miss the higher
// bounces; rays remove the light the blocks occlude (over-lit without them).
TEST(VplAccuracy, FullCornellBoxWithVisibilityRays) {
  Scene s = test::cornellWithSpot(true);
  Pair none = renderPair(s, 128, 128, {"vpl.count=1024"}, false, ReferenceMode::Full, false, "cornell_spot_full_128", 1024);
  Pair rays = renderPair(s, 128, 128, {"vpl.count=1024", "vpl.visibility=rays"}, false, ReferenceMode::Full, false,
                         "cornell_spot_full_128", 1024);
  auto ssimOf = [&](const Pair& p) {
    return metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
  };
  double a = ssimOf(none), b = ssimOf(rays);
  std::printf("Cornell box (blocks), spot light, direct + vpl N=1024 vs full reference: SSIM %.4f without visibility, "
              "%.4f with vpl.visibility=rays; mean %.5f / %.5f vs reference %.5f\n",
              a, b, meanOf(none.raster), meanOf(rays.raster), meanOf(none.reference));
  EXPECT_GE(b, 0.80);
  EXPECT_LT(meanOf(rays.raster), meanOf(none.raster));
  // Against the one-bounce reference (what VPLs compute), the indirect image alone.
  Pair noneOne = renderPair(s, 128, 128, {"vpl.count=1024"}, true, ReferenceMode::OneBounce, true,
                            "cornell_spot_one_bounce_diffuse_128", 256);
  Pair raysOne = renderPair(s, 128, 128, {"vpl.count=1024", "vpl.visibility=rays"}, true, ReferenceMode::OneBounce, true,
                            "cornell_spot_one_bounce_diffuse_128", 256);
  auto relRms = [](const Image& a, const Image& ref) {
    double num = 0, den = 0;
    for (size_t i = 0; i < ref.pixels.size(); ++i) {
      num += double(a.pixels[i] - ref.pixels[i]) * (a.pixels[i] - ref.pixels[i]);
      den += double(ref.pixels[i]) * ref.pixels[i];
    }
    return std::sqrt(num / den);
  };
  double ea = relRms(noneOne.raster, noneOne.reference), eb = relRms(raysOne.raster, raysOne.reference);
  std::printf("same box, indirect vs one-bounce reference: relative RMS %.4f without visibility, %.4f with rays; "
              "SSIM %.4f / %.4f; mean %.5f / %.5f vs %.5f\n", ea, eb, ssimOf(noneOne), ssimOf(raysOne),
              meanOf(noneOne.raster), meanOf(raysOne.raster), meanOf(noneOne.reference));
  EXPECT_LT(eb, ea) << "visibility must bring one-bounce VPLs closer to the one-bounce path tracer";
}

// Keller's multi-bounce VPLs fill in the light of order ≥ 3 that one-bounce VPLs miss.
TEST(VplAccuracy, FullCornellBoxMultiBounceWithVisibilityRays) {
  Scene s = test::cornellWithSpot(true);
  Pair p = renderPair(s, 128, 128, {"vpl.count=1024", "vpl.bounces=6", "vpl.visibility=rays"}, false,
                      ReferenceMode::Full, false, "cornell_spot_full_128", 1024);
  double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
  double mr = meanOf(p.raster), mp = meanOf(p.reference);
  std::printf("Cornell box (blocks), spot light, direct + vpl N=1024, 6 further generations, rays vs full reference: "
              "SSIM %.4f (bound 0.91), mean %.5f vs %.5f (%+.1f %%, bound 10 %%; one bounce: 0.14051)\n",
              ssim, mr, mp, 100.0 * (mr / mp - 1.0));
  EXPECT_GE(ssim, 0.91);
  EXPECT_NEAR(mr / mp, 1.0, 0.10);
}

TEST(VplAccuracy, SponzaSmallFullImageSsim) {
  std::string why;
  std::optional<Scene> sponza = test::loadSponza(why);
  if (!sponza) GTEST_SKIP() << why;
  const Scene& s = *sponza;
  std::vector<std::string> multi = {"vpl.count=1024", "vpl.bounces=3", "vpl.visibility=rays"};
  Pair p = renderPair(s, 96, 54, multi, false, ReferenceMode::Full, false, "sponza_sun_full_96x54", 16);
  auto ssimOf = [&](const Image& raster) {
    return metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(raster, s.exposure)).mean;
  };
  double diffuse = ssimOf(p.raster);
  // The same frame with the receivers' GGX lobe, against the same (already validated) reference.
  multi.push_back("vpl.specular=true");
  RenderSettings rs;
  rs.width = 2 * 96;
  rs.height = 2 * 54;
  rs.technique = "vpl";
  rs.sets = multi;
  Renderer r(test::context(), s, rs);
  r.renderFrame();
  double glossy = ssimOf(test::boxDown(r.radiance(), 2));
  std::printf("Sponza 96x54, sun, direct + vpl N=1024, 3 further generations, rays vs full reference: SSIM %.4f "
              "(bound 0.88; diffuse-indirect ceiling 0.892), with vpl.specular: %.4f (bound 0.90 = issue target)\n",
              diffuse, glossy);
  EXPECT_GE(diffuse, 0.88);
  EXPECT_GE(glossy, 0.90);
}

// `igi` on the same full Cornell box: the interleaved gather with the box discontinuity filter
// (default) and with the separable one (the thesis's form), 4×4 and 8×8, N = 1024. Asserted: 4×4
// ≥ 0.90, the bound for the full image (measured 0.9024 box, 0.9023 separable); 8×8 ≥ 0.88
// (measured 0.8921 / 0.8920: an 8×8 window at 128×128 blurs the indirect light over 1/16 of the
// image); the separable filter within 0.002 SSIM of the box one (docs/techniques/igi.md).
TEST(IgiAccuracy, FullCornellBoxBoxAndSeparableFilters) {
  Scene s = test::cornellWithSpot(true);
  double box[2] = {0, 0};
  int k = 0;
  for (const char* pattern : {"4", "8"}) {
    for (const char* filter : {"box", "separable"}) {
      Pair p = test::renderAgainstReference(s, "igi", 128, 128,
                                            {"igi.count=1024", std::string("igi.n=") + pattern,
                                             std::string("igi.m=") + pattern, std::string("igi.filter=") + filter},
                                            false, ReferenceMode::Full, false, "cornell_spot_full_128", 1024);
      double ssim =
          metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
      std::printf("Cornell box (blocks), spot, direct + igi %sx%s N=1024, %s filter vs full reference: SSIM %.4f\n",
                  pattern, pattern, filter, ssim);
      EXPECT_GE(ssim, pattern == std::string("4") ? 0.90 : 0.88) << pattern << "x" << pattern << " " << filter;
      if (filter == std::string("box")) box[k] = ssim;
      else EXPECT_NEAR(ssim, box[k], 0.002) << pattern << "x" << pattern;
    }
    ++k;
  }
}
