// LDR-FLIP, from Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström, Fairchild 2020, "FLIP: A
// Difference Evaluator for Alternating Images" (HPG 2020), §3 and its constants:
//
//  colour pipeline
//   1. sRGB display values → linear RGB → CIE XYZ (D65) → YCxCz, the linearized opponent space
//      of Flohr et al.: Y = 116·Y/Yn − 16, Cx = 500·(X/Xn − Y/Yn), Cz = 200·(Y/Yn − Z/Zn).
//   2. Contrast-sensitivity filtering of each opponent channel with the paper's spatial filters,
//      sums of Gaussians in visual degrees: S(x) = Σ a_i·√(π/b_i)·exp(−π²x²/b_i) with
//      achromatic (a1, b1) = (1, 0.0047); red-green (1, 0.0053);
//      blue-yellow (34.1, 0.04) + (13.5, 0.025). Kernel radius ⌈3·√(b_max/(2π²))·ppd⌉ pixels,
//      b_max = 0.04; each 2D kernel is normalized to sum 1.
//   3. Back to linear RGB, clamped to [0, 1] (the filtered colour must stay displayable), then to
//      CIELab (D65), then the Hunt adjustment a, b ← 0.01·L·a, 0.01·L·b.
//   4. HyAB distance |ΔL| + √(Δa² + Δb²), raised to qc = 0.7, then remapped to [0, 1]: errors
//      below pc·cmax map linearly to [0, pt], the rest linearly to [pt, 1], with pc = 0.4,
//      pt = 0.95 and cmax = HyAB(Hunt(Lab(green)), Hunt(Lab(blue)))^qc, the largest distance
//      between two displayable colours.
//  feature pipeline
//   5. On the achromatic channel normalized to [0, 1] ((Y + 16)/116 of the unfiltered image):
//      edges by the first and points by the second derivative of a Gaussian with
//      σ = 0.5·w·ppd pixels, w = 0.082° (radius ⌈3σ⌉), applied along x and along y; positive
//      weights normalized to sum 1, negative to −1. Feature strength = length of the (x, y)
//      response vector.
//   6. ΔEf = (max(|edge_ref − edge_test|, |point_ref − point_test|) / √2)^qf, qf = 0.5.
//  final: ΔE = ΔEc^(1 − ΔEf) per pixel; the score is the mean over all pixels.
//
// Implementation choices (those of NVIDIA's reference implementation, which our cross-check
// compares against through the flip_evaluator package): every Gaussian is separable, so the
// filters run as x then y passes — the blue-yellow sum of two Gaussians as two separable passes
// whose 1D kernels are scaled by √(a_i·√(π/b_i)) and normalized together so the 2D sum is 1;
// pixels beyond the image repeat the edge pixel (clamp); arithmetic in float32, the mean in
// double. The RGB→XYZ matrix is the sRGB one from the IEC 61966-2-1 primaries and D65 white as
// exact fractions, and the reference white (Xn, Yn, Zn) is its row sums (linear RGB (1,1,1)).
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "metrics/filter.h"
#include "metrics/metrics.h"
#include "util/error.h"

