// Tests of src/metrics (SSIM, ten Brug's grade, PSNR/RMSE/relMSE, LDR-FLIP, heat maps) and of
// `gi compare`: identities, hand-computed values, invariances, monotonicity, and the command's
// error handling (non-zero exit, one line, no output files). The numerical agreement with
// scikit-image and flip_evaluator is checked by cross_check_metrics.py (ctest MetricsCrossCheck).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "image/image.h"
#include "metrics/metrics.h"
#include "test_support.h"
#include "util/error.h"

namespace {

using gi::Image;
namespace m = gi::metrics;
namespace fs = std::filesystem;

// A smooth, structured display image in [0, 1] (gradients, a disk, a checkerboard).
Image pattern(int w, int h) {
  Image img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* p = img.at(x, y);
      p[0] = 0.5f + 0.4f * std::sin(x / 7.0f) * std::cos(y / 11.0f);
      p[1] = 0.1f + 0.8f * float(x) / float(w);
      p[2] = ((x / 8 + y / 8) % 2) ? 0.7f : 0.3f;
      float dx = x - 0.6f * w, dy = y - 0.4f * h;
      if (dx * dx + dy * dy < 0.04f * w * h) { p[0] = 0.9f; p[1] = 0.2f; p[2] = 0.1f; }
    }
  return img;
}

Image withNoise(const Image& img, float sigma, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, 1.0f);
  Image out = img;
  for (float& v : out.pixels) v = std::clamp(v + sigma * n(rng), 0.0f, 1.0f);
  return out;
}

// SSIM of two constant images, from Wang et al. eq. 13 with σ = 0: (2μxμy + C1) / (μx² + μy² + C1).
double constantSsim(double a, double b) {
  const double c1 = 0.01 * 0.01;
  return (2 * a * b + c1) / (a * a + b * b + c1);
}

TEST(MetricsSsim, IdenticalImagesScoreOne) {
  Image a = pattern(64, 48);
  auto s = m::ssim(a, a);
  EXPECT_NEAR(s.mean, 1.0, 1e-12);
  for (double c : s.channel) EXPECT_NEAR(c, 1.0, 1e-12);
  ASSERT_EQ(s.map.channels, 3);
  for (float v : s.map.pixels) EXPECT_NEAR(v, 1.0f, 1e-6f);
}

TEST(MetricsSsim, ConstantImagesMatchTheFormulaByHand) {
  // Per channel: 0.5 vs 0.3, 0.2 vs 0.2, 0.9 vs 0.6; no variance, so SSIM is the luminance term.
  Image a(32, 24, 3), b(32, 24, 3);
  const float ra[3] = {0.5f, 0.2f, 0.9f}, rb[3] = {0.3f, 0.2f, 0.6f};
  for (size_t p = 0; p < a.pixelCount(); ++p)
    for (int c = 0; c < 3; ++c) {
      a.pixels[p * 3 + c] = ra[c];
      b.pixels[p * 3 + c] = rb[c];
    }
  auto s = m::ssim(a, b);
  double expected = 0;
  for (int c = 0; c < 3; ++c) {
    double e = constantSsim(ra[c], rb[c]);
    EXPECT_NEAR(s.channel[c], e, 1e-7) << "channel " << c;
    expected += e / 3;
  }
  EXPECT_NEAR(s.mean, expected, 1e-7);
  // 0.5 vs 0.3 by hand: (0.3 + 0.0001) / (0.34 + 0.0001) = 0.882387...
  EXPECT_NEAR(s.channel[0], 0.3001 / 0.3401, 1e-7);
}

