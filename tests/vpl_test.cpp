// Instant radiosity kernels against host implementations of the same formulas on tiny inputs
// (ALGORITHMS.md §2, §2.2, §2.3, §3): VPL generation (flux-importance Halton sampling), the
// all-pairs gather, interleaving (de-interleave ∘ re-interleave = identity, per-set shading),
// igi 1×1 == vpl exactly, the discontinuity filter; the one-pixel-per-work-item path (GI_VW = 1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <tuple>

#include "gi/filters/discontinuity_filter.h"
#include "gi/vpl/vpl_lights.h"
#include "render/renderer.h"
#include "scene/cornell_box.h"
#include "test_support.h"

using namespace gi;

namespace {

Scene emptyCornellWithSpot() {
  CornellOptions o;
  o.withBlocks = false;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  o.spotLight->intensity = glm::vec3(1.2f, 1.0f, 0.8f);
  return makeCornellBox(o);
}

// With blocks: depth and normal discontinuities for the geometry-aware passes.
Scene cornellWithBlocksAndSpot() {
  CornellOptions o;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  return makeCornellBox(o);
}

template <typename T>
std::vector<T> download(cl::Context& ctx, const cl::Buffer& b) {
  return ctx.download<T>(b);
}

std::vector<HostVpl> toHost(const std::vector<glm::vec4>& raw) {
  std::vector<HostVpl> v(raw.size() / 3);
  for (size_t k = 0; k < v.size(); ++k) {
    v[k].position = glm::vec3(raw[3 * k]);
    v[k].dmin2 = raw[3 * k].w;
    v[k].normal = glm::vec3(raw[3 * k + 1]);
    v[k].flux = glm::vec3(raw[3 * k + 2]);
  }
  return v;
}


float luminanceOf(glm::vec3 c) { return c.x * 0.2126f + c.y * 0.7152f + c.z * 0.0722f; }

}  // namespace

TEST(VplGeneration, MatchesHostMirrorIsDeterministicAndConservesFlux) {
  cl::Context& ctx = test::context();
  Scene s = emptyCornellWithSpot();
  Renderer r(ctx, s, test::smallRenderSettings("vpl", 16, 16, {"vpl.count=300"}));
  r.renderFrame();
  const ReflectiveShadowMap& rsm = r.rsms().at(0);
  int res = rsm.view.width;
  auto pos = download<glm::vec4>(ctx, rsm.position), nrm = download<glm::vec4>(ctx, rsm.normal),
       flux = download<glm::vec4>(ctx, rsm.flux);
  VplGenerator gen(ctx);
  VplSet a, b;
  for (int count : {1, 7, 300, 4096}) {
    gen.generate(r.rsms(), count, 0.0f, a);
    gen.generate(r.rsms(), count, 0.0f, b);
    ctx.profiler().discard();
    auto ra = download<glm::vec4>(ctx, a.vpls), rb = download<glm::vec4>(ctx, b.vpls);
    ASSERT_EQ(ra.size(), size_t(count) * 3);
    EXPECT_EQ(0, std::memcmp(ra.data(), rb.data(), ra.size() * 16)) << "not deterministic, N=" << count;
    std::vector<HostVpl> dev = toHost(ra);
    std::vector<HostVpl> host = hostGenerateVpls(rsm.view, pos, nrm, flux, res, count, 0.0f);
    int same = 0;
    double lumSum = 0;
    for (int k = 0; k < count; ++k) {
      lumSum += luminanceOf(dev[k].flux);
      if (glm::length(dev[k].position - host[k].position) > 1e-6f) continue;  // a CDF tie picked a neighbour
      ++same;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(dev[k].flux[c], host[k].flux[c], 1e-4f * std::abs(host[k].flux[c]) + 1e-9f);
      EXPECT_NEAR(dev[k].dmin2, host[k].dmin2, 1e-4f * host[k].dmin2);
      EXPECT_NEAR(glm::dot(dev[k].normal, host[k].normal), 1.0f, 1e-5f);
    }
    EXPECT_GE(same, int(0.99 * count)) << "N=" << count;
    // Every VPL carries luminance Σlum/N exactly (pdf ∝ luminance): the sum is the RSM's total.
    double total = 0;
    for (auto& f : flux) total += std::max(0.0f, luminanceOf(glm::vec3(f)));
    EXPECT_NEAR(lumSum, total, 1e-4 * total) << "N=" << count;
  }
  // d_min override and the default (0.5 × texel footprint, perspective RSM: grows with depth).
  gen.generate(r.rsms(), 16, 0.01f, a);
  for (const HostVpl& v : toHost(download<glm::vec4>(ctx, a.vpls))) EXPECT_FLOAT_EQ(v.dmin2, 1e-4f);
  ctx.profiler().discard();
}

