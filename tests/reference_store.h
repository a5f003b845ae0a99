// Converged path-traced references for the accuracy tests, stored in tests/data/references/.
//
// Why: an accuracy test compares a technique with the reference path tracer. A reference rendered
// inside the test at CI-affordable sample counts (≈1k spp at 128×128) is noisy enough to cost
// SSIM several hundredths by itself, which hides the technique's own error. So each accuracy test
// names its reference by a key; the converged image (2k–16k spp, printed when written) lives in the repository and is
// re-validated on every run against a fresh, independent-seed render of the *current* path tracer
// and scene (block means must agree within their standard errors). A stale file — the scene, the
// camera, the light or the path tracer changed — fails the test with the command that regenerates
// it. The stored images are therefore never produced by the code under test (the techniques), and
// the path tracer that produces them is validated on its own (docs/ACCURACY.md).
//
// Regenerate (or create) every stored reference the selected tests use:
//   GI_TEST_WRITE_REFERENCES=16384 build/tests/gi_tests --gtest_filter='VplAccuracy.*'
// A test whose key has no stored file renders `fallbackSpp` samples instead and says so.
#pragma once
#include <string>

#include "image/image.h"
#include "reference/path_tracer.h"
#include "render/views.h"
#include "scene/scene.h"

namespace gi::test {

struct StoredReferenceCheck {
  int checkSpp = 64;            // samples of the fresh validation render
  double maxBlockZ = 5.0;       // |block mean difference| / standard error allowed for ...
  double maxOutlierFraction = 0.01;  // ... all but this fraction of the 8×8 blocks
};

// Empty when `stored` agrees with a fresh render (mean and per-pixel variance of its mean) block
// by block, else a description of the disagreement. Exposed for its own test.
std::string referenceMismatch(const Image& stored, const Image& freshMean, const Image& freshVariance,
                              const StoredReferenceCheck& check = {});

// The converged reference image for `key` (file tests/data/references/<key>.exr). `options.seed`
// is ignored for the stored image (it was rendered with seed 1); the validation render uses seed 2.
Image convergedReference(const std::string& key, const Scene& scene, const GiView& view,
                         const PathTracerOptions& options, int fallbackSpp,
                         const StoredReferenceCheck& check = {});

}  // namespace gi::test
