// Image metrics for comparing a technique's frame with the reference path tracer
// (ALGORITHMS.md §8; definitions, constants and the cross-check in docs/METRICS.md):
//   - SSIM (Wang, Bovik, Sheikh, Simoncelli 2004) per RGB channel on display images, computed the
//     way scikit-image's structural_similarity(gaussian_weights=True, sigma=1.5,
//     use_sample_covariance=False, data_range=1) does, borders cropped;
//   - ten Brug's grade (seed 003 §4.2): 10 × mean_c MSSIM_c^1000 over pixels not black in both;
//     also as `grade255`, the same grade on an SSIM whose constants assume an 8-bit data range
//     (L = 255) while the display values are in [0, 1] — our reading of how his raw scores came out
//     ≥ 0.999 (docs/METRICS.md); for comparison with his tables only;
//   - PSNR on display images (peak 1); RMSE and relative MSE on linear HDR images;
//   - LDR-FLIP (Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström, Fairchild 2020, "FLIP: A
//     Difference Evaluator for Alternating Images"), its error map, and the magma colour map.
//
// "Display image": the output of gi::displayTransform (or a PNG as read), sRGB-encoded in [0,1].
// "Linear image": scene-referred linear Rec.709 RGB. Inputs may have 1 to 4 channels: one or two
// (grey, grey+alpha) are used as grey RGB, alpha is ignored. Both images must have the same size;
// a mismatch throws gi::Error. Everything runs on the host and is deterministic.
#pragma once
#include <array>
#include <cstddef>

#include "image/image.h"

namespace gi::metrics {

// ---- SSIM ----------------------------------------------------------------------------------
constexpr double kSsimK1 = 0.01, kSsimK2 = 0.03, kSsimDataRange = 1.0, kSsimSigma = 1.5;
// The data range behind `grade255`: C1 = (0.01·255)², C2 = (0.03·255)² on values in [0, 1], so the
// luminance and contrast terms sit within ~1e-3 of 1 for any image pair (docs/METRICS.md).
constexpr double kSsimDataRange8Bit = 255.0;
constexpr int kSsimRadius = 5;  // 11×11 window: scikit-image's truncate=3.5 → int(3.5·1.5 + 0.5)
constexpr int kSsimMinSize = 2 * kSsimRadius + 1;

struct SsimResult {
  double mean = 1.0;                        // mean over R, G, B of the per-channel MSSIM
  std::array<double, 3> channel{1, 1, 1};   // MSSIM of R, G, B: mean of the map over the interior
  // Per-pixel, per-channel SSIM (3 channels, full size). Pixels closer than kSsimRadius to an edge
  // are computed with mirrored (half-sample symmetric) borders for display, but are excluded
  // from every mean, as scikit-image crops them.
  Image map;
};
// Throws gi::Error when the images differ in size or are smaller than 11×11. `dataRange` is L in
// C1 = (K1·L)², C2 = (K2·L)²; every metric but `grade255` uses kSsimDataRange.
SsimResult ssim(const Image& referenceDisplay, const Image& testDisplay, double dataRange = kSsimDataRange);

// ---- ten Brug's grade ----------------------------------------------------------------------
constexpr double kGradeExponent = 1000.0;
// A pixel is black when each of its R, G, B display values is below 0.5/255, i.e. it would be
// stored as 0 in an 8-bit PNG (ten Brug compared 8-bit frames and gives no threshold).
constexpr float kBlackThreshold = 0.5f / 255.0f;

struct GradeResult {
  double grade = 10.0;                     // 10 × mean_c (max(0, MSSIM_c))^1000, in [0, 10]
  std::array<double, 3> mssim{1, 1, 1};    // per-channel MSSIM over the counted pixels
  size_t countedPixels = 0;                // interior pixels not black in both images
  size_t ignoredBlackPixels = 0;           // interior pixels black in both images
};
// Uses the SSIM map of `s` (from ssim() on the same images); pixels outside the SSIM interior are
// not counted. With no counted pixel (all black in both) the grade is 10.
GradeResult tenBrugGrade(const Image& referenceDisplay, const Image& testDisplay, const SsimResult& s);
GradeResult tenBrugGrade(const Image& referenceDisplay, const Image& testDisplay);

// ---- Pixel errors --------------------------------------------------------------------------
// PSNR = 10·log10(1 / MSE) over all pixels and R, G, B of two display images (peak value 1).
// +infinity when the images are identical.
double psnr(const Image& referenceDisplay, const Image& testDisplay);
double mse(const Image& reference, const Image& test);  // mean over pixels and R, G, B
double rmse(const Image& referenceLinear, const Image& testLinear);
// Relative MSE: mean over pixels and R, G, B of (test − ref)² / (ref² + ε).
constexpr double kRelMseEpsilon = 1e-2;
double relMse(const Image& referenceLinear, const Image& testLinear, double epsilon = kRelMseEpsilon);

// One-channel per-pixel maps (mean over R, G, B): |test − ref| and (test − ref)² / (ref² + ε).
Image absoluteErrorMap(const Image& reference, const Image& test);
Image relativeErrorMap(const Image& referenceLinear, const Image& testLinear, double epsilon = kRelMseEpsilon);

// ---- FLIP ----------------------------------------------------------------------------------
// Pixels per degree of visual angle for an observer `distanceM` from a monitor `widthM` wide
// showing `resolutionX` pixels across (small-angle approximation, as in the FLIP paper).
double pixelsPerDegree(double distanceM, double resolutionX, double widthM);
// 0.7 m from a 0.7 m wide 3840-pixel monitor: 67.0206 ppd, the FLIP paper's default.
constexpr double kDefaultPpd = 0.7 * (3840.0 / 0.7) * (3.14159265358979323846 / 180.0);

struct FlipResult {
  double mean = 0.0;  // mean of the error map over all pixels, in [0, 1]
  Image map;          // 1 channel, per-pixel LDR-FLIP error in [0, 1]
};
// LDR-FLIP of two display (sRGB-encoded) images, values clamped to [0, 1].
FlipResult flip(const Image& referenceDisplay, const Image& testDisplay, double ppd = kDefaultPpd);

// ---- Heat maps -----------------------------------------------------------------------------
// Matplotlib's magma colour map (256 sRGB-encoded entries), as FLIP's tools show error maps.
const std::array<std::array<float, 3>, 256>& magmaTable();
// 3-channel display image: each value v of the one-channel `map` (scaled by 1/maxValue and
// clamped to [0, 1]) picks magma entry round(255·v). Write it with writeImage(…png).
Image magmaHeatmap(const Image& map, double maxValue = 1.0);

// Helpers shared with `gi compare`: the image as 3-channel RGB (grey replicated, alpha dropped),
// and the inverse of displayTransform for display-encoded inputs: srgbDecode(v) / exposure.
Image toRgb(const Image& image);
Image displayToLinear(const Image& display, float exposure);

}  // namespace gi::metrics
