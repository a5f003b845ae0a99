// Per-pixel error metrics: MSE, PSNR (display images, peak 1), RMSE and relative MSE (linear HDR
// images, relMSE = mean (t − r)² / (r² + ε), ε = 1e-2 as in the denoising literature, e.g.
// Rousselle et al. 2011), their one-channel maps, and the display → linear inverse used by
// `gi compare` for PNG inputs. All sums in double, in pixel order, so results are deterministic.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "metrics/metrics.h"
#include "util/error.h"

namespace gi::metrics {

namespace {

void requireSameSize(const Image& a, const Image& b, const char* what) {
  if (a.width != b.width || a.height != b.height)
    throw Error(std::string(what) + ": image sizes differ (reference " + std::to_string(a.width) + "x" +
                std::to_string(a.height) + ", test " + std::to_string(b.width) + "x" + std::to_string(b.height) + ")");
}

// Calls f(ref, test) for R, G, B of every pixel; returns the mean of what f returns.
template <typename F>
double meanOverRgb(const Image& reference, const Image& test, const char* what, F f) {
  requireSameSize(reference, test, what);
  const Image a = toRgb(reference), b = toRgb(test);
  double sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) sum += f(double(a.pixels[i]), double(b.pixels[i]));
  return a.pixels.empty() ? 0.0 : sum / double(a.pixels.size());
}

}  // namespace

double mse(const Image& reference, const Image& test) {
  return meanOverRgb(reference, test, "mse", [](double r, double t) { return (t - r) * (t - r); });
}

double psnr(const Image& referenceDisplay, const Image& testDisplay) {
  double m = meanOverRgb(referenceDisplay, testDisplay, "psnr", [](double r, double t) {
    // Display values are defined on [0, 1]; clamp as a display would.
    r = std::clamp(r, 0.0, 1.0);
    t = std::clamp(t, 0.0, 1.0);
    return (t - r) * (t - r);
  });
  if (m == 0.0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(1.0 / m);
}

double rmse(const Image& referenceLinear, const Image& testLinear) {
  return std::sqrt(mse(referenceLinear, testLinear));
}

double relMse(const Image& referenceLinear, const Image& testLinear, double epsilon) {
  return meanOverRgb(referenceLinear, testLinear, "relmse",
                     [epsilon](double r, double t) { return (t - r) * (t - r) / (r * r + epsilon); });
}

Image absoluteErrorMap(const Image& reference, const Image& test) {
  requireSameSize(reference, test, "error map");
  const Image a = toRgb(reference), b = toRgb(test);
  Image out(a.width, a.height, 1);
  for (size_t p = 0; p < a.pixelCount(); ++p) {
    double s = 0;
    for (int c = 0; c < 3; ++c) s += std::abs(double(b.pixels[p * 3 + c]) - a.pixels[p * 3 + c]);
    out.pixels[p] = float(s / 3.0);
  }
  return out;
}

Image relativeErrorMap(const Image& referenceLinear, const Image& testLinear, double epsilon) {
  requireSameSize(referenceLinear, testLinear, "error map");
  const Image a = toRgb(referenceLinear), b = toRgb(testLinear);
  Image out(a.width, a.height, 1);
  for (size_t p = 0; p < a.pixelCount(); ++p) {
    double s = 0;
    for (int c = 0; c < 3; ++c) {
      double r = a.pixels[p * 3 + c], d = double(b.pixels[p * 3 + c]) - r;
      s += d * d / (r * r + epsilon);
    }
    out.pixels[p] = float(s / 3.0);
  }
  return out;
}

Image displayToLinear(const Image& display, float exposure) {
  Image out = display;
  const float inv = exposure != 0.0f ? 1.0f / exposure : 1.0f;
  for (size_t p = 0; p < display.pixelCount(); ++p)
    for (int c = 0; c < std::min(3, display.channels); ++c) {
      float& v = out.pixels[p * display.channels + c];
      v = srgbDecode(std::clamp(v, 0.0f, 1.0f)) * inv;
    }
  return out;
}

}  // namespace gi::metrics
