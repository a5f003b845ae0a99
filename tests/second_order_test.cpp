// second-order (Cochran & Steele, seed 002; ALGORITHMS.md §2.6) kernels against host
// implementations of the same formulas on tiny inputs: the Halton directions against an
// independent double-precision transcription of the paper's formula; indirect-light placement
// (spot and directional RSMs) against the host mirror, and their total power against the RSM's;
// negative lights (picked pixels, back-side illumination, direction, flux) against the host
// mirror; the full-resolution image against ρ/π·max(0, E_s − E_n) evaluated on the host; the
// multi-resolution re-shade list against the host's flags; determinism; bad parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "accuracy_support.h"
#include "gi/second_order/second_order.h"
#include "render/renderer.h"
#include "test_support.h"

using namespace gi;

namespace {

constexpr float kInvPi = 0.31830988618379067154f;

RenderSettings settings(int w, int h, std::vector<std::string> sets) {
  RenderSettings rs;
  rs.width = w;
  rs.height = h;
  rs.technique = "second-order";
  rs.sets = std::move(sets);
  rs.sets.push_back("shadow.resolution=256");
  rs.sets.push_back("shadow.cube_resolution=128");
  return rs;
}

std::vector<HostVpl> toHost(const std::vector<glm::vec4>& raw, size_t first, size_t count) {
  std::vector<HostVpl> v(count);
  for (size_t k = 0; k < count; ++k) {
    v[k].position = glm::vec3(raw[3 * (first + k)]);
    v[k].dmin2 = raw[3 * (first + k)].w;
    v[k].normal = glm::vec3(raw[3 * (first + k) + 1]);
    v[k].flux = glm::vec3(raw[3 * (first + k) + 2]);
  }
  return v;
}

float lum(glm::vec3 c) { return c.x * 0.2126f + c.y * 0.7152f + c.z * 0.0722f; }

// Runs the technique once on the renderer's current frame (its own instance, so the test can read
// what it computed).
struct TechniqueRun {
  SecondOrderTechnique technique;
  cl::Buffer indirect;
  explicit TechniqueRun(Renderer& r) : indirect(test::context(), size_t(r.width()) * r.height() * 16) {
    technique.setup(r.frameResources(false));
    technique.render(r.frameResources(false), indirect);
    test::context().profiler().discard();
  }
};

void expectSameLight(const HostVpl& dev, const HostVpl& host, const std::string& what) {
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(dev.position[c], host.position[c], 1e-5f) << what;
    EXPECT_NEAR(dev.normal[c], host.normal[c], 1e-4f) << what;
    EXPECT_NEAR(dev.flux[c], host.flux[c], 1e-4f * std::abs(host.flux[c]) + 1e-12f) << what;
  }
  EXPECT_NEAR(dev.dmin2, host.dmin2, 1e-4f * host.dmin2) << what;
}

}  // namespace

TEST(SecondOrderPlacement, HaltonDirectionsFollowThePaper) {
  // Φ_b(i) in double precision, written independently of radicalInverse().
  auto phi = [](uint32_t i, uint32_t b) {
    double f = 1.0, r = 0.0;
    for (; i; i /= b) r += (f /= b) * (i % b);
    return r;
  };
  for (float cosAccept : {-1.0f, 0.5f, 0.94f}) {
    std::vector<glm::vec4> d = haltonConeDirections(cosAccept, 300);
    ASSERT_EQ(d.size(), 300u);
    size_t k = 0;
    double meanZ = 0;
    for (uint32_t i = 1; k < d.size(); ++i) {
      double varphi = 2.0 * M_PI * phi(i, 2), delta = std::asin(2.0 * phi(i, 3) - 1.0);
      glm::dvec3 s(std::sin(varphi) * std::cos(delta), std::cos(varphi) * std::cos(delta), std::sin(delta));
      if (s.z < cosAccept) continue;
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(d[k][c], s[c], 2e-5) << "cos " << cosAccept << " point " << k;
      meanZ += s.z;
      ++k;
    }
    // Uniform on the cap z ≥ c: E[z] = (1 + c)/2.
    EXPECT_NEAR(meanZ / 300.0, (1.0 + cosAccept) / 2.0, 0.01 * (1.0 - cosAccept) + 1e-3) << cosAccept;
  }
  EXPECT_THROW(haltonConeDirections(0.99999994f, 4096), Error);
  std::vector<glm::vec4> sq = haltonSquarePoints(5);
  EXPECT_FLOAT_EQ(sq[0].x, 0.5f);
  EXPECT_FLOAT_EQ(sq[0].y, 1.0f / 3.0f);
  EXPECT_FLOAT_EQ(sq[4].x, 0.625f);
  EXPECT_FLOAT_EQ(sq[4].y, 7.0f / 9.0f);
}