TEST(VplGather, KernelMatchesHostFormulaOnOddImage) {
  cl::Context& ctx = test::context();
  Scene s = emptyCornellWithSpot();
  const int W = 23, H = 19;  // not multiples of 16: padded slots
  Renderer r(ctx, s, test::smallRenderSettings("vpl", W, H, {"vpl.count=64"}));
  r.renderFrame();
  Image ind = r.indirectRadiance();
  VplGenerator gen(ctx);
  VplSet v;
  gen.generate(r.rsms(), 64, 0.0f, v);
  ctx.profiler().discard();
  std::vector<HostVpl> vpls = toHost(download<glm::vec4>(ctx, v.vpls));
  auto pos = download<glm::vec4>(ctx, r.gbuffer().position), nrm = download<glm::vec4>(ctx, r.gbuffer().normal),
       alb = download<glm::vec4>(ctx, r.gbuffer().albedo);
  int lit = 0;
  for (int p = 0; p < W * H; ++p) {
    glm::vec3 e(0.0f);
    if (pos[p].w > 0) e = hostIrradiance(vpls, glm::vec3(pos[p]), glm::vec3(nrm[p]));
    glm::vec3 expected = glm::vec3(alb[p]) * e * 0.31830988618379067154f;
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(ind.pixels[p * 3 + c], expected[c], 1e-4f * expected[c] + 1e-7f) << "pixel " << p << " ch " << c;
    lit += expected.y > 0;
  }
  EXPECT_GT(lit, W * H / 2);
}

TEST(VplGather, OnePixelPerWorkItemPathGivesTheSameImage) {
  Scene s = emptyCornellWithSpot();
  auto renderWith = [&](cl::Context& ctx, const std::string& technique, std::vector<std::string> sets) {
    Renderer r(ctx, s, test::smallRenderSettings(technique, 21, 17, std::move(sets)));
    r.renderFrame();
    return r.indirectRadiance();
  };
  const char* old = std::getenv("GI_VECTOR_WIDTH");
  std::string saved = old ? old : "";
  setenv("GI_VECTOR_WIDTH", test::context().vectorWidth() == 1 ? "16" : "1", 1);
  cl::Context other(cl::selectDevice(std::getenv("GI_DEVICE") ? "" : "cpu"));
  if (old) setenv("GI_VECTOR_WIDTH", saved.c_str(), 1);
  else unsetenv("GI_VECTOR_WIDTH");
  ASSERT_NE(other.vectorWidth(), test::context().vectorWidth());
  for (auto [tech, sets] : {std::pair<std::string, std::vector<std::string>>{"vpl", {"vpl.count=100"}},
                            {"igi", {"igi.count=100", "igi.n=3", "igi.m=2"}}}) {
    Image a = renderWith(test::context(), tech, sets), b = renderWith(other, tech, sets);
    for (size_t i = 0; i < a.pixels.size(); ++i)
      ASSERT_NEAR(a.pixels[i], b.pixels[i], 1e-5f * std::abs(a.pixels[i]) + 1e-9f) << tech << " value " << i;
  }
}

