// Voxel cone tracing accuracy against the reference path tracer at 128×128 (issue 7). Bounds are
// stated here and in docs/techniques/vct.md (which also has the error analysis):
//   - empty Cornell box lit by the downward punctual spot light (as the vpl accuracy test): `vct`
//     diffuse only (no specular cone) against the one-bounce-indirect diffuse reference (stored
//     converged image when present, reference_store.h; else 512 spp in the test).
//     Asserted: mean indirect radiance within 25 % (the bound; measured −8.7 %).
//   - full Cornell box (blocks), same spot, full image (direct + vct with 4 bounces) against the
//     full reference (stored, 4096 spp): measured SSIM 0.783 (0.789 with the point-sampled injection
//     visibility used before 3 Dec), asserted ≥ 0.75 (against the old
//     in-test 512-spp render it was 0.688: a 512-spp reference itself scores only 0.81). The issue
//     asks 0.85: NOT met. Measured why: the direct part is right (direct mean −0.9 %; raster
//     direct + reference indirect scores 0.996); the indirect mean is −31.7 %, and its shape is
//     wrong through self-illumination (lit floor +134 %) and self-occlusion (ceiling −77 %) of the
//     wide cones, which sample coarse voxels containing the surface they start from.
//   - Sponza (small, 96×54) with its sun, 64³, 1 bounce, full image against the stored converged
//     reference sponza_sun_full_96x54: measured SSIM 0.737 (0.707 before the injection's
//     visibility over the voxel's footprint, 3 Dec), asserted ≥ 0.65; the 0.85 is
//     NOT met (sunlit floor lights itself, +215 % indirect; docs/techniques/vct.md). Skipped
//     without media.
//   - the thin-wall leak (builtin:thin_wall): the indirect light in the dark room B (reference:
//     none) as a fraction of that in the lit room A, isotropic and anisotropic mips, measured and
//     bounded.
//   - the same four with directional voxels (vct.voxels=directional / directional_slab), measured
//     and bounded (docs/techniques/vct.md, Accuracy point 8).
#include <gtest/gtest.h>

#include <cstdio>
#include <optional>

#include "accuracy_support.h"
#include "metrics/metrics.h"
#include "render/renderer.h"
#include "scene/thin_wall.h"
#include "test_support.h"

using namespace gi;
using test::cornellWithSpot;
using test::meanOf;

TEST(VctAccuracy, EmptyCornellBoxOneBounceMean) {
  Scene s = cornellWithSpot(false);
  test::AccuracyPair p = test::renderAgainstReference(s, "vct", 128, 128, {"vct.resolution=64", "vct.specular=0"}, true,
                                                      ReferenceMode::OneBounce, true,
                                                      "cornell_empty_spot_one_bounce_diffuse_128", 512);
  double mr = meanOf(p.raster), mp = meanOf(p.reference);
  double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
  std::printf("empty Cornell box, one-bounce indirect, vct 64^3: mean %.5f vs reference %.5f (%+.1f %%, bound 25 %%), "
              "SSIM %.4f\n", mr, mp, 100.0 * (mr / mp - 1.0), ssim);
  EXPECT_NEAR(mr / mp, 1.0, 0.25);
}

TEST(VctAccuracy, FullCornellBoxFullImageSsim) {
  Scene s = cornellWithSpot(true);
  test::AccuracyPair p = test::renderAgainstReference(s, "vct", 128, 128, {"vct.resolution=64", "vct.bounces=4"},
                                                      false, ReferenceMode::Full, false, "cornell_spot_full_128", 512);
  double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
  std::printf("Cornell box (blocks), spot light, direct + vct 64^3 (4 bounces) vs full reference: SSIM %.4f "
              "(bound 0.75; issue target 0.85), mean %.5f vs %.5f\n", ssim, meanOf(p.raster), meanOf(p.reference));
  EXPECT_GE(ssim, 0.75);
}

TEST(VctAccuracy, SponzaSmallFullImageSsim) {
  std::string why;
  std::optional<Scene> sponza = test::loadSponza(why);
  if (!sponza) GTEST_SKIP() << why;
  const Scene& s = *sponza;
  test::AccuracyPair p = test::renderAgainstReference(s, "vct", 96, 54, {"vct.resolution=64", "shadow.resolution=1024"},
                                                      false, ReferenceMode::Full, false, "sponza_sun_full_96x54", 16);
  double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
  std::printf("Sponza 96x54, sun, direct + vct 64^3 vs full reference: SSIM %.4f (bound 0.65; issue target 0.85), "
              "mean %.5f vs %.5f\n",
              ssim, meanOf(p.raster), meanOf(p.reference));
  EXPECT_GE(ssim, 0.65);
}

