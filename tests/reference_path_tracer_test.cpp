// Path tracer tests: analytic answers (furnace, point-lit plane, emissive ceiling), determinism,
// and statistical consistency (independent seeds, full = direct + indirect).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "reference/path_tracer.h"
#include "reference_scenes.h"
#include "render/views.h"
#include "scene/cornell_box.h"
#include "test_support.h"

using namespace gi;

namespace {

Image render(const Scene& scene, const Camera& cam, PathTracerOptions o, int spp, Image* var = nullptr,
             int perLaunch = 16) {
  PathTracer pt(test::context(), scene, makeCameraView(cam, o.width, o.height), o);
  while (pt.samplesDone() < spp) pt.addSamples(std::min(perLaunch, spp - pt.samplesDone()));
  if (var) *var = pt.variance();
  return pt.image();
}

double meanOf(const Image& img, int c) {
  double s = 0;
  for (size_t i = 0; i < img.pixelCount(); ++i) s += img.pixels[3 * i + c];
  return s / double(img.pixelCount());
}

Camera lookingDown(float height, float yfov) {
  Camera c;
  c.position = glm::vec3(0, height, 0);
  c.target = glm::vec3(0, 0, 0);
  c.up = glm::vec3(0, 0, -1);
  c.yfov = yfov;
  c.znear = 0.01f;
  c.zfar = 100.0f;
  return c;
}

}  // namespace

// Closed sphere, albedo 0.5, point light of intensity π at the centre (pbrt-v4's furnace). With
// NEE every path vertex receives E = π/r² = π and reflects ρ/π·E = 0.5 of it, and each bounce
// multiplies by ρ = 0.5, so L = Σ_{k≥1} 0.5^k = 1 (geometric series); with max order K it is
// 1 − 0.5^K. Russian roulette keeps it unbiased.
TEST(ReferencePathTracer, FurnaceSphereConvergesToOne) {
  Scene scene = test::insideSphere(64, 1.0f, 0.5f);
  scene.lights.push_back(test::pointLight(glm::vec3(0.0f), float(M_PI)));
  scene.lightNames.push_back("centre");
  PathTracerOptions o;
  o.width = o.height = 8;
  o.maxBounces = 40;
  o.diffuseOnly = true;  // a purely Lambertian sphere (glTF materials also carry F0 = 0.04 GGX)
  Image var;
  // Russian roulette makes the per-path value noisy (σ ≈ 0.4 per path): 8192 paths per pixel
  // bring the per-pixel error to σ ≈ 0.45 %, so 2 % is a 4σ bound.
  Image img = render(scene, scene.cameras[0], o, 8192, &var, 2048);
  double mean = meanOf(img, 0);
  std::printf("furnace: mean %.5f\n", mean);
  EXPECT_NEAR(mean, 1.0, 0.005);
  if (getenv("GI_TEST_VERBOSE"))
    for (size_t i = 0; i < img.pixelCount(); ++i) std::printf("%6.3f±%.3f%s", img.pixels[3 * i], std::sqrt(var.pixels[3 * i]), i % 8 == 7 ? "\n" : " ");
  for (size_t i = 0; i < img.pixelCount(); ++i) {
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(img.pixels[3 * i + c], 1.0, 0.02) << "pixel " << i;
  }
  // With only direct light (order 1): exactly 0.5 up to the tessellation (d² and cos off by <0.1 %).
  o.mode = ReferenceMode::Direct;
  Image direct = render(scene, scene.cameras[0], o, 4);
  for (size_t i = 0; i < direct.pixelCount(); ++i) ASSERT_NEAR(direct.pixels[3 * i], 0.5, 0.005);
  // One-bounce indirect (order 2): 0.25.
  o.mode = ReferenceMode::OneBounce;
  Image one = render(scene, scene.cameras[0], o, 64);
  EXPECT_NEAR(meanOf(one, 1), 0.25, 0.005);
}

