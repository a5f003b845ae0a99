// The rasterized camera G-buffer of the Cornell box against a simple, independent host ray caster
// (double precision, brute force over all triangles): view depth and geometric normal must agree
// on at least 99.5 % of the pixels (the rest: pixels whose centre lies within rounding of an edge).
#include <gtest/gtest.h>

#include <cmath>

#include "raster/gbuffer.h"
#include "render/views.h"
#include "scene/cornell_box.h"
#include "scene/device_scene.h"
#include "test_support.h"

using namespace gi;

namespace {

struct HostHit {
  double t = INFINITY;
  glm::dvec3 normal{0.0};
};

HostHit castRay(const Scene& s, glm::dvec3 o, glm::dvec3 d) {
  HostHit best;
  for (size_t i = 0; i < s.triangles.size(); ++i) {
    glm::dvec3 p0 = s.positions[s.triangles[i].x], p1 = s.positions[s.triangles[i].y], p2 = s.positions[s.triangles[i].z];
    glm::dvec3 e1 = p1 - p0, e2 = p2 - p0, pv = glm::cross(d, e2);
    double det = glm::dot(e1, pv);
    if (std::abs(det) < 1e-18) continue;
    glm::dvec3 tv = o - p0;
    double u = glm::dot(tv, pv) / det;
    glm::dvec3 qv = glm::cross(tv, e1);
    double v = glm::dot(d, qv) / det, t = glm::dot(e2, qv) / det;
    if (u < 0 || v < 0 || u + v > 1 || t <= 0 || t >= best.t) continue;
    glm::dvec3 n = glm::normalize(glm::cross(e1, e2));
    if (glm::dot(n, d) > 0) {
      if (!s.materials[s.triangleMaterial[i]].double_sided) continue;  // back face: culled
      n = -n;
    }
    best.t = t;
    best.normal = n;
  }
  return best;
}

}  // namespace

TEST(GBuffer, CornellBoxMatchesHostRayCaster) {
  Scene s = makeCornellBox();
  const int W = 128, H = 128;
  const Camera& cam = s.cameras[0];
  GiView view = makeCameraView(cam, W, H);
  auto& ctx = test::context();
  DeviceScene ds(ctx, s);
  RasterPasses passes(ctx);
  GBuffer g;
  passes.renderGBuffer(ds, view, g);
  ctx.profiler().discard();
  auto depth = ctx.download<float>(g.visibility.depth);
  auto geo = ctx.download<float>(g.geoNormal);

  glm::dvec3 eye = cam.position, fwd = glm::normalize(glm::dvec3(cam.target) - eye);
  glm::dvec3 right = glm::normalize(glm::cross(fwd, glm::dvec3(cam.up))), up = glm::cross(right, fwd);
  double tanHalf = std::tan(0.5 * cam.yfov), aspect = double(W) / H;
  int agree = 0, surfaces = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      double nx = ((x + 0.5) / W * 2 - 1) * tanHalf * aspect, ny = (1 - (y + 0.5) / H * 2) * tanHalf;
      glm::dvec3 d = glm::normalize(fwd + nx * right + ny * up);
      HostHit h = castRay(s, eye, d);
      size_t i = size_t(y) * W + x;
      bool hostSurface = std::isfinite(h.t);
      surfaces += hostSurface;
      if (!hostSurface) {
        agree += std::isinf(depth[i]);
        continue;
      }
      double hostDepth = h.t * glm::dot(d, fwd);
      glm::dvec3 n(geo[i * 4], geo[i * 4 + 1], geo[i * 4 + 2]);
      bool depthOk = std::abs(depth[i] - hostDepth) <= 1e-4 * hostDepth;
      bool normalOk = glm::dot(n, h.normal) > 0.9999;
      agree += depthOk && normalOk;
    }
  EXPECT_GT(surfaces, W * H / 2);
  double fraction = double(agree) / (W * H);
  EXPECT_GE(fraction, 0.995) << agree << " of " << W * H << " pixels agree";
}