namespace {

// Mean indirect radiance of the thin-wall scene's camera image over room B (the left part of the
// image) and room A (the right part), leaving out the columns around the wall.
std::pair<double, double> thinWallIndirect(const Scene& s, std::vector<std::string> sets) {
  RenderSettings rs;
  rs.width = 128;
  rs.height = 64;
  rs.technique = "vct";
  rs.sets = std::move(sets);
  Renderer r(test::context(), s, rs);
  r.renderFrame();
  Image im = r.indirectRadiance();
  double b = 0, a = 0;
  size_t nb = 0, na = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      double v = (im.at(x, y)[0] + im.at(x, y)[1] + im.at(x, y)[2]) / 3.0;
      if (x < im.width / 2 - 8) { b += v; ++nb; }
      if (x >= im.width / 2 + 8) { a += v; ++na; }
    }
  return {b / double(nb), a / double(na)};
}

}  // namespace

TEST(VctAccuracy, ThinWallLeakIsotropicVsAnisotropic) {
  // builtin:thin_wall (scene/thin_wall.h): the path tracer's room B is exactly black, so all the
  // indirect light vct puts there is leak through the 2 cm wall (thinner than a 64³ voxel).
  Scene s = makeThinWallScene();
  double fraction[2];
  for (int an = 0; an < 2; ++an) {
    const char* mips = an ? "anisotropic" : "isotropic";
    auto [roomB, roomA] = thinWallIndirect(s, {"vct.resolution=64", "vct.specular=0", std::string("vct.mips=") + mips});
    fraction[an] = roomB / roomA;
    std::printf("thin wall, 64^3, %s mips: indirect in the lit room A %.5f, leaked into room B %.5f (reference 0): "
                "%.2f %% of room A\n", mips, roomA, roomB, 100.0 * fraction[an]);
    EXPECT_GT(roomA, 0.0);
  }
  // Measured 1.8 % (isotropic) and 2.7 % (anisotropic). Anisotropic mips keep the wall opaque seen
  // along x, yet leak more: a cone leaning over it weights in the ±y volumes, where the lit floor
  // and ceiling of room A are opaque and the wall, edge-on, is diluted (docs/techniques/vct.md).
  EXPECT_LT(fraction[0], 0.03);
  EXPECT_LT(fraction[1], 0.05);
}

// ---- directional voxels (vct.voxels=directional / directional_slab) -----------------------------
// The four configurations above with level 0 as 6 directional volumes from the surfaces' normals
// (docs/techniques/vct.md, Accuracy point 8). Measured, not the targets: the bounds keep
// the recorded numbers (in the comments) from getting worse.
namespace {
const char* const kDirectionalKinds[2] = {"directional", "directional_slab"};
}  // namespace

TEST(VctAccuracy, DirectionalVoxelsEmptyCornellBoxOneBounceMean) {
  // Measured: plane −66.5 % (no self-illumination left to make up for the light the cones miss),
  // slab −36.5 %; isotropic voxels −8.7 % (above).
  Scene s = cornellWithSpot(false);
  const double lowest[2] = {0.25, 0.55};
  for (int k = 0; k < 2; ++k) {
    test::AccuracyPair p = test::renderAgainstReference(
        s, "vct", 128, 128, {"vct.resolution=64", "vct.specular=0", std::string("vct.voxels=") + kDirectionalKinds[k]},
        true, ReferenceMode::OneBounce, true, "cornell_empty_spot_one_bounce_diffuse_128", 512);
    double mr = meanOf(p.raster), mp = meanOf(p.reference);
    double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
    std::printf("%s voxels: empty Cornell box, one-bounce indirect, vct 64^3: mean %.5f vs reference %.5f (%+.1f %%), "
                "SSIM %.4f\n", kDirectionalKinds[k], mr, mp, 100.0 * (mr / mp - 1.0), ssim);
    EXPECT_GT(mr / mp, lowest[k]) << kDirectionalKinds[k];
    EXPECT_LT(mr / mp, 1.25) << kDirectionalKinds[k];
  }
}

TEST(VctAccuracy, DirectionalVoxelsFullCornellBoxFullImageSsim) {
  // Measured: plane 0.7828, slab 0.8389 (isotropic voxels 0.783).
  Scene s = cornellWithSpot(true);
  const double bound[2] = {0.75, 0.80};
  for (int k = 0; k < 2; ++k) {
    test::AccuracyPair p = test::renderAgainstReference(
        s, "vct", 128, 128, {"vct.resolution=64", "vct.bounces=4", std::string("vct.voxels=") + kDirectionalKinds[k]},
        false, ReferenceMode::Full, false, "cornell_spot_full_128", 512);
    double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
    std::printf("%s voxels: Cornell box (blocks), spot light, direct + vct 64^3 (4 bounces) vs full reference: SSIM "
                "%.4f (bound %.2f; issue target 0.85), mean %.5f vs %.5f\n", kDirectionalKinds[k], ssim, bound[k],
                meanOf(p.raster), meanOf(p.reference));
    EXPECT_GE(ssim, bound[k]) << kDirectionalKinds[k];
  }
}