// Plane y = 0, albedo ρ, point light I at height h: L = ρ/π · I · cos θ / d², cos θ = h/d.
TEST(ReferencePathTracer, PointLitPlaneMatchesInverseSquareLaw) {
  Scene scene;
  scene.materials.push_back(test::diffuseMaterial(0.8f, 0.5f, 0.2f));
  test::addQuad(scene, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, 0);
  scene.computeBounds();
  const float I = 3.0f, h = 1.0f;
  scene.lights.push_back(test::pointLight(glm::vec3(0.3f, h, 0.0f), I));
  scene.lightNames.push_back("p");
  PathTracerOptions o;
  o.width = o.height = 24;
  o.mode = ReferenceMode::Direct;
  o.diffuseOnly = true;
  Camera cam = lookingDown(2.0f, 1.2f);
  Image img = render(scene, cam, o, 1024, nullptr, 512);  // jitter noise σ ≈ 0.2 %
  GiView v = makeCameraView(cam, o.width, o.height);
  glm::mat4 inv;
  std::memcpy(&inv, v.inv_view_proj, 64);
  const float rho[3] = {0.8f, 0.5f, 0.2f};
  for (int py = 0; py < o.height; ++py)
    for (int px = 0; px < o.width; ++px) {
      // The pixel's mean over its area (the path tracer jitters over the pixel): 8×8 sub-samples.
      double expected = 0.0;
      for (int sy = 0; sy < 8; ++sy)
        for (int sx = 0; sx < 8; ++sx) {
          glm::vec4 f = inv * glm::vec4((px + (sx + 0.5f) / 8) / o.width * 2 - 1,
                                        1 - (py + (sy + 0.5f) / 8) / o.height * 2, 1, 1);
          glm::vec3 d = glm::normalize(glm::vec3(f) / f.w - cam.position);
          glm::vec3 x = cam.position + d * (-cam.position.y / d.y);
          glm::vec3 toL = glm::vec3(0.3f, h, 0.0f) - x;
          float d2 = glm::dot(toL, toL);
          expected += I * (h / std::sqrt(d2)) / d2 / 64.0;
        }
      if (getenv("GI_TEST_VERBOSE")) std::printf("%6.3f%s", img.at(px, py)[0] / (rho[0] / M_PI * expected), px == o.width - 1 ? "\n" : " ");
      if (!getenv("GI_TEST_VERBOSE"))
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(img.at(px, py)[c], rho[c] / M_PI * expected, 0.012 * rho[c] / M_PI * expected + 1e-6)
            << px << "," << py;
    }
}

// Directional light E along d: L = ρ/π · E · cos θ everywhere on a plane. Spot light with cosine
// falloff pointing down from height h: I(θ) = I0 cos θ, so L = ρ/π · I0 · h² / d⁴. A light named
// "emitter:*" is a rasterizer stand-in and must not add anything.
TEST(ReferencePathTracer, DirectionalAndCosineSpotLightsAndStandInsIgnored) {
  Scene scene;
  scene.materials.push_back(test::diffuseMaterial(0.5f, 0.5f, 0.5f));
  test::addQuad(scene, {-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}, 0);
  scene.computeBounds();
  GiLight sun{};
  sun.type = GI_LIGHT_DIRECTIONAL;
  sun.direction[0] = 0.6f; sun.direction[1] = -0.8f;
  for (int c = 0; c < 3; ++c) sun.intensity[c] = 2.0f;
  sun.shadow_map = -1;
  GiLight standIn = test::pointLight(glm::vec3(0, 0.5f, 0), 1000.0f);
  scene.lights = {sun, standIn};
  scene.lightNames = {"sun", "emitter:fake"};
  PathTracerOptions o;
  o.width = o.height = 8;
  o.mode = ReferenceMode::Direct;
  o.diffuseOnly = true;
  Camera cam = lookingDown(2.0f, 0.8f);
  Image img = render(scene, cam, o, 4);
  for (size_t i = 0; i < img.pixelCount(); ++i) ASSERT_NEAR(img.pixels[3 * i], 0.5 / M_PI * 2.0 * 0.8, 1e-4);

  GiLight spot = test::pointLight(glm::vec3(0, 1.0f, 0), 3.0f);
  spot.type = GI_LIGHT_SPOT;
  spot.direction[0] = 0; spot.direction[1] = -1; spot.direction[2] = 0;
  spot.falloff = GI_SPOT_FALLOFF_COSINE;
  spot.cos_outer = 0.0f;
  scene.lights = {spot};
  scene.lightNames = {"spot"};
  Image s = render(scene, cam, o, 1024, nullptr, 1024);  // NEE is exact: only pixel jitter varies
  GiView v = makeCameraView(cam, o.width, o.height);
  glm::mat4 inv;
  std::memcpy(&inv, v.inv_view_proj, 64);
  for (int py = 0; py < o.height; ++py)
    for (int px = 0; px < o.width; ++px) {
      double expected = 0.0;
      for (int sy = 0; sy < 8; ++sy)
        for (int sx = 0; sx < 8; ++sx) {
          glm::vec4 f = inv * glm::vec4((px + (sx + 0.5f) / 8) / o.width * 2 - 1,
                                        1 - (py + (sy + 0.5f) / 8) / o.height * 2, 1, 1);
          glm::vec3 d = glm::normalize(glm::vec3(f) / f.w - cam.position);
          glm::vec3 x = cam.position + d * (-cam.position.y / d.y);
          double d2 = glm::dot(x - glm::vec3(0, 1, 0), x - glm::vec3(0, 1, 0));
          expected += 0.5 / M_PI * 3.0 * 1.0 / (d2 * d2) / 64.0;
        }
      ASSERT_NEAR(s.at(px, py)[0], expected, 0.01 * expected) << px << "," << py;
    }
}