TEST(SecondOrderPlacement, KernelMatchesHostAndCarriesTheRsmPower) {
  cl::Context& ctx = test::context();
  for (bool directional : {false, true}) {
    Scene s = test::cornellWithSpot(false);
    if (directional) {  // the same box under a sun at 20° from vertical
      GiLight& l = s.lights.at(0);
      l.type = GI_LIGHT_DIRECTIONAL;
      glm::vec3 d = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
      l.direction[0] = d.x, l.direction[1] = d.y, l.direction[2] = d.z;
      l.intensity[0] = 2.0f, l.intensity[1] = 1.5f, l.intensity[2] = 1.0f;
    }
    const int N = 2048;
    Renderer r(ctx, s, settings(16, 16, {"second-order.count=2048", "rsm.resolution=128"}));
    r.renderFrame();
    TechniqueRun run(r);
    const ReflectiveShadowMap& rsm = r.rsms().at(0);
    auto pos = ctx.download<glm::vec4>(rsm.position), nrm = ctx.download<glm::vec4>(rsm.normal),
         flux = ctx.download<glm::vec4>(rsm.flux);
    const GiLight& light = s.lights.at(0);
    std::vector<glm::vec4> samples;
    float weight;
    if (directional) {
      samples = haltonSquarePoints(N);
      weight = float(rsm.view.width) * float(rsm.view.width) / float(N);
    } else {
      float c = acceptedConeCos(light, rsm.view);
      EXPECT_FLOAT_EQ(c, light.cos_outer);  // a 60° spot fits its RSM
      samples = haltonConeDirections(c, N);
      weight = coneSolidAngle(c) / float(N);
    }
    std::vector<HostVpl> host = hostPlaceIndirectLights(rsm.view, samples, weight, pos, nrm, flux, 0.0f);
    std::vector<HostVpl> dev = toHost(ctx.download<glm::vec4>(run.technique.lights().vpls), 0, N);
    double devPower = 0, rsmPower = 0;
    int lit = 0;
    for (int k = 0; k < N; ++k) {
      expectSameLight(dev[k], host[k], (directional ? "sun light " : "spot light ") + std::to_string(k));
      devPower += lum(dev[k].flux);
      lit += lum(dev[k].flux) > 0;
    }
    for (const glm::vec4& f : flux) rsmPower += lum(glm::vec3(f));
    EXPECT_GT(lit, N / 3);  // the box is open at the front: part of the spot's cone leaves it
    // Both estimate the power leaving lit surfaces: the RSM by its texel grid, the lights by N
    // Halton samples of the cone or beam.
    EXPECT_NEAR(devPower / rsmPower, 1.0, 0.02) << (directional ? "directional" : "spot");
    std::printf("%s: %d indirect lights carry %.5f W (luminance), the RSM %.5f W\n",
                directional ? "directional" : "spot", N, devPower, rsmPower);
  }
}

TEST(SecondOrderNegativeLights, KernelMatchesHostMirror) {
  cl::Context& ctx = test::context();
  Scene s = test::cornellWithSpot(true);
  const int W = 40, H = 32, N = 96, M = 48;
  Renderer r(ctx, s, settings(W, H, {"second-order.count=96", "rsm.resolution=64"}));
  r.renderFrame();
  TechniqueRun run(r);
  const GBuffer& g = r.gbuffer();
  auto raw = ctx.download<glm::vec4>(run.technique.lights().vpls);
  ASSERT_EQ(raw.size(), size_t(N + M) * 3);
  std::vector<HostVpl> positive = toHost(raw, 0, N), negative = toHost(raw, N, M);
  auto counters = ctx.download<int>(run.technique.counters());
  auto picked = ctx.download<int>(run.technique.negativePixels());
  auto pos = ctx.download<glm::vec4>(g.position), gn = ctx.download<glm::vec4>(g.geoNormal);
  auto depth = ctx.download<float>(g.visibility.depth);
  auto inst = ctx.download<uint32_t>(g.instance);
  int surface = 0;
  for (uint32_t id : inst) surface += id != GI_INVALID_ID;
  EXPECT_EQ(counters[1], surface);
  // The first M surface pixels along the screen's Halton sequence.
  std::vector<int> expected;
  for (int p : haltonScreenPixels(W, H, 4096))
    if (expected.size() < size_t(M) && inst[p] != GI_INVALID_ID) expected.push_back(p);
  ASSERT_EQ(counters[2], M);
  int blocking = 0;
  for (int j = 0; j < M; ++j) {
    ASSERT_EQ(picked[j], expected[j]) << j;
    int p = picked[j];
    HostVpl h = hostNegativeLight(positive, glm::vec3(pos[p]), glm::vec3(gn[p]), depth[p], g.view, surface, M, 0.0f);
    expectSameLight(negative[j], h, "negative light " + std::to_string(j));
    EXPECT_LE(negative[j].flux.y, 0.0f);
    if (negative[j].flux.y < 0.0f) {
      ++blocking;
      // It emits into the half-space its surface faces (the light passed through from behind).
      EXPECT_GT(glm::dot(negative[j].normal, glm::vec3(gn[p])), 0.0f) << j;
    }
  }
  // With blocks some visible surfaces are lit from behind (block faces turned from the floor's
  // lights); the walls of the closed box never are.
  EXPECT_GT(blocking, 0);
  EXPECT_LT(blocking, M);
}