TEST(VctAccuracy, DirectionalVoxelsSponzaSmallFullImageSsim) {
  // Measured: plane 0.6787, slab 0.7505 (isotropic voxels 0.737).
  std::string why;
  std::optional<Scene> sponza = test::loadSponza(why);
  if (!sponza) GTEST_SKIP() << why;
  const Scene& s = *sponza;
  const double bound[2] = {0.60, 0.68};
  for (int k = 0; k < 2; ++k) {
    test::AccuracyPair p = test::renderAgainstReference(
        s, "vct", 96, 54, {"vct.resolution=64", "shadow.resolution=1024", std::string("vct.voxels=") + kDirectionalKinds[k]},
        false, ReferenceMode::Full, false, "sponza_sun_full_96x54", 16);
    double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
    std::printf("%s voxels: Sponza 96x54, sun, direct + vct 64^3 vs full reference: SSIM %.4f (bound %.2f; issue "
                "target 0.85), mean %.5f vs %.5f\n", kDirectionalKinds[k], ssim, bound[k], meanOf(p.raster),
                meanOf(p.reference));
    EXPECT_GE(ssim, bound[k]) << kDirectionalKinds[k];
  }
}

TEST(VctAccuracy, DirectionalVoxelsThinWallLeak) {
  // Measured: plane 9.2 % (the wall, one-sided where its faces fall in different voxels, is
  // transparent edge-on: cones leaning over it see it only through their x part), slab 4.9 %
  // (isotropic voxels with anisotropic mips: 2.7 %, bound 5 %).
  Scene s = makeThinWallScene();
  const double bound[2] = {0.11, 0.05};
  for (int k = 0; k < 2; ++k) {
    auto [roomB, roomA] = thinWallIndirect(
        s, {"vct.resolution=64", "vct.specular=0", "vct.mips=anisotropic", std::string("vct.voxels=") + kDirectionalKinds[k]});
    std::printf("%s voxels: thin wall, 64^3, anisotropic mips: indirect in the lit room A %.5f, leaked into room B "
                "%.5f (reference 0): %.2f %% of room A (bound %.0f %%)\n", kDirectionalKinds[k], roomA, roomB,
                100.0 * roomB / roomA, 100.0 * bound[k]);
    EXPECT_GT(roomA, 0.0);
    EXPECT_LT(roomB / roomA, bound[k]) << kDirectionalKinds[k];
  }
}

// ---- the grid's border repeating its edge voxels (vct.border=edge) -------------------------------
// The default configuration and directional_slab voxels (6 and 9 cones) with lookups clamped to the
// grid's edge voxels ahead of each cone, in the pixels' cones and in the bounces' (docs/techniques/
// vct.md, Accuracy point 9). The
// Cornell box's walls are the grid's border (one voxel of margin), so with vct.border=zero every
// cone that ends on a wall sees it through coarse samples half past the border, diluted by the
// empty outside. Measured, not the targets; the bounds keep the recorded numbers (in the
// comments) from getting worse.
namespace {
struct BorderConfig {
  const char* label;
  std::vector<std::string> sets;
};
const BorderConfig kBorderEdgeConfigs[3] = {
    {"isotropic voxels", {"vct.border=edge"}},
    {"directional_slab voxels", {"vct.border=edge", "vct.voxels=directional_slab"}},
    {"directional_slab voxels, 9 cones", {"vct.border=edge", "vct.voxels=directional_slab", "vct.cones=9"}}};
std::vector<std::string> withSets(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}
}  // namespace

