// Keller's further VPL generations (kernels/gi/vpl/vpl_bounce.cl; docs/techniques/vpl.md "Bounces")
// on hand-built scenes with hand-placed generation-0 VPLs:
//   - VPLs over a plane: every child lies where the host's walk direction meets the plane
//     (analytic ray-plane intersection, not the BVH) with flux Φ·ρ·(live/N_g) or Φ·ρ/m when a walk
//     splits m ways; independently of that mirror, the flux landing within radius R of the foot
//     point is the cosine emitter's share R²/(R² + h²); parents without flux get no children; two
//     lights keep their blocks apart;
//   - a closed sphere of albedo ρ (furnace-like): every ray lands, each generation carries ρ times
//     the power of the one before, and the children spread uniformly over the sphere (a cosine
//     emitter on a sphere lights its inside uniformly);
//   - same input, same bits;
//   - every VPL technique gathers all generations: `vpl` equals the host sum over the generated
//     list, `igi` 1×1 equals `vpl` bit for bit, `splat` (cut-off beyond the scene) equals it, and
//     bounces brighten `sh-igi` as they brighten `vpl`.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "accuracy_support.h"
#include "vpl_bounce_support.h"
#include "gi/vpl/vpl_lights.h"
#include "render/renderer.h"
#include "reference/bvh.h"
#include "reference_scenes.h"
#include "scene/device_scene.h"
#include "scene_builders.h"
#include "test_support.h"

using namespace gi;

namespace {

struct Vpl {
  glm::vec3 position, normal, flux;
  float dmin2;
};

// Generation-0 VPLs at the start of a buffer with room for all generations.
VplSet seed(cl::Context& ctx, const std::vector<Vpl>& first, int total) {
  std::vector<glm::vec4> raw(size_t(total) * 3, glm::vec4(0.0f));
  for (size_t k = 0; k < first.size(); ++k) {
    raw[3 * k] = glm::vec4(first[k].position, first[k].dmin2);
    raw[3 * k + 1] = glm::vec4(first[k].normal, 0.0f);
    raw[3 * k + 2] = glm::vec4(first[k].flux, 0.0f);
  }
  VplSet s;
  s.vpls = ctx.upload(raw, "test VPLs", CL_MEM_READ_WRITE);
  s.count = total;
  s.perLight = int(first.size());
  return s;
}

std::vector<Vpl> download(cl::Context& ctx, const VplSet& s) {
  std::vector<glm::vec4> raw = ctx.download<glm::vec4>(s.vpls);
  std::vector<Vpl> v(raw.size() / 3);
  for (size_t k = 0; k < v.size(); ++k)
    v[k] = {glm::vec3(raw[3 * k]), glm::vec3(raw[3 * k + 1]), glm::vec3(raw[3 * k + 2]), raw[3 * k].w};
  return v;
}

int totalOf(const std::vector<int>& sizes) {
  int t = 0;
  for (int n : sizes) t += n;
  return t;
}

}  // namespace

// Where the ray of child k of m of the parent in slot `walk` meets the plane y = 0.
glm::vec3 planeHit(glm::vec3 origin, glm::vec3 n, float eps, int walk, int k, int m) {
  glm::vec3 d = hostBounceDirection(n, walk, 1, k, m);
  EXPECT_NEAR(glm::length(d), 1.0f, 1e-5f);
  glm::vec3 o = origin + n * eps;
  return o + d * (-o.y / d.y);
}

