#include "reference_store.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "test_support.h"

namespace gi::test {

namespace {

std::filesystem::path storedPath(const std::string& key) {
  return std::filesystem::path(GI_SOURCE_DIR) / "tests" / "data" / "references" / (key + ".exr");
}

struct Render {
  Image mean, variance;
};

Render renderReference(const Scene& scene, const GiView& view, PathTracerOptions options, uint32_t seed, int spp) {
  options.seed = seed;
  PathTracer pt(context(), scene, view, options);
  while (pt.samplesDone() < spp) pt.addSamples(std::min(64, spp - pt.samplesDone()));
  return {pt.image(), pt.variance()};
}

}  // namespace

// Compares 8×8 block means of the stored image with a fresh render, each difference scaled by the
// fresh render's standard error of that block mean (the stored image's own noise is ≥ 100× smaller
// and ignored). Returns an empty string when consistent, else what disagrees.
std::string referenceMismatch(const Image& stored, const Image& freshMean, const Image& freshVariance,
                              const StoredReferenceCheck& check) {
  if (stored.width != freshMean.width || stored.height != freshMean.height) return "image sizes differ";
  const int B = 8;
  int blocks = 0, outliers = 0;
  double worstZ = 0;
  for (int by = 0; by + B <= stored.height; by += B)
    for (int bx = 0; bx + B <= stored.width; bx += B)
      for (int c = 0; c < 3; ++c) {
        double sumStored = 0, sumFresh = 0, sumVar = 0;
        for (int y = by; y < by + B; ++y)
          for (int x = bx; x < bx + B; ++x) {
            sumStored += stored.at(x, y)[c];
            sumFresh += freshMean.at(x, y)[c];
            sumVar += freshVariance.at(x, y)[c];
          }
        // Blocks lit only by rare paths can have zero variance at low spp; a small absolute floor
        // (1e-4 of the block mean) keeps them from turning float rounding into "infinite" z.
        double stdErr = std::sqrt(sumVar) + 1e-4 * std::fabs(sumStored) + 1e-12;
        double z = std::fabs(sumStored - sumFresh) / stdErr;
        worstZ = std::max(worstZ, z);
        if (z > check.maxBlockZ) ++outliers;
        ++blocks;
      }
  if (blocks == 0) return "image smaller than one 8x8 block";
  double fraction = double(outliers) / blocks;
  if (fraction <= check.maxOutlierFraction) return "";
  char msg[200];
  std::snprintf(msg, sizeof msg, "%d of %d block means differ by more than %.1f standard errors (worst %.1f)", outliers,
                blocks, check.maxBlockZ, worstZ);
  return msg;
}

Image convergedReference(const std::string& key, const Scene& scene, const GiView& view,
                         const PathTracerOptions& options, int fallbackSpp, const StoredReferenceCheck& check) {
  const std::filesystem::path file = storedPath(key);
  if (const char* w = std::getenv("GI_TEST_WRITE_REFERENCES")) {
    int spp = std::atoi(w);
    if (spp < 1) throw std::runtime_error("GI_TEST_WRITE_REFERENCES must be a sample count >= 1");
    Render r = renderReference(scene, view, options, 1, spp);
    std::filesystem::create_directories(file.parent_path());
    writeImage(file, r.mean);
    std::printf("[reference store] wrote %s (%d spp)\n", file.string().c_str(), spp);
    return r.mean;
  }
  if (!std::filesystem::exists(file)) {
    std::printf("[reference store] no stored reference '%s'; rendering %d spp in the test (noisier)\n", key.c_str(),
                fallbackSpp);
    return renderReference(scene, view, options, 1, fallbackSpp).mean;
  }
  Image stored = readImage(file);
  if (stored.width != options.width || stored.height != options.height) {
    ADD_FAILURE() << "stored reference " << file << " is " << stored.width << "x" << stored.height << ", the test asks "
                  << options.width << "x" << options.height << "; regenerate it (tests/reference_store.h)";
    return renderReference(scene, view, options, 1, fallbackSpp).mean;
  }
  Render fresh = renderReference(scene, view, options, 2, check.checkSpp);
  std::string problem = referenceMismatch(stored, fresh.mean, fresh.variance, check);
  if (!problem.empty()) {
    ADD_FAILURE() << "stored reference " << file << " no longer matches the path tracer: " << problem
                  << ". If the scene, camera or path tracer changed on purpose, regenerate it: "
                     "GI_TEST_WRITE_REFERENCES=16384 build/tests/gi_tests --gtest_filter=<this test>";
  }
  return stored;
}

}  // namespace gi::test