TEST(SecondOrderShading, FullResolutionIsRhoOverPiTimesClampedNetIrradiance) {
  cl::Context& ctx = test::context();
  Scene s = test::cornellWithSpot(true);
  const int W = 33, H = 27, N = 80;
  Renderer r(ctx, s, settings(W, H, {"second-order.count=80", "second-order.multires=0", "rsm.resolution=64"}));
  r.renderFrame();
  TechniqueRun run(r);
  Image out = r.indirectRadiance();  // the renderer's own instance: must equal the test's
  auto mine = ctx.download<glm::vec4>(run.indirect);
  const GBuffer& g = r.gbuffer();
  auto raw = ctx.download<glm::vec4>(run.technique.lights().vpls);
  const int M = N / 2;
  std::vector<HostVpl> positive = toHost(raw, 0, N), negative = toHost(raw, N, M);
  auto pos = ctx.download<glm::vec4>(g.position), nrm = ctx.download<glm::vec4>(g.normal),
       alb = ctx.download<glm::vec4>(g.albedo);
  int clamped = 0, subtracted = 0;
  for (int p = 0; p < W * H; ++p) {
    glm::vec3 es(0.0f), en(0.0f);
    if (pos[p].w > 0) {
      es = hostIrradiance(positive, glm::vec3(pos[p]), glm::vec3(nrm[p]));
      en = hostIrradiance(negative, glm::vec3(pos[p]), glm::vec3(nrm[p]));  // ≤ 0
    }
    glm::vec3 expected = glm::vec3(alb[p]) * glm::max(es + en, 0.0f) * kInvPi;
    glm::vec3 scale = glm::vec3(alb[p]) * (es - en) * kInvPi;
    for (int c = 0; c < 3; ++c) {
      ASSERT_NEAR(mine[p][c], expected[c], 1e-4f * scale[c] + 1e-7f) << "pixel " << p << " ch " << c;
      ASSERT_EQ(mine[p][c], out.pixels[p * 3 + c]) << "pixel " << p;
    }
    clamped += es.y + en.y < 0.0f;
    subtracted += en.y < 0.0f;
  }
  EXPECT_GT(subtracted, 0);
  std::printf("%d of %d pixels lose light to negative lights, %d are clamped at 0\n", subtracted, W * H, clamped);
}

TEST(SecondOrderShading, MultiResolutionReshadesExactlyTheDiscontinuityPixels) {
  cl::Context& ctx = test::context();
  Scene s = test::cornellWithSpot(true);
  const int W = 45, H = 38;  // odd: the last column/row have parents inside the image
  Renderer full(ctx, s, settings(W, H, {"second-order.count=64", "second-order.multires=0", "rsm.resolution=64"}));
  full.renderFrame();
  Image ref = full.indirectRadiance();
  Renderer r(ctx, s, settings(W, H, {"second-order.count=64", "rsm.resolution=64"}));
  r.renderFrame();
  Image a = r.indirectRadiance();
  r.renderFrame();
  Image b = r.indirectRadiance();
  ASSERT_EQ(0, std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * 4)) << "not deterministic";
  TechniqueRun run(r);
  const GBuffer& g = r.gbuffer();
  auto depth = ctx.download<float>(g.visibility.depth);
  auto nrm = ctx.download<glm::vec4>(g.normal);
  auto inst = ctx.download<uint32_t>(g.instance);
  auto flags = ctx.download<uint8_t>(run.technique.flags());
  auto counters = ctx.download<int>(run.technique.counters());
  const float cosTau = std::cos(25.0f * float(M_PI) / 180.0f);
  int reshaded = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      size_t i = size_t(y) * W + x, q = size_t(y & ~1) * W + (x & ~1);
      bool surface = inst[i] != GI_INVALID_ID;
      bool differs = inst[q] == GI_INVALID_ID || std::abs(depth[q] - depth[i]) > 0.02f * depth[i] ||
                     glm::dot(glm::vec3(nrm[q]), glm::vec3(nrm[i])) < cosTau;
      bool reshade = surface && i != q && differs;
      ASSERT_EQ(flags[i], (reshade ? 1 : 0) | (surface ? 2 : 0)) << x << "," << y;
      reshaded += reshade;
      if (reshade)  // re-shaded pixels are the full-resolution result, bit for bit
        for (int c = 0; c < 3; ++c) ASSERT_EQ(a.pixels[i * 3 + c], ref.pixels[i * 3 + c]) << x << "," << y;
    }
  EXPECT_EQ(counters[0], reshaded);
  EXPECT_GT(reshaded, 0);
  EXPECT_LT(reshaded, W * H / 2);
}

TEST(SecondOrderParams, BadValuesAreErrorsNamingTheParameter) {
  Scene s = test::cornellWithSpot(false);
  for (const char* bad : {"second-order.count=0", "second-order.placement=sobol", "second-order.tau_d=-1",
                          "second-order.negative=-2"}) {
    try {
      Renderer r(test::context(), s, settings(8, 8, {bad}));
      ADD_FAILURE() << bad << " accepted";
    } catch (const Error& e) {
      std::string name = std::string(bad).substr(0, std::string(bad).find('='));
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}