TEST(MetricsSsim, IsSymmetricAndInvariantToChannelOrderAndMirroring) {
  Image a = pattern(57, 43), b = withNoise(a, 0.1f);
  auto ab = m::ssim(a, b), ba = m::ssim(b, a);
  EXPECT_NEAR(ab.mean, ba.mean, 1e-12);

  // Permuting R, G, B in both images permutes the per-channel values and keeps the mean.
  auto permute = [](const Image& img) {
    Image out = img;
    for (size_t p = 0; p < img.pixelCount(); ++p)
      for (int c = 0; c < 3; ++c) out.pixels[p * 3 + c] = img.pixels[p * 3 + (c + 1) % 3];
    return out;
  };
  auto pp = m::ssim(permute(a), permute(b));
  EXPECT_NEAR(pp.mean, ab.mean, 1e-12);
  EXPECT_NEAR(pp.channel[0], ab.channel[1], 1e-12);

  // The Gaussian window and the cropped border are symmetric: mirroring both images changes nothing.
  auto mirror = [](const Image& img) {
    Image out = img;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        for (int c = 0; c < 3; ++c) out.at(x, y)[c] = img.at(img.width - 1 - x, y)[c];
    return out;
  };
  EXPECT_NEAR(m::ssim(mirror(a), mirror(b)).mean, ab.mean, 1e-9);

  // Grey (1-channel) inputs are treated as grey RGB.
  Image g(32, 32, 1, 0.25f), g3(32, 32, 3, 0.25f), h3(32, 32, 3, 0.5f);
  EXPECT_NEAR(m::ssim(g, h3).mean, m::ssim(g3, h3).mean, 1e-12);
}

TEST(MetricsSsim, DecreasesWithNoiseAndRejectsBadSizes) {
  Image a = pattern(64, 64);
  double s1 = m::ssim(a, withNoise(a, 0.02f)).mean, s2 = m::ssim(a, withNoise(a, 0.1f)).mean;
  EXPECT_LT(s1, 1.0);
  EXPECT_LT(s2, s1);
  EXPECT_THROW(m::ssim(Image(64, 64, 3), Image(64, 63, 3)), gi::Error);
  EXPECT_THROW(m::ssim(Image(10, 64, 3), Image(10, 64, 3)), gi::Error);
}

TEST(MetricsGrade, IdenticalImagesScoreTen) {
  Image a = pattern(48, 40);
  auto g = m::tenBrugGrade(a, a);
  EXPECT_NEAR(g.grade, 10.0, 1e-9);
  // All black in both: nothing to compare, also 10.
  auto black = m::tenBrugGrade(Image(32, 32, 3), Image(32, 32, 3));
  EXPECT_EQ(black.countedPixels, 0u);
  EXPECT_DOUBLE_EQ(black.grade, 10.0);
}

TEST(MetricsGrade, IgnoresPixelsBlackInBothImages) {
  // The same content next to black areas of two widths. Pixels black in both are ignored, so the
  // grade cannot tell the two apart, while plain SSIM (which counts them as perfect) can.
  Image content = pattern(40, 40), noisy = withNoise(content, 0.05f);
  auto padRight = [](const Image& img, int extra) {
    Image out(img.width + extra, img.height, 3, 0.0f);
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        for (int c = 0; c < 3; ++c) out.at(x, y)[c] = img.at(x, y)[c];
    return out;
  };
  Image r1 = padRight(content, 30), t1 = padRight(noisy, 30);
  Image r2 = padRight(content, 200), t2 = padRight(noisy, 200);
  auto g1 = m::tenBrugGrade(r1, t1), g2 = m::tenBrugGrade(r2, t2);
  EXPECT_GT(g2.ignoredBlackPixels, g1.ignoredBlackPixels);
  EXPECT_EQ(g1.countedPixels, g2.countedPixels);
  EXPECT_NEAR(g1.grade, g2.grade, 1e-9);
  EXPECT_GT(m::ssim(r2, t2).mean, m::ssim(r1, t1).mean + 0.01);
  EXPECT_LT(g1.grade, 10.0);
  // The grade is 10 × mean_c MSSIM_c^1000 over the counted pixels.
  double expected = 0;
  for (double v : g1.mssim) expected += 10.0 * std::pow(v, 1000.0) / 3.0;
  EXPECT_NEAR(g1.grade, expected, 1e-9);
}

TEST(MetricsGrade, BlackMeansBelowHalfAnEightBitLevelInAllChannels) {
  // Black in the reference only (test has 1/255 in red): counted, and the grade drops.
  Image r(32, 32, 3, 0.0f), t(32, 32, 3, 0.0f);
  for (size_t p = 0; p < t.pixelCount(); p += 2) t.pixels[p * 3] = 1.0f / 255.0f;
  auto g = m::tenBrugGrade(r, t);
  EXPECT_EQ(g.ignoredBlackPixels, (32u - 10) * (32 - 10) / 2);
  EXPECT_EQ(g.countedPixels, (32u - 10) * (32 - 10) / 2);
  // Just below half a level is still black in both.
  Image t2(32, 32, 3, 0.49f / 255.0f);
  EXPECT_EQ(m::tenBrugGrade(r, t2).countedPixels, 0u);
}