namespace gi::metrics {

using detail::Border;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Paper constants.
constexpr double kQc = 0.7, kPc = 0.4, kPt = 0.95, kW = 0.082;  // qf = 0.5 is a sqrt below
struct Csf { double a1, b1, a2, b2; };
constexpr Csf kCsfA{1.0, 0.0047, 0.0, 1e-5}, kCsfRG{1.0, 0.0053, 0.0, 1e-5}, kCsfBY{34.1, 0.04, 13.5, 0.025};
constexpr double kCsfMaxB = 0.04;

struct Mat3 { double m[3][3]; };

// Linear sRGB → XYZ (D65), as exact fractions of the sRGB primaries.
constexpr Mat3 kRgbToXyz{{{10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0},
                          {2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0},
                          {1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0}}};

Mat3 inverse(const Mat3& a) {
  const auto& m = a.m;
  double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  Mat3 r;
  r.m[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) / det;
  r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det;
  r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det;
  r.m[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) / det;
  r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det;
  r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det;
  r.m[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) / det;
  r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det;
  r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det;
  return r;
}

// Float copies of the colour constants, computed once.
struct Colour {
  float toXyz[3][3], toRgb[3][3];
  float white[3], invWhite[3];
  Colour() {
    Mat3 inv = inverse(kRgbToXyz);
    for (int i = 0; i < 3; ++i) {
      double w = kRgbToXyz.m[i][0] + kRgbToXyz.m[i][1] + kRgbToXyz.m[i][2];
      white[i] = float(w);
      invWhite[i] = float(1.0 / w);
      for (int j = 0; j < 3; ++j) {
        toXyz[i][j] = float(kRgbToXyz.m[i][j]);
        toRgb[i][j] = float(inv.m[i][j]);
      }
    }
  }
  void mul(const float (&m)[3][3], const float in[3], float out[3]) const {
    for (int i = 0; i < 3; ++i) out[i] = m[i][0] * in[0] + m[i][1] * in[1] + m[i][2] * in[2];
  }
  void rgbToYcxcz(const float rgb[3], float out[3]) const {
    float xyz[3];
    mul(toXyz, rgb, xyz);
    float x = xyz[0] * invWhite[0], y = xyz[1] * invWhite[1], z = xyz[2] * invWhite[2];
    out[0] = 116.0f * y - 16.0f;
    out[1] = 500.0f * (x - y);
    out[2] = 200.0f * (y - z);
  }
  void ycxczToRgb(const float in[3], float rgb[3]) const {
    float y = (in[0] + 16.0f) / 116.0f;
    float xyz[3] = {(y + in[1] / 500.0f) * white[0], y * white[1], (y - in[2] / 200.0f) * white[2]};
    mul(toRgb, xyz, rgb);
  }
  // Linear RGB → CIELab (D65) → Hunt-adjusted (L, 0.01·L·a, 0.01·L·b).
  void rgbToHuntLab(const float rgb[3], float out[3]) const {
    constexpr float delta = 6.0f / 29.0f;
    constexpr float deltaCube = delta * delta * delta;
    constexpr float linearSlope = 1.0f / (3.0f * delta * delta);
    float xyz[3];
    mul(toXyz, rgb, xyz);
    float f[3];
    for (int i = 0; i < 3; ++i) {
      float t = xyz[i] * invWhite[i];
      f[i] = t > deltaCube ? std::cbrt(t) : linearSlope * t + 4.0f / 29.0f;
    }
    float L = 116.0f * f[1] - 16.0f, a = 500.0f * (f[0] - f[1]), b = 200.0f * (f[1] - f[2]);
    out[0] = L;
    out[1] = 0.01f * L * a;
    out[2] = 0.01f * L * b;
  }
};

const Colour& colour() {
  static const Colour c;
  return c;
}

float hyab(const float p[3], const float q[3]) {
  float da = p[1] - q[1], db = p[2] - q[2];
  return std::abs(p[0] - q[0]) + std::sqrt(da * da + db * db);
}

// 1D factor of a CSF Gaussian a·√(π/b)·exp(−π²x²/b) sampled at pixel offsets; `weight` scales it
// (for the two-Gaussian blue-yellow filter, √(a·√(π/b)) so that the outer product carries a·√(π/b)).
std::vector<double> csfFactor(double weight, double b, int radius, double ppd) {
  std::vector<double> k(2 * radius + 1);
  for (int i = -radius; i <= radius; ++i) {
    double x = i / ppd;  // degrees
    k[i + radius] = weight * std::exp(-kPi * kPi * x * x / b);
  }
  return k;
}

std::vector<float> toFloat(const std::vector<double>& k) { return std::vector<float>(k.begin(), k.end()); }

struct Filters {
  std::vector<float> a, rg, by1, by2;  // CSF (1D, separable)
  std::vector<float> g, dg, ddg;       // feature detection: Gaussian, 1st and 2nd derivative

