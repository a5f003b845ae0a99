// Separable convolution and row-parallel loop for the metrics (see filter.h).
#include "metrics/filter.h"

#include <algorithm>
#include <thread>

namespace gi::metrics::detail {

int borderIndex(int i, int n, Border border) {
  if (i >= 0 && i < n) return i;
  if (border == Border::Clamp) return std::clamp(i, 0, n - 1);
  // Half-sample symmetric reflection has period 2n; folding handles kernels wider than the image.
  int period = 2 * n;
  int m = i % period;
  if (m < 0) m += period;
  return m < n ? m : period - 1 - m;
}

void parallelRows(int rows, const std::function<void(int, int)>& body) {
  unsigned hw = std::max(1u, std::min(16u, std::thread::hardware_concurrency()));
  int chunks = std::min<int>(static_cast<int>(hw), std::max(1, rows / 16));
  if (chunks <= 1) {
    body(0, rows);
    return;
  }
  std::vector<std::thread> threads;
  threads.reserve(chunks - 1);
  for (int c = 1; c < chunks; ++c) {
    int y0 = int(int64_t(rows) * c / chunks), y1 = int(int64_t(rows) * (c + 1) / chunks);
    threads.emplace_back(body, y0, y1);
  }
  body(0, int(int64_t(rows) / chunks));
  for (auto& t : threads) t.join();
}

// Sums k[i]·row_i[x] over the taps for x in [x0, x0 + n), where row_i = rows[i] (already offset).
// Outputs are produced in blocks of kBlock held in registers across all taps, which is what makes
// these passes fast (one store per output instead of one load/store per tap).
constexpr int kBlock = 16;

template <typename T, int N>
inline void blockSum(const std::vector<T>& k, const T* const* rows, int x0, T* out) {
  T acc[N] = {};
  for (size_t i = 0; i < k.size(); ++i) {
    const T w = k[i];
    const T* p = rows[i] + x0;
    for (int j = 0; j < N; ++j) acc[j] += w * p[j];
  }
  for (int j = 0; j < N; ++j) out[x0 + j] = acc[j];
}

template <typename T>
void sumTaps(const std::vector<T>& k, const T* const* rows, int width, T* out) {
  int x0 = 0;
  for (; x0 + kBlock <= width; x0 += kBlock) blockSum<T, kBlock>(k, rows, x0, out);
  for (; x0 < width; ++x0) blockSum<T, 1>(k, rows, x0, out);
}

template <typename T>
void convolveRows(const T* src, T* dst, int width, int height, const std::vector<T>& k, Border border) {
  const int r = int(k.size()) / 2;
  parallelRows(height, [&](int y0, int y1) {
    std::vector<T> padded(size_t(width) + 2 * r);
    std::vector<const T*> rows(k.size());
    for (size_t i = 0; i < k.size(); ++i) rows[i] = padded.data() + i;  // tap i reads padded[x + i]
    for (int y = y0; y < y1; ++y) {
      const T* row = src + size_t(y) * width;
      for (int x = -r; x < width + r; ++x) padded[x + r] = row[borderIndex(x, width, border)];
      sumTaps(k, rows.data(), width, dst + size_t(y) * width);
    }
  });
}

template <typename T>
void convolveColumns(const T* src, T* dst, int width, int height, const std::vector<T>& k, Border border) {
  const int r = int(k.size()) / 2;
  parallelRows(height, [&](int y0, int y1) {
    std::vector<const T*> rows(k.size());
    for (int y = y0; y < y1; ++y) {
      for (int i = 0; i < int(k.size()); ++i) rows[i] = src + size_t(borderIndex(y + i - r, height, border)) * width;
      sumTaps(k, rows.data(), width, dst + size_t(y) * width);
    }
  });
}

template <typename T>
void convolveSeparable(const T* src, T* dst, int width, int height, const std::vector<T>& kx,
                       const std::vector<T>& ky, Border border) {
  std::vector<T> tmp(size_t(width) * height);
  convolveRows(src, tmp.data(), width, height, kx, border);
  convolveColumns(tmp.data(), dst, width, height, ky, border);
}

template void convolveRows<float>(const float*, float*, int, int, const std::vector<float>&, Border);
template void convolveRows<double>(const double*, double*, int, int, const std::vector<double>&, Border);
template void convolveColumns<float>(const float*, float*, int, int, const std::vector<float>&, Border);
template void convolveColumns<double>(const double*, double*, int, int, const std::vector<double>&, Border);
template void convolveSeparable<float>(const float*, float*, int, int, const std::vector<float>&,
                                       const std::vector<float>&, Border);
template void convolveSeparable<double>(const double*, double*, int, int, const std::vector<double>&,
                                        const std::vector<double>&, Border);

}  // namespace gi::metrics::detail