TEST(Igi, DeinterleaveThenReinterleaveIsIdentityForEveryPattern) {
  cl::Context& ctx = test::context();
  InterleavedGather ig(ctx, "test");
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> U(-1.0f, 1.0f);
  for (auto [W, H] : {std::pair{13, 7}, std::pair{37, 29}, std::pair{16, 16}}) {
    GBuffer g;
    g.allocate(ctx, W, H);
    std::vector<glm::vec4> pos(size_t(W) * H), nrm(size_t(W) * H);
    for (size_t i = 0; i < pos.size(); ++i) {
      pos[i] = glm::vec4(U(rng), U(rng), U(rng), i % 5 == 3 ? 0.0f : 1.0f);  // every 5th: background
      nrm[i] = glm::vec4(U(rng), U(rng), U(rng), 0.0f);
    }
    ctx.write(g.position, pos.data(), pos.size() * 16);
    ctx.write(g.normal, nrm.data(), nrm.size() * 16);
    cl::Buffer out(ctx, pos.size() * 16);
    for (int n = 1; n <= 8; ++n)
      for (int m = 1; m <= 8; ++m) {
        ig.resize(W, H, n, m);
        ig.deinterleave(g);
        auto planes = download<float>(ctx, ig.planes());
        size_t L = ig.slots();
        // The host index formula matches the kernel, and every slot is hit at most once.
        std::vector<int> hits(L, 0);
        for (int y = 0; y < H; ++y)
          for (int x = 0; x < W; ++x) {
            size_t o = packedIndex(x, y, n, m, ig.subPitch(), ig.stride());
            ASSERT_LT(o, L);
            ASSERT_EQ(++hits[o], 1);
            ASSERT_EQ(planes[o], pos[size_t(y) * W + x].x);
            bool surface = pos[size_t(y) * W + x].w > 0;
            ASSERT_EQ(planes[4 * L + o], surface ? nrm[size_t(y) * W + x].y : 0.0f);  // background: E = 0
          }
        // Slots without a pixel (padding of the sub-images) hold a zero normal: E = 0 there.
        for (size_t o = 0; o < L; ++o)
          if (!hits[o])
            ASSERT_TRUE(planes[3 * L + o] == 0 && planes[4 * L + o] == 0 && planes[5 * L + o] == 0)
                << n << "x" << m << " " << W << "x" << H << " slot " << o;
        ctx.copy(ig.planes(), ig.irradiance(), 3 * L * 4);  // x, y, z planes as "irradiance"
        ig.reinterleaveIrradiance(out);
        auto back = download<glm::vec4>(ctx, out);
        for (size_t i = 0; i < pos.size(); ++i)
          ASSERT_EQ(glm::vec3(back[i]), glm::vec3(pos[i])) << n << "x" << m << " " << W << "x" << H << " pixel " << i;
      }
    ctx.profiler().discard();
  }
}

TEST(Igi, EachSubImageIsShadedWithItsOwnVplSet) {
  cl::Context& ctx = test::context();
  Scene s = emptyCornellWithSpot();
  const int W = 19, H = 14, n = 3, m = 2, N = 50;  // N not a multiple of n·m
  Renderer r(ctx, s, test::smallRenderSettings("igi", W, H, {"igi.count=50", "igi.n=3", "igi.m=2"}));
  r.renderFrame();
  VplGenerator gen(ctx);
  VplSet v;
  gen.generate(r.rsms(), N, 0.0f, v);
  InterleavedGather ig(ctx, "test");
  ig.resize(W, H, n, m);
  ig.deinterleave(r.gbuffer());
  ig.shade(v);
  cl::Buffer e(ctx, size_t(W) * H * 16);
  ig.reinterleaveIrradiance(e);
  auto E = download<glm::vec4>(ctx, e);
  ctx.profiler().discard();
  std::vector<HostVpl> vpls = toHost(download<glm::vec4>(ctx, v.vpls));
  auto pos = download<glm::vec4>(ctx, r.gbuffer().position), nrm = download<glm::vec4>(ctx, r.gbuffer().normal);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      size_t p = size_t(y) * W + x;
      int c = x % n + n * (y % m);
      glm::vec3 expected = pos[p].w > 0 ? hostIrradiance(vpls, glm::vec3(pos[p]), glm::vec3(nrm[p]), c, n * m) : glm::vec3(0);
      for (int ch = 0; ch < 3; ++ch)
        ASSERT_NEAR(E[p][ch], expected[ch], 1e-4f * expected[ch] + 1e-7f) << "pixel " << x << "," << y;
    }
}