TEST(MetricsGrade, Grade255UsesEightBitConstantsOnUnitRangeValues) {
  // Constant images, 0.5 vs 0.3 in every channel: only the luminance term differs from 1, and with
  // C1 = (0.01·255)² = 6.5025 it is (2·0.15 + C1) / (0.25 + 0.09 + C1) by hand — within 6e-3 of 1,
  // the nearness to 1 ten Brug reported for every raw score (seed 003 §4.2).
  Image a(32, 24, 3, 0.5f), b(32, 24, 3, 0.3f);
  const double c1 = 6.5025, expected = (0.3 + c1) / (0.34 + c1);
  auto s = m::ssim(a, b, m::kSsimDataRange8Bit);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.channel[c], expected, 1e-9) << "channel " << c;
  auto g = m::tenBrugGrade(a, b, s);
  // The grade averages the SSIM map, which is stored as float (rounding ≤ 6e-8 per pixel); the
  // power 1000 turns that into a relative error ≤ 1e3 × 6e-8 of the grade.
  const double expectedGrade = 10.0 * std::pow(expected, 1000.0);
  EXPECT_NEAR(g.grade, expectedGrade, 1e-4 * expectedGrade);
  // The same pair scores 0 with the grade of ALGORITHMS.md (L = 1): 0.882^1000 underflows.
  EXPECT_LT(m::tenBrugGrade(a, b).grade, 1e-30);
  // Noise lowers it, less than it lowers the L = 1 SSIM.
  Image content = pattern(40, 40), noisy = withNoise(content, 0.05f);
  double s255 = m::ssim(content, noisy, m::kSsimDataRange8Bit).mean, s1 = m::ssim(content, noisy).mean;
  EXPECT_LT(s255, 1.0);
  EXPECT_GT(s255, s1);
}

TEST(MetricsPixelError, PsnrOfAKnownMse) {
  Image a(20, 10, 3, 0.5f), b(20, 10, 3, 0.6f);  // MSE 0.01 → 20 dB
  EXPECT_NEAR(m::mse(a, b), 0.01, 1e-7);
  EXPECT_NEAR(m::psnr(a, b), 20.0, 1e-4);
  // Half the pixels off by 0.1: MSE 0.005 → 10·log10(200) = 23.0103 dB.
  Image c = a;
  for (size_t p = 0; p < c.pixelCount() / 2; ++p)
    for (int ch = 0; ch < 3; ++ch) c.pixels[p * 3 + ch] = 0.6f;
  EXPECT_NEAR(m::psnr(a, c), 10.0 * std::log10(200.0), 1e-4);
  // Identical: infinite, not NaN or a division error.
  double same = m::psnr(a, a);
  EXPECT_TRUE(std::isinf(same) && same > 0);
}

TEST(MetricsPixelError, RmseAndRelMseOnLinearValues) {
  Image ref(8, 8, 3, 2.0f), test(8, 8, 3, 2.5f);  // HDR values above 1 are fine here
  EXPECT_NEAR(m::rmse(ref, test), 0.5, 1e-7);
  EXPECT_NEAR(m::relMse(ref, test), 0.25 / (4.0 + 0.01), 1e-7);
  EXPECT_NEAR(m::relMse(ref, ref), 0.0, 0.0);
  EXPECT_NEAR(m::rmse(ref, ref), 0.0, 0.0);
  Image rel = m::relativeErrorMap(ref, test), abs = m::absoluteErrorMap(ref, test);
  EXPECT_EQ(rel.channels, 1);
  EXPECT_NEAR(rel.pixels[0], 0.25 / 4.01, 1e-6);
  EXPECT_NEAR(abs.pixels[0], 0.5, 1e-6);
}

TEST(MetricsFlip, IdenticalImagesScoreZero) {
  Image a = pattern(64, 48);
  auto f = m::flip(a, a);
  EXPECT_DOUBLE_EQ(f.mean, 0.0);
  ASSERT_EQ(f.map.channels, 1);
  for (float v : f.map.pixels) EXPECT_EQ(v, 0.0f);
}

