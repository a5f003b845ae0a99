// The stored-reference check (tests/reference_store.h) must accept an independent render of the
// same scene and reject a reference that is off by a few per cent — otherwise a stale stored image
// would silently become the "truth" of every accuracy test.
#include <gtest/gtest.h>

#include "reference/path_tracer.h"
#include "reference_store.h"
#include "render/views.h"
#include "scene/cornell_box.h"
#include "test_support.h"

using namespace gi;

namespace {

struct Render {
  Image mean, variance;
};

Render render(const Scene& s, const GiView& view, uint32_t seed, int spp) {
  PathTracerOptions o;
  o.width = 32;
  o.height = 32;
  o.mode = ReferenceMode::Full;
  o.seed = seed;
  PathTracer pt(test::context(), s, view, o);
  pt.addSamples(spp);
  return {pt.image(), pt.variance()};
}

}  // namespace

TEST(ReferenceStore, AcceptsIndependentRenderRejectsScaledOne) {
  Scene s = makeCornellBox();
  Camera cam = s.cameras.at(0);
  GiView view = makeCameraView(cam, 32, 32);
  Render stored = render(s, view, 1, 256);
  Render fresh = render(s, view, 2, 64);
  EXPECT_EQ(test::referenceMismatch(stored.mean, fresh.mean, fresh.variance), "");
  Image scaled = stored.mean;
  for (float& v : scaled.pixels) v *= 1.05f;
  EXPECT_NE(test::referenceMismatch(scaled, fresh.mean, fresh.variance), "");
}