TEST(Igi, OneByOnePatternEqualsVplExactly) {
  Scene s = emptyCornellWithSpot();
  auto run = [&](const std::string& tech, std::vector<std::string> sets) {
    Renderer r(test::context(), s, test::smallRenderSettings(tech, 29, 22, std::move(sets)));
    r.renderFrame();
    return r.indirectRadiance();
  };
  Image a = run("vpl", {"vpl.count=77"});
  Image b = run("igi", {"igi.count=77", "igi.n=1", "igi.m=1"});
  ASSERT_EQ(a.pixels.size(), b.pixels.size());
  EXPECT_EQ(0, std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)));
}

// The discontinuity filter (box and separable) against a host mirror of its formula on a real
// G-buffer with discontinuities (Cornell box with blocks), odd sizes, random E.
TEST(Igi, DiscontinuityFilterMatchesHost) {
  cl::Context& ctx = test::context();
  Scene s = cornellWithBlocksAndSpot();
  const int W = 37, H = 31;
  Renderer r(ctx, s, test::smallRenderSettings("vpl", W, H, {"vpl.count=4"}));
  r.renderFrame();
  const GBuffer& g = r.gbuffer();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  std::vector<glm::vec4> E(size_t(W) * H);
  for (auto& e : E) e = glm::vec4(U(rng), U(rng), U(rng), 0.0f);
  cl::Buffer eb = ctx.upload(E, "E"), out(ctx, E.size() * 16);
  auto depth = download<float>(ctx, g.visibility.depth);
  auto gn = download<glm::vec4>(ctx, g.geoNormal), alb = download<glm::vec4>(ctx, g.albedo);
  auto inst = download<uint32_t>(ctx, g.instance);
  DiscontinuityFilter filter(ctx, "test filter");
  for (auto [fx, fy, same] : {std::tuple{4, 4, false}, std::tuple{3, 5, true}, std::tuple{8, 2, false}}) {
    GeometryTest t;
    t.sameInstance = same;
    float cosN = std::cos(t.tauNDegrees * 3.14159265f / 180.0f);
    auto accepts = [&](size_t p, size_t q) {
      return inst[q] != GI_INVALID_ID && std::abs(depth[q] - depth[p]) <= t.tauZ * depth[p] &&
             glm::dot(glm::vec3(gn[q]), glm::vec3(gn[p])) >= cosN && !(same && inst[q] != inst[p]);
    };
    // One pass over a wx × wy window: the filtered E (applyAlbedo false) or L = ρ/π · E.
    auto hostPass = [&](const std::vector<glm::vec4>& in, int wx, int wy, bool applyAlbedo) {
      std::vector<glm::vec4> res(in.size(), glm::vec4(0.0f));
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          size_t p = size_t(y) * W + x;
          if (inst[p] == GI_INVALID_ID) continue;
          glm::vec3 sum(0.0f);
          float w = 0;
          for (int dy = -(wy / 2); dy < wy - wy / 2; ++dy)
            for (int dx = -(wx / 2); dx < wx - wx / 2; ++dx) {
              int qx = x + dx, qy = y + dy;
              if (qx < 0 || qy < 0 || qx >= W || qy >= H) continue;
              size_t q = size_t(qy) * W + qx;
              if (!accepts(p, q)) continue;
              sum += glm::vec3(in[q]);
              w += 1;
            }
          glm::vec3 e = w > 0 ? sum / w : glm::vec3(in[p]);
          res[p] = glm::vec4(applyAlbedo ? glm::vec3(alb[p]) * e * 0.31830988618379067154f : e, 0.0f);
        }
      return res;
    };
    std::vector<glm::vec4> box = hostPass(E, fx, fy, true), sep = hostPass(hostPass(E, fx, 1, false), 1, fy, true);
    for (FilterShape shape : {FilterShape::Box, FilterShape::Separable}) {
      filter.run(g, eb, fx, fy, t, out, shape);
      auto L = download<glm::vec4>(ctx, out);
      const std::vector<glm::vec4>& expected = shape == FilterShape::Box ? box : sep;
      for (size_t p = 0; p < L.size(); ++p)
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(L[p][c], expected[p][c], 1e-5f)
              << fx << "x" << fy << (shape == FilterShape::Box ? " box" : " separable") << " pixel " << p % W << ","
              << p / W;
    }
    // Where p accepts its whole (clipped) window and every column neighbour accepts its whole row
    // window, both forms are the plain mean over the window: the separable form is the box there.
    int clean = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        size_t p = size_t(y) * W + x;
        if (inst[p] == GI_INVALID_ID) continue;
        bool ok = true;
        for (int dy = -(fy / 2); ok && dy < fy - fy / 2; ++dy)
          for (int dx = -(fx / 2); ok && dx < fx - fx / 2; ++dx) {
            int qx = x + dx, qy = y + dy;
            if (qx < 0 || qy < 0 || qx >= W || qy >= H) continue;
            size_t q = size_t(qy) * W + qx, c = size_t(qy) * W + x;
            ok = accepts(p, q) && accepts(p, c) && accepts(c, q);
          }
        if (!ok) continue;
        ++clean;
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(sep[p][c], box[p][c], 1e-5f) << "pixel " << x << "," << y;
      }
    EXPECT_GT(clean, 40) << fx << "x" << fy;  // 64–138 of the 1147 pixels here: not vacuous
  }
  ctx.profiler().discard();
}