TEST(MetricsFlip, GrowsWithNoise) {
  Image a = pattern(96, 64);
  double previous = 0.0;
  for (float sigma : {0.01f, 0.03f, 0.08f, 0.2f}) {
    double f = m::flip(a, withNoise(a, sigma)).mean;
    EXPECT_GT(f, previous) << "sigma " << sigma;
    EXPECT_LE(f, 1.0);
    previous = f;
  }
}

TEST(MetricsFlip, BlackVersusWhiteIsTheMaximumError) {
  // Flat images: no features, colour error = HyAB(black, white)^0.7 ≥ pc·cmax → near the top of [pt, 1].
  auto f = m::flip(Image(32, 32, 3, 0.0f), Image(32, 32, 3, 1.0f));
  EXPECT_GT(f.mean, 0.95);
  EXPECT_LE(f.mean, 1.0);
  EXPECT_NEAR(m::kDefaultPpd, 67.0206, 1e-4);
  EXPECT_NEAR(m::pixelsPerDegree(0.7, 3840, 0.7), m::kDefaultPpd, 1e-12);
  EXPECT_THROW(m::flip(Image(8, 8, 3), Image(9, 8, 3)), gi::Error);
}

TEST(MetricsFlip, IsDeterministic) {
  Image a = pattern(70, 50), b = withNoise(a, 0.05f);
  auto f1 = m::flip(a, b), f2 = m::flip(a, b);
  EXPECT_EQ(f1.mean, f2.mean);
  EXPECT_EQ(f1.map.pixels, f2.map.pixels);
}

TEST(MetricsHeatmap, MagmaEndsAndIndexing) {
  const auto& t = m::magmaTable();
  EXPECT_NEAR(t[0][0], 0.001462f, 1e-6f);
  EXPECT_NEAR(t[255][2], 0.749504f, 1e-6f);
  Image map(3, 1, 1);
  map.pixels = {0.0f, 1.0f, 2.0f};  // 2 clamps to the top entry
  Image heat = m::magmaHeatmap(map);
  ASSERT_EQ(heat.channels, 3);
  EXPECT_EQ(heat.at(0, 0)[1], t[0][1]);
  EXPECT_EQ(heat.at(1, 0)[1], t[255][1]);
  EXPECT_EQ(heat.at(2, 0)[1], t[255][1]);
  EXPECT_THROW(m::magmaHeatmap(Image(2, 2, 3)), gi::Error);
}

// ---- gi compare -------------------------------------------------------------------------------

