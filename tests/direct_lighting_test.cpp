// Direct lighting and RSM flux against host implementations of the same formulas
// (ALGORITHMS.md §0, §1): a plane under a point light, a spot light and the sun; RSM flux totals.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/gtc/type_ptr.hpp>

#include "render/renderer.h"
#include "render/views.h"
#include "scene_builders.h"
#include "test_support.h"

using namespace gi;
using namespace gi::test;

namespace {

constexpr float kPi = 3.14159265358979f;

// Host mirror of kernels/common/brdf.h: Lambert + GGX (height-correlated Smith, Schlick).
glm::vec3 hostBrdf(glm::vec3 diffuse, glm::vec3 f0, float roughness, glm::vec3 n, glm::vec3 wo, glm::vec3 wi) {
  float nl = glm::dot(n, wi), nv = glm::dot(n, wo);
  if (nl <= 0) return glm::vec3(0);
  glm::vec3 f = diffuse / kPi;
  if (nv <= 0) return f;
  float a = std::max(roughness * roughness, 1e-3f), a2 = a * a;
  glm::vec3 h = glm::normalize(wo + wi);
  float nh = std::max(glm::dot(n, h), 0.0f);
  float d = nh * nh * (a2 - 1) + 1;
  float D = a2 / (kPi * d * d);
  float V = 0.5f / (nl * std::sqrt(nv * nv * (1 - a2) + a2) + nv * std::sqrt(nl * nl * (1 - a2) + a2));
  float m = 1 - glm::dot(wi, h);
  glm::vec3 F = f0 + (1.0f - f0) * (m * m * m * m * m);
  return f + D * V * F;
}

Scene floorScene(float half, glm::vec3 albedo, float roughness) {
  Scene s;
  s.name = "floor";
  s.materials.push_back(diffuseMaterial(albedo, roughness));
  addQuad(s, glm::vec3(-half, 0, half), glm::vec3(2 * half, 0, 0), glm::vec3(0, 0, -2 * half), 0);  // faces +y
  s.computeBounds();
  return s;
}

struct Frame {
  Image radiance, position;
};

Frame render(const Scene& s, int w, int h, std::vector<std::string> sets = {}) {
  RenderSettings rs;
  rs.width = w;
  rs.height = h;
  rs.sets = std::move(sets);
  Renderer r(context(), s, rs);
  r.renderFrame();
  Frame f{r.radiance(), Image()};
  f.position = Image(w, h, 4);
  std::vector<float> pos(size_t(w) * h * 4);
  context().read(r.gbuffer().position, pos.data(), pos.size() * 4);
  f.position.pixels = pos;
  return f;
}

}  // namespace

TEST(DirectLighting, PlaneUnderPointLightMatchesInverseSquareLaw) {
  Scene s = floorScene(3.0f, glm::vec3(0.6f, 0.5f, 0.4f), 0.7f);
  glm::vec3 lightPos(0.4f, 1.5f, -0.2f), I(10.0f, 20.0f, 30.0f);
  s.lights.push_back(pointLight(lightPos, I));
  glm::vec3 eye(1.0f, 2.5f, 3.0f);
  s.cameras.push_back(lookAtCamera(eye, glm::vec3(0, 0, 0), 1.1f));
  Frame f = render(s, 96, 64);
  int checked = 0;
  for (int p = 0; p < 96 * 64; ++p) {
    if (f.position.pixels[p * 4 + 3] == 0) continue;
    glm::vec3 x(f.position.pixels[p * 4], f.position.pixels[p * 4 + 1], f.position.pixels[p * 4 + 2]);
    glm::vec3 n(0, 1, 0);
    glm::vec3 d = lightPos - x;
    float dist2 = glm::dot(d, d);
    glm::vec3 wi = d / std::sqrt(dist2), wo = glm::normalize(eye - x);
    glm::vec3 E = I * glm::dot(n, wi) / dist2;  // I·cosθ/d²
    glm::vec3 expected = hostBrdf(glm::vec3(0.6f, 0.5f, 0.4f), glm::vec3(0.04f), 0.7f, n, wo, wi) * E;
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(f.radiance.pixels[p * 3 + c], expected[c], 0.01f * expected[c]) << "pixel " << p << " channel " << c;
    ++checked;
  }
  EXPECT_GT(checked, 96 * 64 / 2);
}

