// Host images (float, interleaved channels) and their files. PNG/JPG are read and written as
// 8-bit sRGB-encoded display values; EXR as linear float. Writers never leave partial files.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace gi {

struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;  // row-major, top row first, `channels` floats per pixel

  Image() = default;
  Image(int w, int h, int c, float value = 0.0f) : width(w), height(h), channels(c), pixels(size_t(w) * h * c, value) {}
  float* at(int x, int y) { return &pixels[(size_t(y) * width + x) * channels]; }
  const float* at(int x, int y) const { return &pixels[(size_t(y) * width + x) * channels]; }
  size_t pixelCount() const { return size_t(width) * height; }
};

// Reads any format OpenImageIO knows. Values as stored (PNG: 0..1 display values; EXR: linear).
Image readImage(const std::filesystem::path& path);

// By extension: .exr writes float32 (linear values as given); .png/.jpg write 8-bit, clamping the
// given values to [0, 1] (pass display-transformed images). Atomic: no partial file on failure.
void writeImage(const std::filesystem::path& path, const Image& image);

// Shared display transform (ALGORITHMS.md §0): exposure, clamp to [0,1], sRGB transfer curve.
// Channels beyond RGB (alpha) are copied unchanged.
Image displayTransform(const Image& linear, float exposure);

float srgbEncode(float linear);  // [0,1] -> [0,1]
float srgbDecode(float encoded);

}  // namespace gi
