// Compute rasterizer against analytic cases: known pixel sets, the top-left rule on shared edges
// (every pixel of a tessellated screen covered exactly once), exact depths, culling, clipping and
// run-to-run determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/rasterizer.h"
#include "render/views.h"
#include "scene/device_scene.h"
#include "test_support.h"

using namespace gi;

namespace {

GiMaterial plainMaterial(bool doubleSided = true) {
  GiMaterial m{};
  m.base_color[0] = m.base_color[1] = m.base_color[2] = m.base_color[3] = 1.0f;
  m.roughness = 1.0f;
  m.base_color_tex = m.metallic_roughness_tex = m.normal_tex = m.emissive_tex = GI_NO_TEXTURE;
  m.double_sided = doubleSided ? 1 : 0;
  return m;
}

// A scene of independent triangles given in world space.
Scene triangleSoup(const std::vector<std::array<glm::vec3, 3>>& tris, bool doubleSided = true) {
  Scene s;
  s.materials.push_back(plainMaterial(doubleSided));
  for (size_t i = 0; i < tris.size(); ++i) {
    uint32_t base = uint32_t(s.positions.size());
    glm::vec3 n = glm::normalize(glm::cross(tris[i][1] - tris[i][0], tris[i][2] - tris[i][0]));
    for (int k = 0; k < 3; ++k) {
      s.positions.push_back(tris[i][k]);
      s.normals.push_back(n);
      s.uvs.emplace_back(0.0f);
      s.tangents.emplace_back(0.0f);
    }
    s.triangles.emplace_back(base, base + 1, base + 2);
    s.triangleMaterial.push_back(0);
    s.triangleInstance.push_back(uint32_t(i));
  }
  s.computeBounds();
  return s;
}

// Orthographic view in which world (x, y, -z) lands on pixel coordinates (x, y) at depth z.
GiView pixelView(int w, int h, bool cull = false) {
  GiView v = makeView(glm::mat4(1.0f), glm::ortho(0.0f, float(w), float(h), 0.0f, 0.5f, 100.0f), w, h, true,
                      glm::vec3(0.0f), 0.5f, 100.0f, 1.0f);
  v.cull_backfaces = cull ? 1 : 0;
  return v;
}

struct RasterResult {
  std::vector<uint32_t> tri;
  std::vector<float> depth;
};

RasterResult rasterize(const Scene& s, const GiView& view) {
  auto& ctx = test::context();
  DeviceScene ds(ctx, s);
  Rasterizer r(ctx);
  VisibilityBuffer vb;
  r.render(ds, view, vb, "test");
  ctx.profiler().discard();
  return {ctx.download<uint32_t>(vb.triangle), ctx.download<float>(vb.depth)};
}

}  // namespace

TEST(Raster, RightTriangleCoversKnownPixels) {
  // Legs of 8 pixels along the top and left edges: pixel centres with x + y + 1 < 8 are inside;
  // the 8 centres exactly on the hypotenuse belong to its right/bottom side (top-left rule).
  Scene s = triangleSoup({{glm::vec3(0, 0, -5), glm::vec3(8, 0, -5), glm::vec3(0, 8, -5)}});
  RasterResult r = rasterize(s, pixelView(20, 12));
  int covered = 0;
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 20; ++x) {
      bool expected = x + y < 7;
      bool got = r.tri[y * 20 + x] == 0u;
      EXPECT_EQ(got, expected) << "pixel " << x << "," << y;
      covered += got;
      if (got) EXPECT_NEAR(r.depth[y * 20 + x], 5.0f, 1e-4f);
      else EXPECT_TRUE(std::isinf(r.depth[y * 20 + x]));
    }
  EXPECT_EQ(covered, 28);
}

TEST(Raster, SharedEdgesCoverEveryPixelExactlyOnce) {
  // A fan of triangles around a sub-pixel centre whose outer vertices lie far outside the viewport:
  // together they tile the screen, so every pixel must be covered by exactly one triangle.
  const int W = 53, H = 37;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(0.0f, 1.0f);
  for (int trial = 0; trial < 3; ++trial) {
    glm::vec3 centre(20.0f + 10.0f * jitter(rng), 15.0f + 5.0f * jitter(rng), -3.0f);
    if (trial == 0) centre = glm::vec3(26.5f, 18.5f, -3.0f);  // exactly on a pixel centre
    const int n = 17;
    std::vector<glm::vec3> rim;
    for (int i = 0; i < n; ++i) {
      float a = 6.2831853f * (float(i) + 0.3f * jitter(rng)) / float(n);
      rim.emplace_back(centre.x + 200.0f * std::cos(a), centre.y + 200.0f * std::sin(a), -3.0f - jitter(rng));
    }
    std::vector<int> coverage(W * H, 0);
    for (int i = 0; i < n; ++i) {
      Scene s = triangleSoup({{centre, rim[i], rim[(i + 1) % n]}});
      RasterResult r = rasterize(s, pixelView(W, H));
      for (int p = 0; p < W * H; ++p) coverage[p] += r.tri[p] == 0u;
    }
    for (int p = 0; p < W * H; ++p) ASSERT_EQ(coverage[p], 1) << "trial " << trial << " pixel " << p % W << "," << p / W;
  }
}