// A huge emissive ceiling (radiance Le) 1 m above a diffuse floor: irradiance π·Le, so the floor's
// direct radiance is ρ·Le. Exercises triangle-light NEE, BSDF-hit emission and their MIS weights.
TEST(ReferencePathTracer, EmissiveCeilingGivesAlbedoTimesRadiance) {
  Scene scene;
  scene.materials.push_back(test::diffuseMaterial(0.6f, 0.6f, 0.6f));
  GiMaterial em = test::diffuseMaterial(0.0f, 0.0f, 0.0f);
  em.emissive[0] = 2.0f; em.emissive[1] = 1.0f; em.emissive[2] = 0.5f;
  scene.materials.push_back(em);
  const float R = 300.0f;
  test::addQuad(scene, {-R, 0, -R}, {-R, 0, R}, {R, 0, R}, {R, 0, -R}, 0);
  // Ceiling facing down (winding gives a -y normal).
  test::addQuad(scene, {-R, 1, -R}, {R, 1, -R}, {R, 1, R}, {-R, 1, R}, 1);
  scene.computeBounds();
  PathTracerOptions o;
  o.width = o.height = 8;
  o.mode = ReferenceMode::Direct;
  o.diffuseOnly = true;
  Camera cam = lookingDown(0.5f, 0.3f);
  Image img = render(scene, cam, o, 256);
  const float Le[3] = {2.0f, 1.0f, 0.5f};
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(meanOf(img, c), 0.6 * Le[c], 0.01 * 0.6 * Le[c]) << "channel " << c;
  // The ceiling is seen from above from its back: emission is one-sided, so nothing.
  Camera up = lookingDown(2.0f, 0.3f);
  o.mode = ReferenceMode::Full;
  Image back = render(scene, up, o, 4);
  EXPECT_LT(meanOf(back, 0), 1e-6);
}

TEST(ReferencePathTracer, SameOptionsGiveSameBitsWhateverTheBatching) {
  Scene scene = makeCornellBox();
  PathTracerOptions o;
  o.width = 24; o.height = 24;
  o.maxBounces = 5;
  Image a = render(scene, scene.cameras[0], o, 8, nullptr, 8);
  Image b = render(scene, scene.cameras[0], o, 8, nullptr, 3);
  ASSERT_EQ(a.pixels.size(), b.pixels.size());
  EXPECT_EQ(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * 4), 0);
  o.seed = 1;
  Image c = render(scene, scene.cameras[0], o, 8);
  EXPECT_NE(std::memcmp(a.pixels.data(), c.pixels.data(), a.pixels.size() * 4), 0);
}

// Mitsuba-style statistical test: two renders with independent seeds differ per pixel by amounts
// consistent with their own variance estimates: z = (a − b)/sqrt(va + vb) ~ N(0, 1).
TEST(ReferencePathTracer, IndependentSeedsAgreeWithinTheirVariance) {
  Scene scene = makeCornellBox();
  PathTracerOptions o;
  o.width = 32; o.height = 32;
  o.maxBounces = 4;
  Image va, vb;
  Image a = render(scene, scene.cameras[0], o, 128, &va, 64);
  o.seed = 12345;
  Image b = render(scene, scene.cameras[0], o, 128, &vb, 64);
  double sumAbs = 0;
  int n = 0, beyond3 = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    double v = va.pixels[i] + vb.pixels[i];
    if (v <= 0) continue;
    double z = (a.pixels[i] - b.pixels[i]) / std::sqrt(v);
    sumAbs += std::fabs(z);
    beyond3 += std::fabs(z) > 3.0;
    ++n;
  }
  double meanAbs = sumAbs / n;
  std::printf("z-scores: %d values, mean |z| %.3f (N(0,1): 0.798), beyond 3 sigma %.4f (0.0027)\n", n, meanAbs,
              double(beyond3) / n);
  ASSERT_GT(n, 2000);
  EXPECT_NEAR(meanAbs, 0.798, 0.08);
  EXPECT_LT(double(beyond3) / n, 0.01);
}

// Full = direct + indirect and indirect >= one-bounce, on the image mean of the empty Cornell box,
// within 4 standard errors.
TEST(ReferencePathTracer, FullEqualsDirectPlusIndirect) {
  CornellOptions co;
  co.withBlocks = false;
  Scene scene = makeCornellBox(co);
  PathTracerOptions o;
  o.width = 32; o.height = 32;
  o.maxBounces = 6;
  auto run = [&](ReferenceMode m, uint32_t seed, double& mean, double& se) {
    o.mode = m;
    o.seed = seed;
    Image v;
    Image img = render(scene, scene.cameras[0], o, 64, &v, 64);
    mean = meanOf(img, 1);
    double vs = 0;
    for (size_t i = 0; i < v.pixelCount(); ++i) vs += v.pixels[3 * i + 1];
    se = std::sqrt(vs) / double(v.pixelCount());
  };
  double mf, sf, md, sd, mi, si, m1, s1;
  run(ReferenceMode::Full, 1, mf, sf);
  run(ReferenceMode::Direct, 2, md, sd);
  run(ReferenceMode::Indirect, 3, mi, si);
  run(ReferenceMode::OneBounce, 4, m1, s1);
  std::printf("full %.5f±%.5f direct %.5f±%.5f indirect %.5f±%.5f one-bounce %.5f±%.5f\n", mf, sf, md, sd, mi, si,
              m1, s1);
  double se = std::sqrt(sf * sf + sd * sd + si * si);
  EXPECT_NEAR(mf, md + mi, 4 * se);
  EXPECT_GT(mi, m1);
  EXPECT_GT(mi, 0.05 * mf);
}