// The geometry-aware upsampler (ALGORITHMS.md §3; shared by rsm, second-order, vct, probes)
// against a host mirror of its formula: 2×2 bilinear taps at the low-resolution pixels' guide
// pixels (u·f, v·f), kept by the depth/normal test, renormalised, nearest tap when none passes,
// L = ρ/π · max(0, E). Real G-buffer discontinuities (Cornell box with blocks), odd sizes,
// random E with negative values (second-order's net irradiance can be negative). W = 45 gives
// factor 2 blocks away from the borders (the swizzled-lane path) at 8 and at 16 lanes, next to
// border blocks (the per-lane gathers).
TEST(Igi, GeometryAwareUpsamplerMatchesHost) {
  cl::Context& ctx = test::context();
  Scene s = cornellWithBlocksAndSpot();
  const int W = 45, H = 37;
  Renderer r(ctx, s, test::smallRenderSettings("vpl", W, H, {"vpl.count=4"}));
  r.renderFrame();
  const GBuffer& g = r.gbuffer();
  auto depth = download<float>(ctx, g.visibility.depth);
  auto gn = download<glm::vec4>(ctx, g.geoNormal), alb = download<glm::vec4>(ctx, g.albedo);
  auto inst = download<uint32_t>(ctx, g.instance);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(-0.2f, 1.0f);
  GeometryAwareUpsampler upsampler(ctx, "test upsample");
  GeometryTest t;
  float cosN = std::cos(t.tauNDegrees * 3.14159265f / 180.0f);
  cl::Buffer out(ctx, size_t(W) * H * 16);
  for (int f : {2, 3}) {
    int lw = (W + f - 1) / f, lh = (H + f - 1) / f;
    std::vector<glm::vec4> E(size_t(lw) * lh);
    for (auto& e : E) e = glm::vec4(U(rng), U(rng), U(rng), 0.0f);
    cl::Buffer eb = ctx.upload(E, "low E");
    upsampler.run(g, eb, f, t, out);
    auto L = download<glm::vec4>(ctx, out);
    int accepted = 0, rejected = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        size_t p = size_t(y) * W + x;
        glm::vec3 expected(0.0f);
        if (inst[p] != GI_INVALID_ID) {
          float fx = (float(x) + 0.5f) / float(f) - 0.5f, fy = (float(y) + 0.5f) / float(f) - 0.5f;
          int u0 = std::clamp(int(std::floor(fx)), 0, lw - 1), v0 = std::clamp(int(std::floor(fy)), 0, lh - 1);
          float ax = std::clamp(fx - float(u0), 0.0f, 1.0f), ay = std::clamp(fy - float(v0), 0.0f, 1.0f);
          glm::vec3 sum(0.0f);
          float wsum = 0;
          for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 2; ++k) {
              int u = std::min(u0 + k, lw - 1), v = std::min(v0 + j, lh - 1);
              size_t q = size_t(std::min(v * f, H - 1)) * W + std::min(u * f, W - 1);
              float w = (k ? ax : 1.0f - ax) * (j ? ay : 1.0f - ay) + 1e-4f;
              bool ok = inst[q] != GI_INVALID_ID && std::abs(depth[q] - depth[p]) <= t.tauZ * depth[p] &&
                        glm::dot(glm::vec3(gn[q]), glm::vec3(gn[p])) >= cosN;
              (ok ? accepted : rejected)++;
              if (ok) {
                sum += w * glm::vec3(E[size_t(v) * lw + u]);
                wsum += w;
              }
            }
          int un = std::clamp(int(std::floor(fx + 0.5f)), 0, lw - 1), vn = std::clamp(int(std::floor(fy + 0.5f)), 0, lh - 1);
          glm::vec3 e = wsum > 0 ? sum / wsum : glm::vec3(E[size_t(vn) * lw + un]);
          expected = glm::vec3(alb[p]) * glm::max(e, glm::vec3(0.0f)) * 0.31830988618379067154f;
        }
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(L[p][c], expected[c], 1e-5f) << "factor " << f << " pixel " << x << "," << y;
      }
    EXPECT_GT(rejected, W * H / 50) << "factor " << f << ": the test must exercise rejected taps";
    EXPECT_GT(accepted, W * H) << "factor " << f;
  }
  ctx.profiler().discard();
}