TEST(VplBounce, VplsOverAPlaneLandWhereTheHostWalksMeetThePlane) {
  cl::Context& ctx = test::context();
  const float half = 100.0f, h = 1.0f, eps = 1e-3f;
  const glm::vec3 rho(0.6f, 0.4f, 0.2f), phi(2.0f, 3.0f, 4.0f);
  Scene s;
  s.name = "plane";
  s.materials.push_back(test::diffuseMaterial(rho));
  test::addQuad(s, glm::vec3(-half, 0.0f, half), glm::vec3(2 * half, 0, 0), glm::vec3(0, 0, -2 * half), 0);  // faces +y
  s.computeBounds();
  DeviceScene ds(ctx, s);
  DeviceBvh bvh(ctx, s, ds);
  VplGenerator gen(ctx);
  const glm::vec3 origin(0.0f, h, 0.0f), down(0.0f, -1.0f, 0.0f);
  VplBounces b;
  b.generations = 1;
  b.rayEpsilon = eps;
  b.scene = &ds;
  b.bvh = &bvh;
  auto onPlane = [&](glm::vec3 p) { return std::abs(p.x) < 0.99f * half && std::abs(p.z) < 0.99f * half; };

  // 1024 live parents at one point; fraction 1: one child each; 0.5: the first 512 continue, × 2.
  const int n0 = 1024;
  for (float fraction : {1.0f, 0.5f}) {
    b.fraction = fraction;
    std::vector<int> sizes = vplGenerationSizes(n0, b);
    ASSERT_EQ(sizes.size(), 2u);
    ASSERT_EQ(sizes[1], int(fraction * n0));
    VplSet set = seed(ctx, std::vector<Vpl>(n0, Vpl{origin, down, phi, 0.01f}), totalOf(sizes));
    gen.bounce(1, b, set);
    std::vector<Vpl> v = download(ctx, set);
    const float scale = float(n0) / float(sizes[1]);
    int landed = 0;
    for (int j = 0; j < sizes[1]; ++j) {
      const Vpl& c = v[size_t(n0 + j)];
      glm::vec3 hit = planeHit(origin, down, eps, j, 0, 1);
      if (!onPlane(hit)) continue;  // grazing, may miss
      ++landed;
      ASSERT_NEAR(glm::distance(c.position, hit), 0.0f, 1e-4f * (1.0f + glm::length(hit))) << "walk " << j;
      ASSERT_NEAR(c.normal.y, 1.0f, 1e-6f);
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(c.flux[k], phi[k] * rho[k] * scale, 1e-5f * phi[k] * rho[k] * scale);
      ASSERT_EQ(c.dmin2, 0.01f);
    }
    EXPECT_GE(landed, int(0.99 * sizes[1]));
    // Independent of the mirror: the cosine emitter's share within radius R of the foot point is
    // sin²θ_R = R² / (R² + h²).
    double total = 0;
    for (int j = 0; j < sizes[1]; ++j) total += v[size_t(n0 + j)].flux.y;
    for (float R : {0.25f, 0.5f, 1.0f, 2.0f, 4.0f}) {
      double inside = 0;
      for (int j = 0; j < sizes[1]; ++j) {
        const Vpl& c = v[size_t(n0 + j)];
        if (std::hypot(c.position.x, c.position.z) < R) inside += c.flux.y;
      }
      double expected = double(R) * R / (double(R) * R + double(h) * h) * n0 * phi.y * rho.y;
      EXPECT_NEAR(inside, expected, 0.01 * n0 * phi.y * rho.y) << "R " << R << ", fraction " << fraction;
    }
    EXPECT_NEAR(total, n0 * phi.y * rho.y, 0.01 * n0 * phi.y * rho.y);
  }

  // 4 live parents of 16 (the others without flux) and 16 slots: each live walk splits 4 ways,
  // child k of parent rank r in slot r + 4k, flux Φ·ρ/4; the 4 directions of one parent are
  // stratified, so their hits spread around the foot point.
  b.fraction = 1.0f;
  const int live[4] = {1, 6, 7, 12};
  std::vector<Vpl> first(16, Vpl{origin, down, glm::vec3(0.0f), 0.01f});
  for (int p : live) first[size_t(p)] = Vpl{origin + glm::vec3(0.1f * p, 0.0f, 0.0f), down, phi * float(p), 0.01f};
  VplSet set = seed(ctx, first, 32);
  gen.bounce(1, b, set);
  std::vector<Vpl> v = download(ctx, set);
  for (int j = 0; j < 16; ++j) {
    int r = j % 4, k = j / 4, p = live[r];
    const Vpl& c = v[size_t(16 + j)];
    glm::vec3 hit = planeHit(first[size_t(p)].position, down, eps, p, k, 4);
    ASSERT_TRUE(onPlane(hit));
    EXPECT_NEAR(glm::distance(c.position, hit), 0.0f, 1e-4f * (1.0f + glm::length(hit))) << "slot " << j;
    for (int q = 0; q < 3; ++q) EXPECT_NEAR(c.flux[q], phi[q] * float(p) * rho[q] / 4.0f, 1e-5f * phi[q] * p);
  }
  for (int r = 0; r < 4; ++r) {
    glm::vec3 mean(0.0f);
    for (int k = 0; k < 4; ++k) mean += v[size_t(16 + r + 4 * k)].position - first[size_t(live[r])].position;
    EXPECT_LT(std::hypot(mean.x, mean.z) / 4.0f, 1.5f * h) << "split directions of parent " << live[r] << " bunched";
  }
  // Two lights, generation-major and light by light: [light 0: 16][light 1: 16] then the children
  // [light 0: 16][light 1: 16]. Light 0 has no live parent (its children carry nothing); light 1's
  // children are the single-light result above.
  std::vector<Vpl> twoLights(16, Vpl{origin, down, glm::vec3(0.0f), 0.01f});
  twoLights.insert(twoLights.end(), first.begin(), first.end());
  VplSet both = seed(ctx, twoLights, 64);
  both.perLight = 16;
  gen.bounce(2, b, both);
  std::vector<Vpl> w = download(ctx, both);
  for (int j = 0; j < 16; ++j) {
    EXPECT_EQ(w[size_t(32 + j)].flux, glm::vec3(0.0f)) << "light 0 slot " << j;
    EXPECT_EQ(w[size_t(48 + j)].position, v[size_t(16 + j)].position) << "light 1 slot " << j;
    EXPECT_EQ(w[size_t(48 + j)].flux, v[size_t(16 + j)].flux) << "light 1 slot " << j;
  }
  // No live parent: every slot without flux.
  VplSet dead = seed(ctx, std::vector<Vpl>(8, Vpl{origin, down, glm::vec3(0.0f), 0.01f}), 16);
  gen.bounce(1, b, dead);
  for (int j = 8; j < 16; ++j) EXPECT_EQ(download(ctx, dead)[size_t(j)].flux, glm::vec3(0.0f));
}