TEST(Raster, GridOfSharedEdgesThroughPixelCentres) {
  // Quads whose diagonals and sides pass exactly through pixel centres, all in one scene: every
  // pixel covered by exactly one triangle is the same as: no pixel left uncovered and the
  // triangle ids of both halves appear in the expected proportions.
  const int W = 32, H = 32;
  std::vector<std::array<glm::vec3, 3>> tris;
  for (int qy = 0; qy < 4; ++qy)
    for (int qx = 0; qx < 4; ++qx) {
      float x0 = qx * 8 + 0.5f, y0 = qy * 8 + 0.5f, x1 = x0 + 8, y1 = y0 + 8;
      tris.push_back({glm::vec3(x0, y0, -2), glm::vec3(x1, y0, -2), glm::vec3(x1, y1, -2)});
      tris.push_back({glm::vec3(x0, y0, -2), glm::vec3(x1, y1, -2), glm::vec3(x0, y1, -2)});
    }
  // Render each triangle alone and count coverage.
  std::vector<int> coverage(W * H, 0);
  for (auto& t : tris) {
    RasterResult r = rasterize(triangleSoup({t}), pixelView(W, H));
    for (int p = 0; p < W * H; ++p) coverage[p] += r.tri[p] == 0u;
  }
  // The quads span pixel centres 0.5 .. 32.5: pixels 0..31 in both axes, each exactly once.
  for (int p = 0; p < W * H; ++p) ASSERT_EQ(coverage[p], 1) << "pixel " << p % W << "," << p / W;
}

TEST(Raster, NearestTriangleWinsAndDepthIsExact) {
  Scene s = triangleSoup({{glm::vec3(-100, -100, -10), glm::vec3(100, -100, -10), glm::vec3(0, 100, -10)},
                          {glm::vec3(-100, -100, -4), glm::vec3(100, -100, -4), glm::vec3(0, 100, -4)}});
  // Perspective camera at the origin looking down -z.
  Camera cam;
  cam.position = glm::vec3(0.0f);
  cam.target = glm::vec3(0, 0, -1);
  cam.yfov = 1.0f;
  cam.znear = 0.1f;
  cam.zfar = 50.0f;
  RasterResult r = rasterize(s, makeCameraView(cam, 40, 30));
  for (int p = 0; p < 40 * 30; ++p) {
    ASSERT_EQ(r.tri[p], 1u);
    ASSERT_NEAR(r.depth[p], 4.0f, 4.0f * 1e-5f);
  }
}

TEST(Raster, BackFacesCulledForSingleSidedMaterials) {
  // Counter-clockwise seen from the camera = front face (glTF); the pixel view flips y, so a
  // triangle that is CCW in world xy is seen clockwise here.
  std::array<glm::vec3, 3> ccwWorld = {glm::vec3(0, 0, -5), glm::vec3(8, 0, -5), glm::vec3(0, 8, -5)};
  std::array<glm::vec3, 3> cwWorld = {ccwWorld[0], ccwWorld[2], ccwWorld[1]};
  auto count = [](const RasterResult& r) { return std::count(r.tri.begin(), r.tri.end(), 0u); };
  EXPECT_EQ(count(rasterize(triangleSoup({ccwWorld}, false), pixelView(16, 16, true))), 0);
  EXPECT_EQ(count(rasterize(triangleSoup({cwWorld}, false), pixelView(16, 16, true))), 28);
  EXPECT_EQ(count(rasterize(triangleSoup({ccwWorld}, true), pixelView(16, 16, true))), 28);
}

TEST(Raster, NearPlaneClippingKeepsVisiblePart) {
  // A floor that passes under and behind the camera: clipped, never wrapped around.
  Camera cam;
  cam.position = glm::vec3(0, 1, 0);
  cam.target = glm::vec3(0, 1, -1);
  cam.yfov = 1.2f;
  cam.znear = 0.05f;
  cam.zfar = 100.0f;
  Scene s = triangleSoup({{glm::vec3(-50, 0, 50), glm::vec3(50, 0, 50), glm::vec3(0, 0, -60)}});
  RasterResult r = rasterize(s, makeCameraView(cam, 64, 48));
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      uint32_t t = r.tri[y * 64 + x];
      if (y < 24) EXPECT_EQ(t, GI_INVALID_ID) << x << "," << y;  // above the horizon: sky
      if (y >= 26 && std::abs(x - 32) < 10) {
        EXPECT_EQ(t, 0u) << x << "," << y;
        // Depth along the view axis of the floor point seen through this pixel centre.
        float ndcY = 1.0f - (y + 0.5f) / 48.0f * 2.0f;
        float tanY = -ndcY * std::tan(0.6f);
        EXPECT_NEAR(r.depth[y * 64 + x], 1.0f / tanY, 1e-3f / tanY);
      }
    }
}

TEST(Raster, DeterministicAcrossRuns) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<std::array<glm::vec3, 3>> tris;
  for (int i = 0; i < 3000; ++i) {
    glm::vec3 c(u(rng) * 30 + 32, u(rng) * 20 + 24, -5 - 4 * u(rng));
    tris.push_back({c, c + glm::vec3(u(rng) * 6, u(rng) * 6, u(rng)), c + glm::vec3(u(rng) * 6, u(rng) * 6, u(rng))});
  }
  Scene s = triangleSoup(tris);
  RasterResult a = rasterize(s, pixelView(64, 48));
  RasterResult b = rasterize(s, pixelView(64, 48));
  EXPECT_EQ(a.tri, b.tri);
  EXPECT_EQ(0, std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * sizeof(float)));
}
