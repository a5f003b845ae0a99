// SSIM (Wang, Bovik, Sheikh, Simoncelli 2004, "Image quality assessment: from error visibility to
// structural similarity", eq. 13 with C3 = C2/2) and ten Brug's grade (seed 003 §4.2).
//
// SSIM follows scikit-image's structural_similarity(gaussian_weights=True, sigma=1.5,
// use_sample_covariance=False, data_range=1) number for number, so the cross-check
// (tests/cross_check_metrics.py) can hold us to 1e-3:
//   - local statistics are Gaussian-weighted means (σ = 1.5, 11 taps, weights normalized to sum
//     to 1) of x, y, x², y², xy; variances are E[x²] − E[x]² (population, not sample, covariance);
//   - the per-pixel index is ((2μxμy + C1)(2σxy + C2)) / ((μx² + μy² + C1)(σx² + σy² + C2)),
//     C1 = (0.01·L)², C2 = (0.03·L)², L = 1 (L = 255 only for `grade255`, metrics.h);
//   - the mean (MSSIM) skips the 5-pixel border, where the window would leave the image.
// All in double precision, as scikit-image computes on float64.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "metrics/filter.h"
#include "metrics/metrics.h"
#include "util/error.h"

namespace gi::metrics {

using detail::Border;

namespace {

std::vector<double> ssimKernel() {
  std::vector<double> k(2 * kSsimRadius + 1);
  double sum = 0;
  for (int i = -kSsimRadius; i <= kSsimRadius; ++i) sum += k[i + kSsimRadius] = std::exp(-0.5 * i * i / (kSsimSigma * kSsimSigma));
  for (double& w : k) w /= sum;
  return k;
}

void requireSameSize(const Image& a, const Image& b, const char* what) {
  if (a.width != b.width || a.height != b.height)
    throw Error(std::string(what) + ": image sizes differ (reference " + std::to_string(a.width) + "x" +
                std::to_string(a.height) + ", test " + std::to_string(b.width) + "x" + std::to_string(b.height) + ")");
}

bool isBlack(const float* rgb) {
  return rgb[0] < kBlackThreshold && rgb[1] < kBlackThreshold && rgb[2] < kBlackThreshold;
}

}  // namespace

Image toRgb(const Image& image) {
  if (image.channels == 3) return image;
  Image out(image.width, image.height, 3);
  for (size_t p = 0; p < image.pixelCount(); ++p)
    for (int c = 0; c < 3; ++c)
      out.pixels[p * 3 + c] = image.pixels[p * image.channels + (image.channels >= 3 ? c : 0)];
  return out;
}

SsimResult ssim(const Image& referenceDisplay, const Image& testDisplay, double dataRange) {
  requireSameSize(referenceDisplay, testDisplay, "ssim");
  const int w = referenceDisplay.width, h = referenceDisplay.height;
  if (w < kSsimMinSize || h < kSsimMinSize)
    throw Error("ssim: images must be at least " + std::to_string(kSsimMinSize) + "x" + std::to_string(kSsimMinSize) +
                " pixels (got " + std::to_string(w) + "x" + std::to_string(h) + ")");
  const Image a = toRgb(referenceDisplay), b = toRgb(testDisplay);
  const size_t n = size_t(w) * h;
  const std::vector<double> k = ssimKernel();
  const double c1 = (kSsimK1 * dataRange) * (kSsimK1 * dataRange);
  const double c2 = (kSsimK2 * dataRange) * (kSsimK2 * dataRange);

  SsimResult result;
  result.map = Image(w, h, 3);
  // Five moments of one channel, filtered in place of their products.
  std::vector<double> x(n), y(n), xx(n), yy(n), xy(n);
  std::vector<double> mx(n), my(n), mxx(n), myy(n), mxy(n);
  for (int c = 0; c < 3; ++c) {
    for (size_t p = 0; p < n; ++p) {
      x[p] = a.pixels[p * 3 + c];
      y[p] = b.pixels[p * 3 + c];
      xx[p] = x[p] * x[p];
      yy[p] = y[p] * y[p];
      xy[p] = x[p] * y[p];
    }
    // Reflect only matters for the border pixels, which the mean excludes (window radius ==
    // crop width); it makes the displayed map sensible there.
    detail::convolveSeparable(x.data(), mx.data(), w, h, k, k, Border::Reflect);
    detail::convolveSeparable(y.data(), my.data(), w, h, k, k, Border::Reflect);
    detail::convolveSeparable(xx.data(), mxx.data(), w, h, k, k, Border::Reflect);
    detail::convolveSeparable(yy.data(), myy.data(), w, h, k, k, Border::Reflect);
    detail::convolveSeparable(xy.data(), mxy.data(), w, h, k, k, Border::Reflect);

    // Per-row sums, added in row order afterwards, keep the mean independent of threading.
    std::vector<double> rowSum(h, 0.0);
    detail::parallelRows(h, [&](int y0, int y1) {
      for (int yy0 = y0; yy0 < y1; ++yy0)
        for (int xx0 = 0; xx0 < w; ++xx0) {
          size_t p = size_t(yy0) * w + xx0;
          double ux = mx[p], uy = my[p];
          double vx = mxx[p] - ux * ux, vy = myy[p] - uy * uy, vxy = mxy[p] - ux * uy;
          double s = ((2 * ux * uy + c1) * (2 * vxy + c2)) / ((ux * ux + uy * uy + c1) * (vx + vy + c2));
          result.map.pixels[p * 3 + c] = float(s);
          if (yy0 >= kSsimRadius && yy0 < h - kSsimRadius && xx0 >= kSsimRadius && xx0 < w - kSsimRadius) rowSum[yy0] += s;
        }
    });
    double sum = 0;
    for (double s : rowSum) sum += s;
    result.channel[c] = sum / (double(w - 2 * kSsimRadius) * double(h - 2 * kSsimRadius));
  }
  result.mean = (result.channel[0] + result.channel[1] + result.channel[2]) / 3.0;
  return result;
}

GradeResult tenBrugGrade(const Image& referenceDisplay, const Image& testDisplay, const SsimResult& s) {
  requireSameSize(referenceDisplay, testDisplay, "grade");
  requireSameSize(referenceDisplay, s.map, "grade");
  const Image a = toRgb(referenceDisplay), b = toRgb(testDisplay);
  const int w = a.width, h = a.height;
  GradeResult g;
  std::array<double, 3> sum{0, 0, 0};
  for (int y = kSsimRadius; y < h - kSsimRadius; ++y)
    for (int x = kSsimRadius; x < w - kSsimRadius; ++x) {
      if (isBlack(a.at(x, y)) && isBlack(b.at(x, y))) {
        ++g.ignoredBlackPixels;
        continue;
      }
      ++g.countedPixels;
      const float* m = s.map.at(x, y);
      for (int c = 0; c < 3; ++c) sum[c] += m[c];
    }
  if (g.countedPixels == 0) return g;  // nothing but black in both: identical as far as the grade sees
  double acc = 0;
  for (int c = 0; c < 3; ++c) {
    g.mssim[c] = sum[c] / double(g.countedPixels);
    // SSIM can be negative for anti-correlated images; the grade treats that as no similarity
    // (an even power would otherwise turn it into a high score).
    acc += std::pow(std::clamp(g.mssim[c], 0.0, 1.0), kGradeExponent);
  }
  g.grade = 10.0 * acc / 3.0;
  return g;
}

GradeResult tenBrugGrade(const Image& referenceDisplay, const Image& testDisplay) {
  return tenBrugGrade(referenceDisplay, testDisplay, ssim(referenceDisplay, testDisplay));
}

}  // namespace gi::metrics