// The fused gather (vpl_gather_camera, used by `vpl` and `igi`) computes exactly what
// de-interleave + vpl_gather + re-interleave compute, for radiance and irradiance, for square and
// non-square patterns on an odd image (the sub-images' padding lanes must stay unwritten).
TEST(Igi, FusedGatherEqualsDeinterleaveShadeReinterleave) {
  cl::Context& ctx = test::context();
  Scene s = emptyCornellWithSpot();
  const int W = 37, H = 23;
  Renderer r(ctx, s, test::smallRenderSettings("vpl", W, H, {"vpl.count=4"}));
  r.renderFrame();
  VplGenerator gen(ctx);
  VplSet v;
  gen.generate(r.rsms(), 70, 0.0f, v);
  InterleavedGather ig(ctx, "test");
  const glm::vec4 sentinel(-7.0f);
  std::vector<glm::vec4> init(size_t(W) * H, sentinel);
  for (auto [n, m] : {std::pair{1, 1}, std::pair{3, 2}, std::pair{4, 4}, std::pair{8, 5}})
    for (bool radiance : {false, true}) {
      ig.resize(W, H, n, m);
      cl::Buffer copies(ctx, size_t(W) * H * 16), fused = ctx.upload(init, "fused out");
      ig.deinterleave(r.gbuffer());
      ig.shade(v);
      if (radiance) ig.reinterleaveRadiance(r.gbuffer(), copies);
      else ig.reinterleaveIrradiance(copies);
      ig.shadeCameraOrder(r.gbuffer(), v, nullptr, radiance, fused);
      auto a = download<glm::vec4>(ctx, copies), b = download<glm::vec4>(ctx, fused);
      int lit = 0;
      for (size_t p = 0; p < a.size(); ++p) {
        ASSERT_EQ(a[p], b[p]) << n << "x" << m << (radiance ? " radiance" : " irradiance") << " pixel " << p;
        lit += a[p].y > 0;
      }
      EXPECT_GT(lit, W * H / 3);
    }
  ctx.profiler().discard();
}