TEST(VctAccuracy, BorderEdgeCornellBoxes) {
  // Measured (border zero in brackets): empty box, one bounce: mean +10.4 % (−8.7 %), SSIM 0.696
  // (0.651); slab −9.1 % (−36.5 %), SSIM 0.863 (0.793); slab with 9 cones −10.3 % (−41.5 %), SSIM
  // 0.893 (0.815). Full Cornell box (4 bounces): SSIM 0.784 (0.783), mean +0.1 % (−23.7 %); slab
  // 0.850 (0.839), mean −4.4 % (−32.9 %); slab with 9 cones **0.855** (0.850), mean −1.3 % (−33.6 %):
  // the 0.85 on this scene, with these options (the defaults score 0.783).
  const double fullBound[3] = {0.76, 0.82, 0.85};
  for (int k = 0; k < 3; ++k) {
    const BorderConfig& c = kBorderEdgeConfigs[k];
    Scene empty = cornellWithSpot(false);
    test::AccuracyPair p = test::renderAgainstReference(
        empty, "vct", 128, 128, withSets({"vct.resolution=64", "vct.specular=0"}, c.sets), true,
        ReferenceMode::OneBounce, true, "cornell_empty_spot_one_bounce_diffuse_128", 512);
    double mr = meanOf(p.raster), mp = meanOf(p.reference);
    double ssim =
        metrics::ssim(displayTransform(p.reference, empty.exposure), displayTransform(p.raster, empty.exposure)).mean;
    std::printf("border edge, %s: empty Cornell box, one-bounce indirect, vct 64^3: mean %.5f vs reference %.5f "
                "(%+.1f %%, bound 25 %%), SSIM %.4f\n", c.label, mr, mp, 100.0 * (mr / mp - 1.0), ssim);
    EXPECT_NEAR(mr / mp, 1.0, 0.25) << c.label;
    Scene full = cornellWithSpot(true);
    p = test::renderAgainstReference(full, "vct", 128, 128, withSets({"vct.resolution=64", "vct.bounces=4"}, c.sets),
                                     false, ReferenceMode::Full, false, "cornell_spot_full_128", 512);
    ssim = metrics::ssim(displayTransform(p.reference, full.exposure), displayTransform(p.raster, full.exposure)).mean;
    std::printf("border edge, %s: Cornell box (blocks), spot light, direct + vct 64^3 (4 bounces) vs full reference: "
                "SSIM %.4f (bound %.2f; issue target 0.85), mean %.5f vs %.5f\n", c.label, ssim, fullBound[k],
                meanOf(p.raster), meanOf(p.reference));
    EXPECT_GE(ssim, fullBound[k]) << c.label;
  }
}

TEST(VctAccuracy, BorderEdgeSponzaSmall) {
  // Measured (border zero in brackets): 0.742 (0.737), slab 0.755 (0.751), slab with 9 cones 0.751
  // (0.747). Sponza's floor and roof lie inside the cubic grid (its edge is along x), so few cones
  // end at the border.
  std::string why;
  std::optional<Scene> sponza = test::loadSponza(why);
  if (!sponza) GTEST_SKIP() << why;
  const Scene& s = *sponza;
  for (int k = 0; k < 3; ++k) {
    const BorderConfig& c = kBorderEdgeConfigs[k];
    test::AccuracyPair p = test::renderAgainstReference(s, "vct", 96, 54,
                                                        withSets({"vct.resolution=64", "shadow.resolution=1024"}, c.sets),
                                                        false, ReferenceMode::Full, false, "sponza_sun_full_96x54", 16);
    double ssim = metrics::ssim(displayTransform(p.reference, s.exposure), displayTransform(p.raster, s.exposure)).mean;
    std::printf("border edge, %s: Sponza 96x54, sun, direct + vct 64^3 vs full reference: SSIM %.4f (bound 0.70; "
                "issue target 0.85), mean %.5f vs %.5f\n", c.label, ssim, meanOf(p.raster), meanOf(p.reference));
    EXPECT_GE(ssim, 0.70) << c.label;
  }
}

TEST(VctAccuracy, BorderEdgeThinWallLeak) {
  // Measured (border zero in brackets), anisotropic mips: 5.9 % (2.7 %), slab 10.2 % (4.9 %), slab
  // with 9 cones 12.5 % (6.3 %). The rooms are open at the front, and the cubic grid reaches far
  // past the opening: a cone leaving through it keeps sampling coarse levels, which hold both
  // rooms' light, at full weight up to the grid's border, where border zero fades them out.
  Scene s = makeThinWallScene();
  const double bound[3] = {0.08, 0.13, 0.16};
  for (int k = 0; k < 3; ++k) {
    const BorderConfig& c = kBorderEdgeConfigs[k];
    auto [roomB, roomA] = thinWallIndirect(s, withSets({"vct.resolution=64", "vct.specular=0", "vct.mips=anisotropic"}, c.sets));
    std::printf("border edge, %s: thin wall, 64^3, anisotropic mips: indirect in the lit room A %.5f, leaked into "
                "room B %.5f (reference 0): %.2f %% of room A (bound %.0f %%)\n", c.label, roomA, roomB,
                100.0 * roomB / roomA, 100.0 * bound[k]);
    EXPECT_GT(roomA, 0.0);
    EXPECT_LT(roomB / roomA, bound[k]) << c.label;
  }
}