TEST(DirectLighting, SunOnPlaneAndShadowOfABlocker) {
  Scene s = floorScene(3.0f, glm::vec3(0.5f), 1.0f);
  // A horizontal blocker 1 m above the floor, 1 m wide, facing down and up (double-sided).
  s.materials.push_back(diffuseMaterial(glm::vec3(0.5f)));
  s.materials.back().double_sided = 1;
  addQuad(s, glm::vec3(-0.5f, 1.0f, 0.5f), glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), 1);
  s.computeBounds();
  glm::vec3 sunDir = glm::normalize(glm::vec3(0.0f, -1.0f, 0.0f)), E(3.0f);
  s.lights.push_back(directionalLight(sunDir, E));
  // Seen from the side, low enough to look under the blocker.
  glm::vec3 eye(4.0f, 2.5f, 0.0f);
  s.cameras.push_back(lookAtCamera(eye, glm::vec3(0, 0, 0), 0.9f));
  Frame f = render(s, 64, 64);
  int lit = 0, shadowed = 0;
  for (int p = 0; p < 64 * 64; ++p) {
    if (f.position.pixels[p * 4 + 3] == 0) continue;
    glm::vec3 x(f.position.pixels[p * 4], f.position.pixels[p * 4 + 1], f.position.pixels[p * 4 + 2]);
    if (x.y > 0.5f) continue;  // the blocker itself
    glm::vec3 wo = glm::normalize(eye - x), n(0, 1, 0);
    glm::vec3 full = hostBrdf(glm::vec3(0.5f), glm::vec3(0.04f), 1.0f, n, wo, -sunDir) * E * glm::dot(n, -sunDir);
    bool underBlocker = std::abs(x.x) < 0.45f && std::abs(x.z) < 0.45f;
    bool clearOfBlocker = std::abs(x.x) > 0.55f || std::abs(x.z) > 0.55f;
    if (underBlocker) {
      EXPECT_NEAR(f.radiance.pixels[p * 3], 0.0f, 1e-6f) << "pixel " << p;
      ++shadowed;
    } else if (clearOfBlocker) {
      EXPECT_NEAR(f.radiance.pixels[p * 3], full.x, 0.01f * full.x) << "pixel " << p;
      ++lit;
    }
  }
  EXPECT_GT(lit, 500);
  EXPECT_GT(shadowed, 50);
}

