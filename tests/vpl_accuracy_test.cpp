// Instant-radiosity accuracy against the reference path tracer at 128×128 (issue 4). Bounds are
// stated here and in docs/techniques/vpl.md, next to the targets that are NOT yet met:
//   - empty Cornell box (convex: every point sees every other, so "no visibility" is exact) lit by
//     a downward punctual spot light under the ceiling (the RSM and the path tracer see the same
//     light): `vpl`, N = 1024, against the one-bounce-indirect reference (k = 2, diffuse only,
//     since the RSM and the VPL receivers are Lambertian) at 1024 spp.
//     Asserted: mean radiance within 5 % (the bound; measured +0.46 %) and SSIM ≥ 0.90 on
//     the display-transformed indirect image (measured 0.914). The issue asks SSIM ≥ 0.95: with a
//     4096-spp reference (66 s, too slow for CI) we measured 0.947; what remains is reference noise
//     and the VPL singularities (bright dots where floor meets wall, d_min = 0.5 RSM texel).
//   - full Cornell box (blocks) under the same spot, full image (direct + `vpl` indirect) against
//     the full reference (1024 spp): asserted SSIM ≥ 0.80 (measured 0.843). The issue asks 0.9;
//     one-bounce VPLs miss the higher bounces (image mean 0.149 vs 0.205), so it is not met.
//   - Sponza (small, 96×54) with its sun, full image, 16-spp reference: measured and printed, with
//     only a sanity bound (SSIM ≥ 0.45; measured 0.517); the 0.9 is not verified (the
//     16-spp reference is too noisy to judge, a converged one too slow for CI). Skipped without media.
// The rasterized images are rendered at 2×2 the size and box-filtered down (the path tracer
// integrates over each pixel's area). References come from tests/reference_store.h (stored, converged,
// re-validated each run); GI_TEST_SAVE_IMAGES=<dir> writes the images.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "metrics/metrics.h"
#include "reference/path_tracer.h"
#include "render/renderer.h"
#include "render/views.h"
#include "scene/cornell_box.h"
#include "scene/media_path.h"
#include "scene/scene_loader.h"
#include "reference_store.h"
#include "test_support.h"

using namespace gi;

namespace {

Image boxDown(const Image& big, int f) {
  Image out(big.width / f, big.height / f, big.channels);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < big.channels; ++c) {
        double s = 0;
        for (int j = 0; j < f; ++j)
          for (int i = 0; i < f; ++i) s += big.at(x * f + i, y * f + j)[c];
        out.at(x, y)[c] = float(s / (f * f));
      }
  return out;
}

double meanOf(const Image& im) {
  double s = 0;
  for (size_t i = 0; i < im.pixelCount(); ++i)
    for (int c = 0; c < 3; ++c) s += im.pixels[i * im.channels + c];
  return s / (3.0 * im.pixelCount());
}

struct Pair {
  Image raster, reference;
  Camera camera;
};

Pair renderPair(const Scene& scene, int W, int H, std::vector<std::string> sets, bool indirectOnly, ReferenceMode mode,
                bool diffuseOnly, const std::string& referenceKey, int fallbackSpp) {
  const int kSuper = 2;
  RenderSettings rs;
  rs.width = W * kSuper;
  rs.height = H * kSuper;
  rs.technique = "vpl";
  rs.sets = std::move(sets);
  Renderer r(test::context(), scene, rs);
  r.renderFrame();
  Pair p;
  p.raster = boxDown(indirectOnly ? r.indirectRadiance() : r.radiance(), kSuper);
  p.camera = r.camera();
  PathTracerOptions o;
  o.width = W;
  o.height = H;
  o.mode = mode;
  o.diffuseOnly = diffuseOnly;
  p.reference = test::convergedReference(referenceKey, scene, makeCameraView(r.camera(), W, H), o, fallbackSpp);
  if (const char* dir = std::getenv("GI_TEST_SAVE_IMAGES")) {
    std::string base = std::string(dir) + "/vpl_" + scene.name + (indirectOnly ? "_indirect" : "_full");
    writeImage(base + "_raster.exr", p.raster);
    writeImage(base + "_reference.exr", p.reference);
    writeImage(base + "_raster.png", displayTransform(p.raster, scene.exposure));
    writeImage(base + "_reference.png", displayTransform(p.reference, scene.exposure));
  }
  return p;
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
              "SSIM %.4f (bound 0.90; issue target 0.95)\n", mr, mp, 100.0 * (mr / mp - 1.0), ssim);
  EXPECT_NEAR(mr / mp, 1.0, 0.05);
  EXPECT_GE(ssim, 0.90);
}

TEST(VplAccuracy, FullCornellBoxFullImageSsim) {
  CornellOptions o;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  o.spotLight->intensity = glm::vec3(1.2f, 1.0f, 0.8f);
  Scene s = makeCornellBox(o);
  Pair p = renderPair(s, 128, 128, {"vpl.count=1024"}, false, ReferenceMode::Full, false, "cornell_spot_full_128", 1024);
  double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
  std::printf("Cornell box (blocks), spot light, direct + vpl N=1024 vs full reference: SSIM %.4f (bound 0.80; issue target 0.9), "
              "mean %.5f vs %.5f\n", ssim, meanOf(p.raster), meanOf(p.reference));
  EXPECT_GE(ssim, 0.80);
}

TEST(VplAccuracy, SponzaSmallFullImageSsim) {
  if (!findMediaDir("")) GTEST_SKIP() << "Sponza media not found (docs/SCENES.md)";
  Scene s;
  try {
    s = loadScene(std::string(GI_SOURCE_DIR) + "/scenes/sponza.json", "");
  } catch (const std::exception& e) {
    GTEST_SKIP() << "Sponza not loadable: " << e.what();
  }
  Pair p = renderPair(s, 96, 54, {"vpl.count=256", "rsm.resolution=256"}, false, ReferenceMode::Full, false,
                      "sponza_sun_full_96x54", 16);
  double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
  std::printf("Sponza 96x54, sun, direct + vpl N=256 vs full reference (16 spp): SSIM %.4f (sanity bound 0.45; issue target 0.9 not verified)\n", ssim);
  EXPECT_GE(ssim, 0.45);
}