TEST(VplBounce, ClosedSphereCarriesAlbedoTimesThePowerPerGeneration) {
  cl::Context& ctx = test::context();
  const float rho = 0.5f, radius = 1.0f;
  Scene s = test::insideSphere(24, radius, rho);
  DeviceScene ds(ctx, s);
  DeviceBvh bvh(ctx, s, ds);
  // 256 generation-0 VPLs of 1 W on the inside wall (Halton points on the sphere), facing inwards,
  // and one without flux.
  const int n0 = 257;
  std::vector<Vpl> first;
  for (int k = 0; k < n0; ++k) {
    float z = 1.0f - 2.0f * radicalInverse(uint32_t(k) + 1, 2), a = 6.2831853f * radicalInverse(uint32_t(k) + 1, 3);
    glm::vec3 p(std::sqrt(1.0f - z * z) * std::cos(a), z, std::sqrt(1.0f - z * z) * std::sin(a));
    first.push_back({0.98f * radius * p, -p, k == 100 ? glm::vec3(0.0f) : glm::vec3(1.0f), 1e-4f});
  }
  VplBounces b;
  b.generations = 4;
  b.fraction = 0.5f;
  b.rayEpsilon = 1e-3f;
  b.scene = &ds;
  b.bvh = &bvh;
  std::vector<int> sizes = vplGenerationSizes(n0, b);
  ASSERT_EQ(sizes, (std::vector<int>{257, 129, 65, 33, 17}));
  VplGenerator gen(ctx);
  VplSet a = seed(ctx, first, totalOf(sizes)), again = seed(ctx, first, totalOf(sizes));
  gen.bounce(1, b, a);
  gen.bounce(1, b, again);
  auto ra = ctx.download<glm::vec4>(a.vpls), rb = ctx.download<glm::vec4>(again.vpls);
  EXPECT_EQ(0, std::memcmp(ra.data(), rb.data(), ra.size() * sizeof(glm::vec4))) << "not deterministic";
  std::vector<Vpl> v = download(ctx, a);
  // Every ray lands (closed sphere); generation g continues the first N_g live walks of g − 1
  // (N_g < live count here), each child carrying Φ_parent · ρ · live/N_g.
  int offset = 0;
  std::vector<double> power;
  for (size_t g = 0; g < sizes.size(); ++g) {
    double p = 0;
    glm::dvec3 mean(0.0);
    for (int j = 0; j < sizes[g]; ++j) {
      const Vpl& c = v[size_t(offset + j)];
      p += c.flux.x;
      if (g == 0) continue;
      EXPECT_GT(c.flux.x, 0.0f) << "generation " << g << " slot " << j << ": a ray left the closed sphere";
      EXPECT_NEAR(glm::length(c.position), radius, 0.01f) << "generation " << g << " VPL " << j;
      EXPECT_GT(glm::dot(c.normal, -glm::normalize(c.position)), 0.99f);
      mean += glm::dvec3(c.position);
    }
    power.push_back(p);
    if (g == 1) EXPECT_LT(glm::length(mean / double(sizes[g])), 0.1) << "children not spread over the sphere";
    if (g > 0) {
      std::vector<double> liveFlux;
      for (int j = 0; j < sizes[g - 1]; ++j)
        if (v[size_t(offset - sizes[g - 1] + j)].flux.x > 0.0f) liveFlux.push_back(v[size_t(offset - sizes[g - 1] + j)].flux.x);
      ASSERT_LT(sizes[g], int(liveFlux.size()));
      double expected = 0;
      for (int j = 0; j < sizes[g]; ++j) expected += rho * liveFlux[size_t(j)] * double(liveFlux.size()) / sizes[g];
      EXPECT_NEAR(p, expected, 1e-5 * p) << "generation " << g;
    }
    offset += sizes[g];
  }
  // ρ^g of the seeds' power, within the stratification error of the continued prefix.
  for (size_t g = 1; g < power.size(); ++g)
    EXPECT_NEAR(power[g] / power[0], std::pow(rho, double(g)), 0.02 * std::pow(rho, double(g))) << "generation " << g;
}