// The sun's shadow view (render/views.h, makeDirectionalShadowView): every corner of the bounds
// lies on the map with at least two texels of margin and within its depth range, the texels are
// square with side texel_world_size, the map holds about size² texels (no side above 4·size), and
// its texels are no larger than those of the square map around the bounding sphere.
TEST(DirectLighting, SunShadowViewFitsTheBoundsWithSquareTexels) {
  const int size = 512;
  const Bounds boxes[] = {{glm::vec3(-1.0f), glm::vec3(1.0f)},
                          {glm::vec3(-26.8f, 2.3f, -16.5f), glm::vec3(24.2f, 23.6f, 14.9f)},  // Sponza's
                          {glm::vec3(-50.0f, 0.0f, -1.0f), glm::vec3(50.0f, 0.1f, 1.0f)}};
  const glm::vec3 directions[] = {{0, -1, 0}, {0.3f, -1.0f, 0.1f}, {1, -0.05f, 0.02f}, {0, 0, 1}, {-0.6f, -0.5f, 0.7f}};
  for (const Bounds& b : boxes)
    for (const glm::vec3& d : directions) {
      SCOPED_TRACE(::testing::Message() << "direction " << d.x << " " << d.y << " " << d.z << ", bounds extent "
                                        << b.hi.x - b.lo.x << " " << b.hi.y - b.lo.y << " " << b.hi.z - b.lo.z);
      GiView v = makeDirectionalShadowView(d, b, size);
      ASSERT_TRUE(v.orthographic);
      EXPECT_LE(v.width, 4 * size);
      EXPECT_LE(v.height, 4 * size);
      EXPECT_LE(double(v.width) * v.height, double(size) * size + 5.0 * (v.width + v.height) + 25.0);
      EXPECT_LE(v.texel_world_size, makeDirectionalLightView(d, b, size).texel_world_size * 1.0001f);
      glm::mat4 view = glm::make_mat4(v.view), viewProj = glm::make_mat4(v.view_proj);
      auto texelOf = [&](glm::vec3 p) {
        glm::vec4 c = viewProj * glm::vec4(p, 1.0f);
        return glm::vec2((c.x / c.w * 0.5f + 0.5f) * float(v.width), (0.5f - c.y / c.w * 0.5f) * float(v.height));
      };
      for (int i = 0; i < 8; ++i) {
        glm::vec3 corner((i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z);
        glm::vec2 t = texelOf(corner);
        EXPECT_GE(t.x, 1.99f) << "corner " << i;
        EXPECT_GE(t.y, 1.99f) << "corner " << i;
        EXPECT_LE(t.x, float(v.width) - 1.99f) << "corner " << i;
        EXPECT_LE(t.y, float(v.height) - 1.99f) << "corner " << i;
        float depth = -(view * glm::vec4(corner, 1.0f)).z;
        EXPECT_GT(depth, v.znear) << "corner " << i;
        EXPECT_LT(depth, v.zfar) << "corner " << i;
      }
      // One texel_world_size along the view's x and y axes is one texel on the map.
      glm::mat4 toWorld = glm::inverse(view);
      glm::vec3 c = b.center(), ax(toWorld * glm::vec4(1, 0, 0, 0)), ay(toWorld * glm::vec4(0, 1, 0, 0));
      glm::vec2 t0 = texelOf(c), tx = texelOf(c + ax * v.texel_world_size), ty = texelOf(c + ay * v.texel_world_size);
      EXPECT_NEAR(tx.x - t0.x, 1.0f, 1e-3f);
      EXPECT_NEAR(std::abs(ty.y - t0.y), 1.0f, 1e-3f);
    }
}

TEST(DirectLighting, RsmFluxOfSunOnFloorEqualsAlbedoTimesIrradianceTimesArea) {
  for (float tiltDeg : {0.0f, 35.0f}) {
    float half = 1.0f;
    glm::vec3 albedo(0.7f, 0.5f, 0.3f);
    Scene s = floorScene(half, albedo, 1.0f);
    float t = tiltDeg * kPi / 180.0f;
    glm::vec3 dir(std::sin(t), -std::cos(t), 0.0f);
    glm::vec3 E(2.0f, 3.0f, 4.0f);
    s.lights.push_back(directionalLight(dir, E));
    s.cameras.push_back(lookAtCamera(glm::vec3(0, 3, 3), glm::vec3(0), 1.0f));
    RenderSettings rs;
    rs.width = 16;
    rs.height = 16;
    Renderer r(context(), s, rs);
    r.renderFrame();
    auto tmp = tempDir("rsm");
    r.writeAovs(tmp.string());
    Image flux = readImage(tmp / "rsm0_flux.exr");
    glm::dvec3 total(0.0);
    for (size_t p = 0; p < flux.pixelCount(); ++p)
      for (int c = 0; c < 3; ++c) total[c] += flux.pixels[p * flux.channels + c];
    double area = 4.0 * half * half;
    for (int c = 0; c < 3; ++c) {
      double expected = albedo[c] * E[c] * std::cos(t) * area;
      EXPECT_NEAR(total[c], expected, 0.01 * expected) << "tilt " << tiltDeg << " channel " << c;
    }
    std::filesystem::remove_all(tmp);
  }
}

TEST(DirectLighting, RsmFluxOfPointLightMatchesSolidAngleIntegral) {
  // Point light 1 m above the centre of a 2 m × 2 m floor: the RSM (one 160° view pointing down)
  // sees the whole floor; the flux reaching the floor is I·Ω(floor), Ω of a square of half side a
  // at height h: 4·asin(a² / (a² + h²)).
  glm::vec3 albedo(0.5f);
  Scene s = floorScene(1.0f, albedo, 1.0f);
  glm::vec3 I(10.0f);
  s.lights.push_back(pointLight(glm::vec3(0, 1, 0), I));
  s.cameras.push_back(lookAtCamera(glm::vec3(0, 3, 3), glm::vec3(0), 1.0f));
  RenderSettings rs;
  rs.width = 16;
  rs.height = 16;
  rs.sets = {"rsm.resolution=1024"};
  Renderer r(context(), s, rs);
  r.renderFrame();
  auto tmp = tempDir("rsmpoint");
  r.writeAovs(tmp.string());
  Image flux = readImage(tmp / "rsm0_flux.exr");
  double total = 0;
  for (size_t p = 0; p < flux.pixelCount(); ++p) total += flux.pixels[p * flux.channels];
  double omega = 4.0 * std::asin(1.0 / (1.0 + 1.0));
  double expected = 0.5 * 10.0 * omega;
  EXPECT_NEAR(total, expected, 0.01 * expected);
  std::filesystem::remove_all(tmp);
}
