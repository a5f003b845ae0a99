// Shared by the accuracy tests that compare a rasterized technique with the reference path tracer:
// render the technique at 2×2 the size and box-filter it down (the path tracer integrates over
// each pixel's area); the reference at the same camera comes from tests/reference_store.h (stored,
// converged, re-validated each run; `fallbackSpp` samples while no file is stored).
// GI_TEST_SAVE_IMAGES=<dir> writes both images (EXR and display-transformed PNG) as
// <dir>/<technique>_<scene>_<indirect|full>_*.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "image/image.h"
#include "reference/path_tracer.h"
#include "scene/scene.h"

namespace gi::test {

// The Cornell box lit only by the downward punctual spot (intensity (1.2, 1.0, 0.8) W/sr), so the
// RSM and the path tracer see the same light; with or without its two blocks.
Scene cornellWithSpot(bool blocks);

// The Sponza scene config (scenes/sponza.json) through the media path; empty with `why` set when
// the media are missing or do not load (the caller skips).
std::optional<Scene> loadSponza(std::string& why);

Image boxDown(const Image& big, int factor);
double meanOf(const Image& image);  // over all pixels and the three colour channels

struct AccuracyPair {
  Image raster, reference;
  Camera camera;
};

// indirectOnly: the technique's indirect image (else direct + indirect); mode/diffuseOnly configure
// the path tracer; referenceKey names the stored reference (the same scene, camera, size and mode
// must use the same key in every test).
AccuracyPair renderAgainstReference(const Scene& scene, const std::string& technique, int width, int height,
                                    std::vector<std::string> sets, bool indirectOnly, ReferenceMode mode,
                                    bool diffuseOnly, const std::string& referenceKey, int fallbackSpp);

}  // namespace gi::test