TEST(VplBounce, GenerationSizesAndBadInput) {
  VplBounces b;
  EXPECT_EQ(vplGenerationSizes(256, b), std::vector<int>{256});
  b.generations = 3;
  b.fraction = 0.3f;
  EXPECT_EQ(vplGenerationSizes(100, b), (std::vector<int>{100, 30, 9, 3}));
  b.fraction = 1.0f;
  EXPECT_EQ(vplGenerationSizes(7, b), (std::vector<int>{7, 7, 7, 7}));
  cl::Context& ctx = test::context();
  VplGenerator gen(ctx);
  VplSet set = seed(ctx, {Vpl{glm::vec3(0.0f), glm::vec3(0, 1, 0), glm::vec3(1.0f), 0.0f}}, 4);
  EXPECT_THROW(gen.bounce(1, b, set), Error) << "bounces without a BVH";
  EXPECT_THROW(bounceSequence(9), Error);
  glm::uvec4 q = bounceSequence(4);
  EXPECT_EQ(q, glm::uvec4(23, 14, 29, 18));
}

TEST(VplBounce, EveryVplTechniqueGathersAllGenerations) {
  cl::Context& ctx = test::context();
  Scene s = test::cornellWithSpot(true);
  const int W = 29, H = 22;
  auto run = [&](const std::string& tech, std::vector<std::string> sets) {
    Renderer r(ctx, s, test::smallRenderSettings(tech, W, H, std::move(sets)));
    r.renderFrame();
    return r.indirectRadiance();
  };
  Renderer r(ctx, s, test::smallRenderSettings("vpl", W, H, {"vpl.count=64", "vpl.bounces=2"}));
  r.renderFrame();
  Image a = r.indirectRadiance();
  // The host sum over the list VplGenerator makes with the same settings (all generations).
  std::vector<HostVpl> vpls = test::generatedVpls(ctx, s, r, 64, 2);
  ASSERT_EQ(vpls.size(), size_t(64 + 32 + 16));
  auto pos = ctx.download<glm::vec4>(r.gbuffer().position), nrm = ctx.download<glm::vec4>(r.gbuffer().normal),
       alb = ctx.download<glm::vec4>(r.gbuffer().albedo);
  ctx.profiler().discard();
  for (int p = 0; p < W * H; ++p) {
    glm::vec3 e = pos[p].w > 0 ? hostIrradiance(vpls, glm::vec3(pos[p]), glm::vec3(nrm[p])) : glm::vec3(0.0f);
    glm::vec3 expected = glm::vec3(alb[p]) * e * 0.31830988618379067154f;
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(a.pixels[size_t(p) * 3 + c], expected[c], 1e-4f * expected[c] + 1e-7f) << "pixel " << p;
  }
  Image one = run("vpl", {"vpl.count=64"});
  EXPECT_GT(test::meanOf(a), 1.1 * test::meanOf(one)) << "the bounces add light";
  Image igi = run("igi", {"igi.count=64", "igi.n=1", "igi.m=1", "vpl.bounces=2"});
  EXPECT_EQ(0, std::memcmp(a.pixels.data(), igi.pixels.data(), a.pixels.size() * sizeof(float)));
  Image splat = run("splat", {"splat.count=64", "splat.epsilon=1e-12", "vpl.bounces=2"});
  for (size_t i = 0; i < a.pixels.size(); ++i)
    ASSERT_NEAR(splat.pixels[i], a.pixels[i], 1e-5f * std::abs(a.pixels[i]) + 1e-9f) << "value " << i;
  double shOne = test::meanOf(run("sh-igi", {"sh-igi.count=64"}));
  double shBounced = test::meanOf(run("sh-igi", {"sh-igi.count=64", "vpl.bounces=2"}));
  EXPECT_NEAR(shBounced / shOne, test::meanOf(a) / test::meanOf(one), 0.05 * test::meanOf(a) / test::meanOf(one));
}