  explicit Filters(double ppd) {
    const int r = int(std::ceil(3.0 * std::sqrt(kCsfMaxB / (2.0 * kPi * kPi)) * ppd));
    // Single-Gaussian channels (a2 = 0): normalize the 1D factor; the 2D outer product then sums to 1.
    auto single = [&](const Csf& c) {
      auto k = csfFactor(1.0, c.b1, r, ppd);
      double s = 0;
      for (double v : k) s += v;
      for (double& v : k) v /= s;
      return toFloat(k);
    };
    a = single(kCsfA);
    rg = single(kCsfRG);
    // Blue-yellow: K(x,y) = u1(x)u1(y) + u2(x)u2(y) with u_i = √(a_i√(π/b_i))·exp(−π²x²/b_i);
    // ΣK = (Σu1)² + (Σu2)², so dividing both factors by √ΣK normalizes the 2D kernel.
    auto u1 = csfFactor(std::sqrt(kCsfBY.a1 * std::sqrt(kPi / kCsfBY.b1)), kCsfBY.b1, r, ppd);
    auto u2 = csfFactor(std::sqrt(kCsfBY.a2 * std::sqrt(kPi / kCsfBY.b2)), kCsfBY.b2, r, ppd);
    double s1 = 0, s2 = 0;
    for (double v : u1) s1 += v;
    for (double v : u2) s2 += v;
    double norm = 1.0 / std::sqrt(s1 * s1 + s2 * s2);
    for (double& v : u1) v *= norm;
    for (double& v : u2) v *= norm;
    by1 = toFloat(u1);
    by2 = toFloat(u2);

    const double sd = 0.5 * kW * ppd;
    const int fr = int(std::ceil(3.0 * sd));
    std::vector<double> gd(2 * fr + 1), dgd(2 * fr + 1), ddgd(2 * fr + 1);
    double gs = 0, dPos = 0, dNeg = 0, ddPos = 0, ddNeg = 0;
    for (int i = -fr; i <= fr; ++i) {
      double gv = std::exp(-(double(i) * i) / (2.0 * sd * sd));
      double d1 = -double(i) * gv;
      double d2 = (double(i) * i / (sd * sd) - 1.0) * gv;
      gd[i + fr] = gv;
      dgd[i + fr] = d1;
      ddgd[i + fr] = d2;
      gs += gv;
      (d1 > 0 ? dPos : dNeg) += std::abs(d1);
      (d2 > 0 ? ddPos : ddNeg) += std::abs(d2);
    }
    // The Gaussian factor along the other axis sums to 1, so the 2D filter's positive and
    // negative parts keep the ±1 sums of the 1D derivative factor.
    for (int i = 0; i < 2 * fr + 1; ++i) {
      gd[i] /= gs;
      dgd[i] /= dgd[i] > 0 ? dPos : dNeg;
      ddgd[i] /= ddgd[i] > 0 ? ddPos : ddNeg;
    }
    g = toFloat(gd);
    dg = toFloat(dgd);
    ddg = toFloat(ddgd);
  }
};

struct Planes {
  int w = 0, h = 0;
  std::vector<float> c[3];
  Planes(int w_, int h_) : w(w_), h(h_) {
    for (auto& p : c) p.assign(size_t(w) * h, 0.0f);
  }
};

// srgbDecode, from a table when the value is an exact 8-bit level (every PNG input): the same
// numbers, without a powf per channel.
float decodeSrgb(float v) {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = srgbDecode(float(i) / 255.0f);
    return t;
  }();
  v = std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
  int level = int(v * 255.0f + 0.5f);
  return float(level) / 255.0f == v ? table[level] : srgbDecode(v);
}

Planes toYcxcz(const Image& display) {
  const Colour& col = colour();
  const Image rgb = toRgb(display);
  Planes out(rgb.width, rgb.height);
  detail::parallelRows(rgb.height, [&](int y0, int y1) {
    for (size_t p = size_t(y0) * rgb.width; p < size_t(y1) * rgb.width; ++p) {
      float lin[3], o[3];
      for (int c = 0; c < 3; ++c) lin[c] = decodeSrgb(rgb.pixels[p * 3 + c]);
      col.rgbToYcxcz(lin, o);
      for (int c = 0; c < 3; ++c) out.c[c][p] = o[c];
    }
  });
  return out;
}

// CSF-filtered image in Hunt-adjusted Lab (3 planes).
Planes filteredHuntLab(const Planes& ycxcz, const Filters& f) {
  const int w = ycxcz.w, h = ycxcz.h;
  const size_t n = size_t(w) * h;
  Planes filtered(w, h);
  std::vector<float> tmp(n);
  detail::convolveSeparable(ycxcz.c[0].data(), filtered.c[0].data(), w, h, f.a, f.a, Border::Clamp);
  detail::convolveSeparable(ycxcz.c[1].data(), filtered.c[1].data(), w, h, f.rg, f.rg, Border::Clamp);
  detail::convolveSeparable(ycxcz.c[2].data(), filtered.c[2].data(), w, h, f.by1, f.by1, Border::Clamp);
  detail::convolveSeparable(ycxcz.c[2].data(), tmp.data(), w, h, f.by2, f.by2, Border::Clamp);
  for (size_t p = 0; p < n; ++p) filtered.c[2][p] += tmp[p];

  const Colour& col = colour();
  Planes lab(w, h);
  detail::parallelRows(h, [&](int y0, int y1) {
    for (size_t p = size_t(y0) * w; p < size_t(y1) * w; ++p) {
      float in[3] = {filtered.c[0][p], filtered.c[1][p], filtered.c[2][p]}, rgb[3], o[3];
      col.ycxczToRgb(in, rgb);
      for (float& v : rgb) v = std::clamp(v, 0.0f, 1.0f);
      col.rgbToHuntLab(rgb, o);
      for (int c = 0; c < 3; ++c) lab.c[c][p] = o[c];
    }
  });
  return lab;
}

// Edge and point strengths (lengths of the x/y filter responses) of the normalized achromatic channel.
struct Features {
  std::vector<float> edge, point;
};

