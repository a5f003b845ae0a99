// Texture decoding and mip chains (see textures.h).
#include "scene/textures.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <functional>
#include <memory>
#include <thread>

// stb_image is compiled into this file with internal linkage: the tinygltf shared library links
// its own copy (libstb), and private symbols keep the two from interposing each other.
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_NO_STDIO  // images arrive as bytes (files are read by tinygltf), never by file name
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"  // static copies of stb entry points we do not call
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // false positive in stb's memory reader
#include <stb/stb_image.h>
#pragma GCC diagnostic pop

#include "image/image.h"
#include "util/error.h"

namespace gi {
namespace {

// Runs job(i) for i in order[0..n) on all hardware threads. Every job runs even if one throws;
// the exception of the earliest failing position in `order` is rethrown, so the message does not
// depend on thread timing.
void runInParallel(const std::vector<size_t>& order, const std::function<void(size_t)>& job) {
  std::vector<std::exception_ptr> failures(order.size());
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t k; (k = next.fetch_add(1)) < order.size();) {
      try {
        job(order[k]);
      } catch (...) {
        failures[k] = std::current_exception();
      }
    }
  };
  size_t threadCount = std::min<size_t>(std::max(1u, std::thread::hardware_concurrency()), order.size());
  std::vector<std::thread> threads;
  for (size_t t = 1; t < threadCount; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& f : failures)
    if (f) std::rethrow_exception(f);
}

// sRGB-correct averaging without pow() per texel: codes decode to 16-bit fixed-point linear
// values (1/65535 steps, 20 per sRGB code even at the darkest codes), whose average indexes a
// 64 K-entry table of the rounded re-encoded code.
struct SrgbTables {
  std::array<uint16_t, 256> toLinear16;
  std::vector<uint8_t> fromLinear16 = std::vector<uint8_t>(65536);
};

const SrgbTables& srgbTables() {
  static const SrgbTables tables = [] {
    SrgbTables t;
    for (int k = 0; k < 256; ++k) t.toLinear16[k] = uint16_t(std::lround(65535.0f * srgbDecode(k / 255.0f)));
    for (int v = 0; v < 65536; ++v) t.fromLinear16[v] = uint8_t(std::lround(255.0f * srgbEncode(v / 65535.0f)));
    return t;
  }();
  return tables;
}

// One box-filtered level from its parent. Odd parent sizes drop the last row/column's
// half-weight (a plain 2×2 box); a parent of size 1 along an axis is reused for both taps.
void downsample(const uint8_t* parent, int pw, int ph, uint8_t* child, int cw, int ch, bool srgb) {
  const SrgbTables& t = srgbTables();
  for (int y = 0; y < ch; ++y) {
    int y0 = std::min(2 * y, ph - 1), y1 = std::min(2 * y + 1, ph - 1);
    for (int x = 0; x < cw; ++x) {
      int x0 = std::min(2 * x, pw - 1), x1 = std::min(2 * x + 1, pw - 1);
      const uint8_t* taps[4] = {parent + (size_t(y0) * pw + x0) * 4, parent + (size_t(y0) * pw + x1) * 4,
                                parent + (size_t(y1) * pw + x0) * 4, parent + (size_t(y1) * pw + x1) * 4};
      uint8_t* out = child + (size_t(y) * cw + x) * 4;
      for (int c = 0; c < 3; ++c) {
        if (srgb) {
          uint32_t sum = t.toLinear16[taps[0][c]] + t.toLinear16[taps[1][c]] + t.toLinear16[taps[2][c]] +
                         t.toLinear16[taps[3][c]];
          out[c] = t.fromLinear16[(sum + 2) / 4];
        } else {
          out[c] = static_cast<uint8_t>((taps[0][c] + taps[1][c] + taps[2][c] + taps[3][c] + 2) / 4);
        }
      }
      out[3] = static_cast<uint8_t>((taps[0][3] + taps[1][3] + taps[2][3] + taps[3][3] + 2) / 4);
    }
  }
}

// stb_image's RGBA8 decode of one image, freed when it goes out of scope.
struct DecodedImage {
  int width = 0, height = 0;
  std::unique_ptr<stbi_uc, void (*)(void*)> pixels{nullptr, stbi_image_free};
};

DecodedImage decodeRgba8(const EncodedImage& image) {
  if (image.bytes.empty()) throw Error("image '" + image.name + "' is empty");
  if (image.bytes.size() > size_t(INT32_MAX)) throw Error("image '" + image.name + "' is too large");
  DecodedImage out;
  int channelsInFile = 0;
  out.pixels.reset(stbi_load_from_memory(image.bytes.data(), static_cast<int>(image.bytes.size()), &out.width,
                                         &out.height, &channelsInFile, 4));
  if (!out.pixels) throw Error("cannot decode image '" + image.name + "': " + stbi_failure_reason());
  return out;
}

}  // namespace

int mipLevelCount(int width, int height) {
  int levels = 1;
  for (int size = std::max(width, height); size > 1; size >>= 1) ++levels;
  return levels;
}

Texture makeTexture(std::string name, int width, int height, const uint8_t* level0, bool srgb) {
  if (width <= 0 || height <= 0)
    throw Error("texture '" + name + "': bad size " + std::to_string(width) + "x" + std::to_string(height));
  Texture tex;
  tex.name = std::move(name);
  tex.width = width;
  tex.height = height;
  tex.levels = mipLevelCount(width, height);
  tex.srgb = srgb;

  size_t total = 0;
  for (int l = 0; l < tex.levels; ++l) total += size_t(std::max(1, width >> l)) * std::max(1, height >> l) * 4;
  tex.rgba8.resize(total);
  std::copy(level0, level0 + size_t(width) * height * 4, tex.rgba8.begin());

  size_t parentOffset = 0;
  for (int l = 1; l < tex.levels; ++l) {
    int pw = std::max(1, width >> (l - 1)), ph = std::max(1, height >> (l - 1));
    int cw = std::max(1, width >> l), ch = std::max(1, height >> l);
    size_t childOffset = parentOffset + size_t(pw) * ph * 4;
    downsample(tex.rgba8.data() + parentOffset, pw, ph, tex.rgba8.data() + childOffset, cw, ch, srgb);
    parentOffset = childOffset;
  }
  return tex;
}

std::vector<Texture> decodeTextures(const std::vector<EncodedImage>& images,
                                    const std::vector<TextureRequest>& requests) {
  std::vector<std::vector<size_t>> requestsOfImage(images.size());
  for (size_t r = 0; r < requests.size(); ++r) {
    if (requests[r].image >= images.size())
      throw Error("texture request " + std::to_string(r) + " names image " + std::to_string(requests[r].image) +
                  " of " + std::to_string(images.size()));
    requestsOfImage[requests[r].image].push_back(r);
  }

  // One job per used image: decode, then build each texture that uses it. Largest files first so
  // the last job to start is a short one.
  std::vector<size_t> order;
  for (size_t i = 0; i < images.size(); ++i)
    if (!requestsOfImage[i].empty()) order.push_back(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return images[a].bytes.size() > images[b].bytes.size(); });

  std::vector<Texture> textures(requests.size());
  runInParallel(order, [&](size_t i) {
    DecodedImage decoded = decodeRgba8(images[i]);
    for (size_t r : requestsOfImage[i])
      textures[r] = makeTexture(images[i].name, decoded.width, decoded.height, decoded.pixels.get(), requests[r].srgb);
  });
  return textures;
}

}  // namespace gi
