#include "accuracy_support.h"

#include <algorithm>
#include <cstdlib>

#include "render/renderer.h"
#include "reference_store.h"
#include "render/views.h"
#include "scene/cornell_box.h"
#include "scene/media_path.h"
#include "scene/scene_loader.h"
#include "test_support.h"

namespace gi::test {

Scene cornellWithSpot(bool blocks) {
  CornellOptions o;
  o.withBlocks = blocks;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  o.spotLight->intensity = glm::vec3(1.2f, 1.0f, 0.8f);
  return makeCornellBox(o);
}

std::optional<Scene> loadSponza(std::string& why) {
  if (!findMediaDir("")) {
    why = "Sponza media not found (docs/SCENES.md)";
    return std::nullopt;
  }
  try {
    return loadScene(std::string(GI_SOURCE_DIR) + "/scenes/sponza.json", "");
  } catch (const std::exception& e) {
    why = std::string("Sponza not loadable: ") + e.what();
    return std::nullopt;
  }
}

Image boxDown(const Image& big, int f) {
  Image out(big.width / f, big.height / f, big.channels);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < big.channels; ++c) {
        double s = 0;
        for (int j = 0; j < f; ++j)
          for (int i = 0; i < f; ++i) s += big.at(x * f + i, y * f + j)[c];
        out.at(x, y)[c] = float(s / (f * f));
      }
  return out;
}

double meanOf(const Image& im) {
  double s = 0;
  for (size_t i = 0; i < im.pixelCount(); ++i)
    for (int c = 0; c < 3; ++c) s += im.pixels[i * im.channels + c];
  return s / (3.0 * im.pixelCount());
}

AccuracyPair renderAgainstReference(const Scene& scene, const std::string& technique, int W, int H,
                                    std::vector<std::string> sets, bool indirectOnly, ReferenceMode mode,
                                    bool diffuseOnly, const std::string& referenceKey, int fallbackSpp) {
  const int kSuper = 2;
  RenderSettings rs;
  rs.width = W * kSuper;
  rs.height = H * kSuper;
  rs.technique = technique;
  rs.sets = std::move(sets);
  Renderer r(context(), scene, rs);
  r.renderFrame();
  AccuracyPair p;
  p.raster = boxDown(indirectOnly ? r.indirectRadiance() : r.radiance(), kSuper);
  p.camera = r.camera();
  PathTracerOptions o;
  o.width = W;
  o.height = H;
  o.mode = mode;
  o.diffuseOnly = diffuseOnly;
  p.reference = convergedReference(referenceKey, scene, makeCameraView(r.camera(), W, H), o, fallbackSpp);
  if (const char* dir = std::getenv("GI_TEST_SAVE_IMAGES")) {
    std::string base = std::string(dir) + "/" + technique + "_" + scene.name + (indirectOnly ? "_indirect" : "_full");
    writeImage(base + "_raster.exr", p.raster);
    writeImage(base + "_reference.exr", p.reference);
    writeImage(base + "_raster.png", displayTransform(p.raster, scene.exposure));
    writeImage(base + "_reference.png", displayTransform(p.reference, scene.exposure));
  }
  return p;
}

}  // namespace gi::test