Features features(const Planes& ycxcz, const Filters& f) {
  const int w = ycxcz.w, h = ycxcz.h;
  const size_t n = size_t(w) * h;
  std::vector<float> y(n);
  for (size_t p = 0; p < n; ++p) y[p] = (ycxcz.c[0][p] + 16.0f) / 116.0f;
  std::vector<float> rowG(n), rowD(n), rowDD(n), dx(n), dy(n), ddx(n), ddy(n);
  detail::convolveRows(y.data(), rowG.data(), w, h, f.g, Border::Clamp);
  detail::convolveRows(y.data(), rowD.data(), w, h, f.dg, Border::Clamp);
  detail::convolveRows(y.data(), rowDD.data(), w, h, f.ddg, Border::Clamp);
  detail::convolveColumns(rowD.data(), dx.data(), w, h, f.g, Border::Clamp);
  detail::convolveColumns(rowDD.data(), ddx.data(), w, h, f.g, Border::Clamp);
  detail::convolveColumns(rowG.data(), dy.data(), w, h, f.dg, Border::Clamp);
  detail::convolveColumns(rowG.data(), ddy.data(), w, h, f.ddg, Border::Clamp);
  Features out;
  out.edge.resize(n);
  out.point.resize(n);
  detail::parallelRows(h, [&](int y0, int y1) {
    for (size_t p = size_t(y0) * w; p < size_t(y1) * w; ++p) {
      out.edge[p] = std::sqrt(dx[p] * dx[p] + dy[p] * dy[p]);
      out.point[p] = std::sqrt(ddx[p] * ddx[p] + ddy[p] * ddy[p]);
    }
  });
  return out;
}

}  // namespace

double pixelsPerDegree(double distanceM, double resolutionX, double widthM) {
  return distanceM * (resolutionX / widthM) * (kPi / 180.0);
}

FlipResult flip(const Image& referenceDisplay, const Image& testDisplay, double ppd) {
  if (referenceDisplay.width != testDisplay.width || referenceDisplay.height != testDisplay.height)
    throw Error("flip: image sizes differ (reference " + std::to_string(referenceDisplay.width) + "x" +
                std::to_string(referenceDisplay.height) + ", test " + std::to_string(testDisplay.width) + "x" +
                std::to_string(testDisplay.height) + ")");
  if (!(ppd > 0.0) || !std::isfinite(ppd)) throw Error("flip: pixels per degree must be positive (got " + std::to_string(ppd) + ")");
  const int w = referenceDisplay.width, h = referenceDisplay.height;
  FlipResult result;
  result.map = Image(w, h, 1);
  if (w == 0 || h == 0) return result;

  const Filters filters(ppd);
  const Planes refY = toYcxcz(referenceDisplay), testY = toYcxcz(testDisplay);
  const Planes refLab = filteredHuntLab(refY, filters), testLab = filteredHuntLab(testY, filters);
  const Features refF = features(refY, filters), testF = features(testY, filters);

  // cmax: HyAB distance between Hunt-adjusted green and blue, the most different primaries.
  const Colour& col = colour();
  float green[3] = {0, 1, 0}, blue[3] = {0, 0, 1}, gl[3], bl[3];
  col.rgbToHuntLab(green, gl);
  col.rgbToHuntLab(blue, bl);
  const float cmax = std::pow(hyab(gl, bl), float(kQc));
  const float pccmax = float(kPc) * cmax;
  const float pt = float(kPt);
  const float invSqrt2 = float(1.0 / std::sqrt(2.0));

  std::vector<double> rowSum(h, 0.0);
  detail::parallelRows(h, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      double sum = 0;
      for (int x = 0; x < w; ++x) {
        size_t p = size_t(y) * w + x;
        float a[3] = {refLab.c[0][p], refLab.c[1][p], refLab.c[2][p]};
        float b[3] = {testLab.c[0][p], testLab.c[1][p], testLab.c[2][p]};
        float dc = std::pow(hyab(a, b), float(kQc));
        dc = dc < pccmax ? dc * (pt / pccmax) : pt + (dc - pccmax) / (cmax - pccmax) * (1.0f - pt);
        float df = std::max(std::abs(refF.edge[p] - testF.edge[p]), std::abs(refF.point[p] - testF.point[p]));
        df = std::sqrt(invSqrt2 * df);  // ^qf, qf = 0.5
        float e = std::pow(dc, 1.0f - df);
        result.map.pixels[p] = e;
        sum += e;
      }
      rowSum[y] = sum;
    }
  });
  double total = 0;
  for (double s : rowSum) total += s;
  result.mean = total / double(size_t(w) * h);
  return result;
}

}  // namespace gi::metrics