struct CompareFiles {
  fs::path dir, ref, test, small, json, heat;
  explicit CompareFiles(const std::string& name) {
    dir = gi::test::tempDir(name);
    ref = dir / "ref.png";
    test = dir / "test.png";
    small = dir / "small.png";
    json = dir / "out.json";
    heat = dir / "heat.png";
    Image a = pattern(64, 48);
    gi::writeImage(ref, a);
    gi::writeImage(test, withNoise(a, 0.05f));
    gi::writeImage(small, pattern(32, 48));
  }
  std::string outputs() const { return " --json " + json.string() + " --heatmap " + heat.string(); }
  bool noOutputs() const { return !fs::exists(json) && !fs::exists(heat); }
  ~CompareFiles() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

int lineCount(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

TEST(MetricsCompareCli, WritesJsonAndHeatmapMatchingTheLibrary) {
  CompareFiles f("metrics_cli_ok");
  auto r = gi::test::runGi("compare --reference " + f.ref.string() + " --test " + f.test.string() + f.outputs());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("flip"), std::string::npos) << r.output;
  ASSERT_TRUE(fs::exists(f.json) && fs::exists(f.heat));
  nlohmann::json j = nlohmann::json::parse(std::ifstream(f.json));
  Image a = gi::readImage(f.ref), b = gi::readImage(f.test);
  EXPECT_NEAR(j["metrics"]["ssim"].get<double>(), m::ssim(a, b).mean, 1e-12);
  EXPECT_NEAR(j["metrics"]["flip"].get<double>(), m::flip(a, b).mean, 1e-12);
  EXPECT_NEAR(j["metrics"]["psnr"].get<double>(), m::psnr(a, b), 1e-9);
  EXPECT_EQ(j["reference"]["encoding"], "display");
  for (const char* k : {"grade", "rmse", "relmse"}) EXPECT_TRUE(j["metrics"].contains(k)) << k;
  Image heat = gi::readImage(f.heat);
  EXPECT_EQ(heat.width, 64);
  EXPECT_EQ(heat.channels, 3);
}

TEST(MetricsCompareCli, IdenticalImagesAndLinearInput) {
  CompareFiles f("metrics_cli_same");
  // An EXR holding the linear values of the PNG compares as identical at exposure 1.
  fs::path exr = f.dir / "ref.exr";
  gi::writeImage(exr, m::displayToLinear(gi::readImage(f.ref), 1.0f));
  auto r = gi::test::runGi("compare --reference " + exr.string() + " --test " + f.ref.string() + " --json " + f.json.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  nlohmann::json j = nlohmann::json::parse(std::ifstream(f.json));
  EXPECT_EQ(j["reference"]["encoding"], "linear");
  EXPECT_NEAR(j["metrics"]["ssim"].get<double>(), 1.0, 1e-4);
  EXPECT_NEAR(j["metrics"]["grade"].get<double>(), 10.0, 0.05);
  EXPECT_LT(j["metrics"]["flip"].get<double>(), 1e-3);
  EXPECT_LT(j["metrics"]["rmse"].get<double>(), 1e-5);

  auto same = gi::test::runGi("compare --reference " + f.ref.string() + " --test " + f.ref.string() +
                              " --metrics psnr,ssim,flip,grade --json " + f.json.string());
  ASSERT_EQ(same.exitCode, 0) << same.output;
  EXPECT_NE(same.output.find("inf"), std::string::npos) << same.output;
  j = nlohmann::json::parse(std::ifstream(f.json));
  EXPECT_TRUE(j["metrics"]["psnr"].is_null());  // infinite PSNR
  EXPECT_TRUE(j["details"]["psnr_infinite"].get<bool>());
  EXPECT_EQ(j["metrics"]["ssim"].get<double>(), 1.0);
  EXPECT_EQ(j["metrics"]["flip"].get<double>(), 0.0);
  EXPECT_EQ(j["metrics"]["grade"].get<double>(), 10.0);
  EXPECT_FALSE(j["metrics"].contains("rmse"));  // only what --metrics asked for
}

TEST(MetricsCompareCli, MismatchedSizesFailWithoutOutput) {
  CompareFiles f("metrics_cli_size");
  auto r = gi::test::runGi("compare --reference " + f.ref.string() + " --test " + f.small.string() + f.outputs());
  EXPECT_NE(r.exitCode, 0);
  EXPECT_EQ(lineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("small.png"), std::string::npos) << r.output;
  EXPECT_TRUE(f.noOutputs());
}

TEST(MetricsCompareCli, MissingFileFailsWithoutOutput) {
  CompareFiles f("metrics_cli_missing");
  auto r = gi::test::runGi("compare --reference " + f.ref.string() + " --test " + (f.dir / "nope.png").string() + f.outputs());
  EXPECT_NE(r.exitCode, 0);
  EXPECT_EQ(lineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("nope.png"), std::string::npos) << r.output;
  EXPECT_TRUE(f.noOutputs());
  // A file that exists but is not an image.
  fs::path junk = f.dir / "junk.png";
  std::ofstream(junk) << "not a png";
  r = gi::test::runGi("compare --reference " + junk.string() + " --test " + f.test.string() + f.outputs());
  EXPECT_NE(r.exitCode, 0);
  EXPECT_EQ(lineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("junk.png"), std::string::npos) << r.output;
  EXPECT_TRUE(f.noOutputs());
}

TEST(MetricsCompareCli, UnknownMetricFailsWithoutOutput) {
  CompareFiles f("metrics_cli_metric");
  auto r = gi::test::runGi("compare --reference " + f.ref.string() + " --test " + f.test.string() +
                           " --metrics ssim,bogus" + f.outputs());
  EXPECT_NE(r.exitCode, 0);
  EXPECT_EQ(lineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("'bogus'"), std::string::npos) << r.output;
  EXPECT_TRUE(f.noOutputs());
  // A heat map name that is neither .png nor .exr is refused up front too.
  r = gi::test::runGi("compare --reference " + f.ref.string() + " --test " + f.test.string() + " --json " +
                      f.json.string() + " --heatmap " + (f.dir / "h.bmp").string());
  EXPECT_NE(r.exitCode, 0);
  EXPECT_TRUE(f.noOutputs());
}

}  // namespace
