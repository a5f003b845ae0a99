// Separable 2D convolution of one image plane, and a row-parallel loop, shared by the metrics
// (SSIM's Gaussian window, FLIP's contrast-sensitivity and feature filters). Internal to
// src/metrics: the public API is metrics.h.
//
// Every output row depends only on input rows, so rows are split across threads; the result is
// bit-identical whatever the thread count (no cross-row reductions happen here).
#pragma once
#include <functional>
#include <vector>

namespace gi::metrics::detail {

// How samples outside the image are defined.
enum class Border {
  Clamp,    // edge pixel repeated (numpy 'edge'); FLIP's reference implementation does this
  Reflect,  // half-sample symmetric, d c b a | a b c d (scipy.ndimage 'reflect')
};

// Maps a possibly out-of-range coordinate into [0, n).
int borderIndex(int i, int n, Border border);

// Runs body(y0, y1) over [0, rows) split into contiguous chunks, one per hardware thread (at most
// 16). Small jobs run inline.
void parallelRows(int rows, const std::function<void(int y0, int y1)>& body);

// dst = src convolved with kx along x then ky along y (both odd-length, centred; correlation, so
// kernels need not be symmetric). dst must not alias src. T is float or double.
template <typename T>
void convolveSeparable(const T* src, T* dst, int width, int height, const std::vector<T>& kx,
                       const std::vector<T>& ky, Border border);

// Only the x pass (rows), or only the y pass (columns).
template <typename T>
void convolveRows(const T* src, T* dst, int width, int height, const std::vector<T>& k, Border border);
template <typename T>
void convolveColumns(const T* src, T* dst, int width, int height, const std::vector<T>& k, Border border);

}  // namespace gi::metrics::detail
