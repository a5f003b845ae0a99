// Light propagation volume kernels against the host implementation of the same formulas
// (tests/lpv_host_reference.h) on 8³ grids with 2 cascades; energy bookkeeping of propagation
// against the analytic face solid angles; blocking by a wall in the geometry volume; determinism.
// ALGORITHMS.md §4, §7; docs/techniques/lpv.md.
// The injection, surfel and lookup kernels work on GI_VW (1, 8 or 16) texels or pixels of a row at
// a time and on runs of 16 (LpvVolume::kRunLength): their tests use row lengths that are multiples
// of neither (19 merged RSM texels, 19 RSM and 27 camera pixels), so that the lanes past a row's
// end, which re-read its last texel and must be dropped, are exercised at every width (run them
// under Oclgrind to check that no lane reads or writes outside the buffers: README, "Development notes").
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <random>

#include "gi/lpv/lpv_volume.h"
#include "lpv_host_reference.h"
#include "render/renderer.h"
#include "render/views.h"
#include "scene/cornell_box.h"
#include "test_support.h"

using namespace gi;

namespace {

constexpr int kN = 8;
const std::vector<LpvCascade> kTwoCascades = {{glm::vec3(0.0f), 1.0f / kN}, {glm::vec3(-0.5f), 2.0f / kN}};

// Largest |a - b| over all components, relative to the largest |b|.
double relativeMaxError(const std::vector<glm::vec4>& a, const std::vector<glm::vec4>& b) {
  double err = 0.0, scale = 1e-30;
  for (size_t i = 0; i < b.size(); ++i)
    for (int c = 0; c < 4; ++c) {
      err = std::max(err, double(std::fabs(a[i][c] - b[i][c])));
      scale = std::max(scale, double(std::fabs(b[i][c])));
    }
  return err / scale;
}

glm::vec3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<float> g;
  return glm::normalize(glm::vec3(g(rng), g(rng), g(rng)) + glm::vec3(1e-6f));
}

struct Planes {
  std::vector<glm::vec4> position, normal, flux;
};

// res×res texels at random places inside [0.02, 0.98]³ (cascade 0); every 5th texel empty.
Planes randomPlanes(int res, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.02f, 0.98f), f(0.0f, 1.0f);
  Planes p;
  for (int i = 0; i < res * res; ++i) {
    bool valid = i % 5 != 3;
    p.position.emplace_back(u(rng), u(rng), u(rng), valid ? 1.0f : 0.0f);
    p.normal.emplace_back(randomUnit(rng), 0.0f);
    p.flux.push_back(valid ? glm::vec4(f(rng), f(rng), f(rng), 0.0f) : glm::vec4(0.0f));
  }
  return p;
}

GiView testCameraView(int w, int h) {
  Camera c;
  c.position = glm::vec3(0.5f, 0.5f, -1.5f);
  c.target = glm::vec3(0.5f, 0.5f, 0.5f);
  c.znear = 0.1f;
  c.zfar = 10.0f;
  return makeCameraView(c, w, h);
}

void uploadGBuffer(cl::Context& ctx, GBuffer& g, const Planes& p, const std::vector<glm::vec4>& albedo) {
  ctx.write(g.position, p.position.data(), p.position.size() * 16);
  ctx.write(g.geoNormal, p.normal.data(), p.normal.size() * 16);
  ctx.write(g.normal, p.normal.data(), p.normal.size() * 16);  // the lookup test overwrites it
  ctx.write(g.albedo, albedo.data(), albedo.size() * 16);
}

// Host mirror of a surfel's area (lpv.cl surfel_area).
float surfelArea(const GiView& v, glm::vec3 p, glm::vec3 n) {
  glm::vec3 axis(-v.view[2], -v.view[6], -v.view[10]);
  float a = v.texel_world_size * v.texel_world_size;
  glm::vec3 dir = axis;
  if (!v.orthographic) {
    glm::vec3 d = p - glm::vec3(v.eye[0], v.eye[1], v.eye[2]);
    float dist = glm::length(d), z = glm::dot(d, axis);
    dir = d / dist;
    a *= z * z * (z / dist);
  }
  return a / std::max(std::fabs(glm::dot(n, dir)), 0.1f);
}

// The SH convention (kernels/common/sh.h): the lobe constants are the projection of max(0, n·ω)
// (numerical quadrature), and evaluating the projection gives 0.25 + 0.5·cos θ, whose largest
// error against max(0, cos θ) is the known l <= 1 approximation error of 0.25 (at θ = 0 and π).
TEST(LpvSh, ClampedCosineProjectionAndEvaluation) {
  const glm::vec3 n = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
  glm::dvec4 projected(0.0);
  const int steps = 400;
  for (int i = 0; i < steps; ++i)
    for (int j = 0; j < 2 * steps; ++j) {
      double theta = (i + 0.5) * M_PI / steps, phi = (j + 0.5) * M_PI / steps;
      glm::vec3 w(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      double dOmega = std::sin(theta) * (M_PI / steps) * (M_PI / steps);
      projected += glm::dvec4(lpvref::basis(w)) * (std::max(0.0, double(glm::dot(n, w))) * dOmega);
    }
  glm::vec4 lobe = lpvref::lobe(n);
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(projected[c], lobe[c], 2e-4) << c;
  double maxError = 0.0;
  for (int i = 0; i <= 180; ++i) {
    double theta = i * M_PI / 180.0;
    glm::vec3 w = std::cos(float(theta)) * n + std::sin(float(theta)) * glm::normalize(glm::cross(n, glm::vec3(0, 0, 1)));
    double value = glm::dot(lobe, lpvref::basis(w));
    EXPECT_NEAR(value, 0.25 + 0.5 * std::cos(theta), 1e-5);
    maxError = std::max(maxError, std::fabs(value - std::max(0.0, std::cos(theta))));
  }
  EXPECT_NEAR(maxError, 0.25, 1e-5);
}

TEST(LpvKernels, InjectionMatchesHost) {
  cl::Context& ctx = test::context();
  const int res = 38, block = 2;  // 19 merged texels per row: a full run of 16 and a partial one
  const float bias = 0.5f, scale = float(std::ldexp(1.0, 40));
  Planes p = randomPlanes(res, 7);
  LpvVolume v(ctx, kN, 2);
  v.begin(kTwoCascades, scale);
  cl::Buffer pos = ctx.upload(p.position, "pos"), nrm = ctx.upload(p.normal, "nrm"), flux = ctx.upload(p.flux, "flux");
  v.inject(pos, nrm, flux, res, block, bias);
  v.resolve(false);
  std::vector<glm::vec4> got = v.readCurrent();

  lpvref::Grid want(kN, 2);
  std::vector<glm::dvec4> sums(want.c.size(), glm::dvec4(0.0));
  int injected = 0;
  for (int y = 0; y < res / block; ++y)
    for (int x = 0; x < res / block; ++x) {
      glm::vec3 f(0.0f), q(0.0f), n(0.0f);
      float w = 0.0f;
      for (int by = 0; by < block; ++by)
        for (int bx = 0; bx < block; ++bx) {
          size_t t = size_t(y * block + by) * res + x * block + bx;
          float wt = p.flux[t].x + p.flux[t].y + p.flux[t].z;
          if (!(wt > 0.0f)) continue;
          f += glm::vec3(p.flux[t]);
          q += wt * glm::vec3(p.position[t]);
          n += wt * glm::vec3(p.normal[t]);
          w += wt;
        }
      if (!(w > 0.0f)) continue;
      q /= w;
      n = glm::normalize(n);
      for (int k = 0; k < 2; ++k) {
        glm::vec3 u = (q + bias * kTwoCascades[k].cell * n - kTwoCascades[k].origin) / kTwoCascades[k].cell;
        glm::ivec3 c(glm::floor(u));
        if (!want.inside(c)) continue;
        ++injected;
        for (int ch = 0; ch < 3; ++ch) sums[want.index(k, ch, c)] += glm::dvec4(lpvref::lobe(n) * (f[ch] / lpvref::kPi));
      }
    }
  for (size_t i = 0; i < sums.size(); ++i) want.c[i] = glm::vec4(sums[i]);
  EXPECT_GT(injected, 80);
  double err = relativeMaxError(got, want.c);
  std::printf("injection: %d VPL-cascade pairs, max error %.2e of the largest coefficient\n", injected, err);
  EXPECT_LT(err, 1e-5);
}

TEST(LpvKernels, GeometryVolumeMatchesHost) {
  cl::Context& ctx = test::context();
  const int w = 27, h = 16, rsmRes = 19;  // rows of neither a multiple of the lane count nor of the run
  Planes camera;
  Planes all = randomPlanes(32, 11);  // 1024 surfels: the first w·h are the camera's, the next rsmRes² the RSM's
  for (int i = 0; i < w * h; ++i) {
    camera.position.push_back(all.position[i]);
    camera.normal.push_back(all.normal[i]);
  }
  Planes rsm;
  for (int i = 0; i < rsmRes * rsmRes; ++i) {
    rsm.position.push_back(all.position[w * h + i]);
    rsm.normal.push_back(all.normal[w * h + i]);
  }
  GiView cameraView = testCameraView(w, h), rsmView = testCameraView(rsmRes, rsmRes);
  GBuffer g;
  g.allocate(ctx, w, h);
  g.view = cameraView;
  uploadGBuffer(ctx, g, camera, std::vector<glm::vec4>(size_t(w) * h, glm::vec4(1.0f)));
  LpvVolume v(ctx, kN, 2);
  v.begin(kTwoCascades, 1.0f);
  cl::Buffer pos = ctx.upload(rsm.position, "pos"), nrm = ctx.upload(rsm.normal, "nrm");
  v.addGeometryRsm(rsmView, pos, nrm, rsmRes);
  v.addGeometryCamera(g);
  v.resolve(true);
  std::vector<glm::vec4> got = v.readGeometry();

  size_t nodes = v.nodesPerGrid();
  std::vector<glm::dvec4> sums(2 * 2 * nodes, glm::dvec4(0.0));  // [cascade][source][node]
  auto add = [&](const Planes& s, const GiView& view, int source) {
    for (size_t i = 0; i < s.position.size(); ++i) {
      if (!(s.position[i].w > 0.0f)) continue;
      glm::vec3 q(s.position[i]), n(s.normal[i]);
      float area = surfelArea(view, q, n);
      for (int k = 0; k < 2; ++k) {
        float cell = kTwoCascades[k].cell;
        glm::vec3 u = (q - kTwoCascades[k].origin) / cell;
        glm::ivec3 c(std::nearbyint(u.x), std::nearbyint(u.y), std::nearbyint(u.z));
        if (glm::any(glm::lessThan(c, glm::ivec3(0))) || glm::any(glm::greaterThan(c, glm::ivec3(kN)))) continue;
        size_t node = lpvref::nodeIndex(kN, 0, c);
        sums[(size_t(k) * 2 + source) * nodes + node] += glm::dvec4(lpvref::lobe(n) * (area / (cell * cell)));
      }
    }
  };
  add(rsm, rsmView, 0);
  add(camera, cameraView, 1);
  std::vector<glm::vec4> want(2 * nodes);
  int fromBoth = 0;
  for (int k = 0; k < 2; ++k)
    for (size_t node = 0; node < nodes; ++node) {
      glm::dvec4 a = sums[(size_t(k) * 2) * nodes + node], b = sums[(size_t(k) * 2 + 1) * nodes + node];
      fromBoth += a.x > 0 && b.x > 0;
      want[k * nodes + node] = glm::vec4(a.x >= b.x ? a : b);
    }
  EXPECT_GT(fromBoth, 10);  // the max-of-sources rule is exercised
  double err = relativeMaxError(got, want);
  std::printf("geometry volume: max error %.2e of the largest coefficient\n", err);
  EXPECT_LT(err, 1e-5);
}

// A random n³ grid (SH coefficients of either sign) with 2 cascades for the propagation and lookup tests.
lpvref::Grid randomGrid(uint32_t seed, int n = kN) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), pos(0.0f, 1.0f);
  lpvref::Grid g(n, 2);
  for (glm::vec4& c : g.c) c = glm::vec4(pos(rng), 0.5f * u(rng), 0.5f * u(rng), 0.5f * u(rng));
  return g;
}

// 3 steps with blocking on an n³ grid of 2 cascades against the host mirror. n = 8: 8 cells of a
// row per work-item; n = 16: 16 where the device's native width is 16 (AVX-512: the propagation
// then loads the face factors through lpv.cl's lpv_load_factor conversion). With `bounces` the
// blocked light is reflected after each blocked step (LpvBounces below).
void propagationMatchesHost(int n, bool bounces = false) {
  cl::Context& ctx = test::context();
  lpvref::Grid g = randomGrid(3, n);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 0.4f), unit(0.0f, 1.0f);
  size_t nodes = 2 * size_t(n + 1) * (n + 1) * (n + 1);
  std::vector<glm::vec4> geometry(nodes), albedo(nodes);
  for (glm::vec4& c : geometry) c = lpvref::lobe(randomUnit(rng)) * u(rng);
  for (size_t i = 0; i < nodes; ++i) {
    float w = i % 5 == 2 ? 0.0f : unit(rng);  // Σ w per node (A/s²)
    albedo[i] = glm::vec4(unit(rng) * w, unit(rng) * w, unit(rng) * w, w);
  }
  LpvVolume v(ctx, n, 2, LpvLookupStorage::Buffer, bounces);
  v.begin({{glm::vec3(0.0f), 1.0f / n}, {glm::vec3(-0.5f), 2.0f / n}}, 1.0f);
  v.resolve(false);
  v.setGeometry(geometry);
  if (bounces) v.setSurfelAlbedo(albedo);
  v.setInjected(g.c);
  const int steps = 3;
  v.propagate(steps, true);
  lpvref::Grid cur = g, acc = g;
  for (int i = 0; i < steps; ++i) {
    lpvref::Grid next = lpvref::propagate(cur, geometry, i > 0);
    if (bounces && i > 0) {
      lpvref::Grid reflected = lpvref::reflectBlocked(cur, geometry, albedo);
      for (size_t j = 0; j < next.c.size(); ++j) next.c[j] += reflected.c[j];
    }
    cur = next;
    for (size_t j = 0; j < acc.c.size(); ++j) acc.c[j] += cur.c[j];
  }
  double errStep = relativeMaxError(v.readCurrent(), cur.c);
  double errAcc = relativeMaxError(v.readAccumulated(), acc.c);
  std::printf("propagation, %d^3, 3 steps with blocking%s: max error %.2e (last step), %.2e (accumulated)\n", n,
              bounces ? " and reflection" : "", errStep, errAcc);
  // Both sides round each face factor T_f to half precision (lpv_face_factors, lpvref::propagate),
  // from float values that differ in their last bits (fused multiply-adds on the device): where
  // the two lie on either side of a half rounding boundary (about 2e-4 of the factors: a float
  // difference of ~1e-7 against a half step of 2^-11) they differ by one half step, 2^-11·T_f,
  // which moves that face's flux by 2^-11 of itself — at most 2^-11 · T_f,max (0.135) · LOBE0
  // (0.886) · max I / max c (< 1 here) ≈ 6e-5 of the largest coefficient per flipped factor, and
  // a cell can hold a few. Without factor rounding the two agree to 4e-7 (1e-5 was the bound).
  EXPECT_LT(errStep, 2e-4);
  EXPECT_LT(errAcc, 2e-4);
}

TEST(LpvKernels, PropagationMatchesHost) { propagationMatchesHost(kN); }
TEST(LpvKernels, PropagationMatchesHost16) { propagationMatchesHost(16); }

// The lookup from a buffer (the kernel interpolates) or from a 3D image (the sampler does; PoCL
// in software with float weights, so the same bound holds; GPU samplers use 8-bit fractional
// weights, up to 1/512 of the cell-to-cell difference: 4e-3 there). With `steps` > 0 the grid is
// propagated first, so that the last step writes the lookup grid (lpv.cl LPV_WRITE_LOOKUP) instead
// of lpv_lookup_grid; the host then starts from the device's accumulated grid.
// With `damping` (lpv.damping) the irradiance is also looked up one cell further along the
// geometric normal and E limited to it (lpv.cl lpv_lookup).
void lookupMatchesHost(LpvLookupStorage storage, int steps = 0, bool damping = false) {
  cl::Context& ctx = test::context();
  if (storage == LpvLookupStorage::Image) ASSERT_TRUE(ctx.device().imageSupport) << "the test device has no images";
  const int w = 27, h = 16;  // rows end inside a work-item's lanes: their last lanes must not be stored
  lpvref::Grid g = randomGrid(9);
  Planes p = randomPlanes(32, 13);
  p.position.resize(size_t(w) * h);
  p.normal.resize(size_t(w) * h);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> a(0.1f, 0.9f), spread(-0.6f, 1.6f);
  std::vector<glm::vec4> albedo, shading;
  for (int i = 0; i < w * h; ++i) {
    albedo.emplace_back(a(rng), a(rng), a(rng), 0.0f);
    shading.emplace_back(randomUnit(rng), 0.0f);
    // Spread the points over both cascades and their blend zones.
    if (i % 2) p.position[i] = glm::vec4(spread(rng), spread(rng), spread(rng), p.position[i].w);
  }
  GBuffer gb;
  gb.allocate(ctx, w, h);
  uploadGBuffer(ctx, gb, p, albedo);
  ctx.write(gb.normal, shading.data(), shading.size() * 16);
  LpvVolume v(ctx, kN, 2, storage);
  v.begin(kTwoCascades, 1.0f);
  v.setInjected(g.c);
  if (steps > 0) {
    v.propagate(steps, false);
    g.c = v.readAccumulated();
  }
  cl::Buffer out(ctx, size_t(w) * h * 16, CL_MEM_READ_WRITE, "out");

  auto irradianceAt = [&](int k, glm::vec3 q, glm::vec3 ng, glm::vec3 n, float offset) {
    float s = kTwoCascades[k].cell;
    glm::vec3 u = glm::clamp((q + offset * s * ng - kTwoCascades[k].origin) / s - 0.5f, 0.0f, float(kN - 1));
    glm::ivec3 c0 = glm::min(glm::ivec3(glm::floor(u)), glm::ivec3(kN - 2));
    glm::vec3 f = u - glm::vec3(c0);
    glm::vec3 e(0.0f);
    glm::vec4 conv(lpvref::kPi * GI_SH_Y0, 2.0f * lpvref::kPi / 3.0f * GI_SH_Y1 * -n.y,
                   2.0f * lpvref::kPi / 3.0f * GI_SH_Y1 * -n.z, 2.0f * lpvref::kPi / 3.0f * GI_SH_Y1 * -n.x);
    for (int corner = 0; corner < 8; ++corner) {
      glm::ivec3 o(corner & 1, (corner >> 1) & 1, corner >> 2);
      float wt = (o.x ? f.x : 1 - f.x) * (o.y ? f.y : 1 - f.y) * (o.z ? f.z : 1 - f.z);
      for (int ch = 0; ch < 3; ++ch) e[ch] += wt * glm::dot(g.c[g.index(k, ch, c0 + o)], conv) / (s * s);
    }
    return e;
  };
  auto blend = [&](int k, glm::vec3 q) {
    float extent = kTwoCascades[k].cell * kN, wd = 0.1f * extent;
    glm::vec3 centre = kTwoCascades[k].origin + 0.5f * extent;
    glm::vec3 t = glm::clamp((glm::abs(q - centre) - (0.5f * extent - wd)) / wd, 0.0f, 1.0f);
    return std::max(t.x, std::max(t.y, t.z));
  };
  int damped = 0;
  auto irradiance = [&](int k, glm::vec3 q, glm::vec3 ng, glm::vec3 n) { return irradianceAt(k, q, ng, n, 0.5f); };
  auto outer = [&](int k, glm::vec3 q, glm::vec3 ng, glm::vec3 n) { return irradianceAt(k, q, ng, n, 1.5f); };
  for (bool blendCascades : {false, true}) {
    v.lookup(gb, blendCascades, out, damping);
    std::vector<glm::vec4> got = ctx.download<glm::vec4>(out), want(size_t(w) * h, glm::vec4(0.0f));
    int blended = 0;
    for (int i = 0; i < w * h; ++i) {
      if (!(p.position[i].w > 0.0f)) continue;
      glm::vec3 q(p.position[i]), ng(p.normal[i]), n(shading[i]);
      glm::vec3 e, eOuter;
      if (!blendCascades) {
        e = irradiance(0, q, ng, n);
        eOuter = outer(0, q, ng, n);
      } else {
        float t = blend(0, q);
        int k = t >= 1.0f ? 1 : 0;
        if (k == 1) t = blend(1, q);
        e = irradiance(k, q, ng, n);
        eOuter = outer(k, q, ng, n);
        if (k == 0 && t > 0.0f) {
          e = glm::mix(e, irradiance(1, q, ng, n), t);
          eOuter = glm::mix(eOuter, outer(1, q, ng, n), t);
          ++blended;
        }
      }
      if (damping) {
        glm::vec3 limited = glm::min(e, glm::max(eOuter, 0.0f));
        if (limited != e && glm::any(glm::greaterThan(e, glm::vec3(0.0f)))) ++damped;
        e = limited;
      }
      want[i] = glm::vec4(glm::max(glm::vec3(albedo[i]) / lpvref::kPi * e, 0.0f), 0.0f);
    }
    if (blendCascades) EXPECT_GT(blended, 5);
    double err = relativeMaxError(got, want);
    std::printf("lookup from a %s (blend %d%s): max error %.2e\n",
                storage == LpvLookupStorage::Image ? "3D image" : "buffer", int(blendCascades),
                damping ? ", damping" : "", err);
    EXPECT_LT(err, storage == LpvLookupStorage::Image && ctx.device().isGpu ? 4e-3 : 1e-5);
  }
  if (damping) EXPECT_GT(damped, 20);  // the damping is exercised
}

TEST(LpvKernels, LookupMatchesHost) { lookupMatchesHost(LpvLookupStorage::Buffer); }
TEST(LpvKernels, LookupFrom3dImageMatchesHost) { lookupMatchesHost(LpvLookupStorage::Image); }
TEST(LpvKernels, LookupAfterPropagationMatchesHost) { lookupMatchesHost(LpvLookupStorage::Buffer, 3); }
TEST(LpvKernels, LookupWithDampingMatchesHost) { lookupMatchesHost(LpvLookupStorage::Buffer, 3, true); }

// One cell at the centre of an empty 16³ grid, propagated without blocking. Step 1 keeps
// Σ_faces ΔΩ_f · max(0, I(ω_f)) of the injected flux Φ (the face solid angles and directions of
// ALGORITHMS.md §4), computed here from the SH function alone; later steps are compared with the
// host propagation and printed (docs/techniques/lpv.md quotes them).
TEST(LpvEnergy, FluxKeptPerStepMatchesFaceSolidAngles) {
  cl::Context& ctx = test::context();
  const int n = 16;
  struct Source {
    const char* name;
    glm::vec4 coefficients;  // of I(ω) for flux Φ = 1
  };
  const Source sources[] = {{"isotropic", glm::vec4(1.0f / (4.0f * lpvref::kPi * GI_SH_Y0), 0, 0, 0)},
                            {"cosine lobe +x", lpvref::lobe({1, 0, 0}) / lpvref::kPi},
                            {"cosine lobe (1,2,3)", lpvref::lobe(glm::normalize(glm::vec3(1, 2, 3))) / lpvref::kPi}};
  for (const Source& s : sources) {
    lpvref::Grid g(n, 1);
    for (int ch = 0; ch < 3; ++ch) g.c[g.index(0, ch, glm::ivec3(n / 2))] = s.coefficients;
    double injected = lpvref::totalFlux(g, 0, 0);
    EXPECT_NEAR(injected, 1.0, 1e-6) << s.name;
    double analytic = 0.0;
    for (glm::vec3 d : lpvref::axes())
      for (const lpvref::Face& f : lpvref::facesFor(d))
        analytic += f.solidAngle * std::max(0.0f, glm::dot(s.coefficients, lpvref::basis(f.eval)));
    LpvVolume v(ctx, n, 1);
    v.begin({LpvCascade{glm::vec3(0.0f), 1.0f}}, 1.0f);
    v.setInjected(g.c);
    lpvref::Grid host = g;
    std::printf("%-20s flux kept per step (step 1 analytic %.6f):", s.name, analytic);
    double previous = injected;
    for (int step = 1; step <= 7; ++step) {  // the light reaches the border at step 8
      v.propagate(1, false);
      lpvref::Grid dev(n, 1);
      dev.c = v.readCurrent();
      host = lpvref::propagate(host, {}, false);
      double flux = lpvref::totalFlux(dev, 0, 0);
      if (step == 1) EXPECT_NEAR(flux, analytic, 1e-5) << s.name;
      EXPECT_NEAR(flux, lpvref::totalFlux(host, 0, 0), 1e-5 * flux) << s.name << " step " << step;
      std::printf(" %.4f", flux / previous);
      previous = flux;
    }
    std::printf("\n");
  }
  // Isotropic: the 6 × 5 faces tile the sphere (6 · (0.4007 + 4 · 0.4234) = 4π to 2e-5).
  EXPECT_NEAR(6.0 * (lpvref::kMainFace + 4.0 * lpvref::kSideFace) / (4.0 * M_PI), 1.0, 2e-5);
}

// A wall of occluders (blocking potential of a surface facing the light, A = s² per node) on the
// plane between two cells: the flux reaching the far side drops by the factor the face weights
// and the blocking formula give.
TEST(LpvBlocking, WallCutsTransportedFluxByExpectedFactor) {
  cl::Context& ctx = test::context();
  const int n = 8;
  lpvref::Grid g(n, 1);
  // Source: a cosine lobe along +x in cell x = 2 (every y, z, so the wall is lit evenly).
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int ch = 0; ch < 3; ++ch) g.c[g.index(0, ch, {2, y, z})] = lpvref::lobe({1, 0, 0}) / lpvref::kPi;
  size_t m = n + 1;
  std::vector<glm::vec4> empty(m * m * m, glm::vec4(0.0f)), wall = empty;
  for (int z = 0; z <= n; ++z)
    for (int y = 0; y <= n; ++y) wall[lpvref::nodeIndex(n, 0, {4, y, z})] = lpvref::lobe({-1, 0, 0});  // plane x = 4
  auto fluxBeyondWall = [&](const std::vector<glm::vec4>& geometry) {
    LpvVolume v(ctx, n, 1);
    v.begin({LpvCascade{glm::vec3(0.0f), 1.0f}}, 1.0f);
    v.resolve(false);
    v.setGeometry(geometry);
    v.setInjected(g.c);
    v.propagate(2, true);  // step 1 fills x = 3 (no blocking), step 2 crosses the plane x = 4
    std::vector<glm::vec4> c = v.readCurrent();
    double s = 0.0;
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y) s += c[g.index(0, 0, {4, y, z})].x;
    return s;
  };
  double open = fluxBeyondWall(empty), blocked = fluxBeyondWall(wall);
  // Expected: the host propagation with the same wall.
  lpvref::Grid h1 = lpvref::propagate(g, wall, false), h2 = lpvref::propagate(h1, wall, true);
  lpvref::Grid o2 = lpvref::propagate(h1, empty, true);
  double expectBlocked = 0.0, expectOpen = 0.0;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y) {
      expectBlocked += h2.c[h2.index(0, 0, {4, y, z})].x;
      expectOpen += o2.c[o2.index(0, 0, {4, y, z})].x;
    }
  // Analytic bounds: the main face is blocked by 1 - (0.25 + 0.5) = 0.25 transmission, the side
  // faces (|n·ω| = 2/√5) by 1 - (0.25 + 0.5·0.894) = 0.303.
  double ratio = blocked / open;
  std::printf("wall between source and receiver: transmitted %.4f of the open flux (host %.4f)\n", ratio,
              expectBlocked / expectOpen);
  EXPECT_NEAR(ratio, expectBlocked / expectOpen, 1e-5);
  EXPECT_GT(ratio, 0.25 - 1e-4);
  EXPECT_LT(ratio, 0.303 + 1e-3);
  EXPECT_NEAR(open, expectOpen, 1e-5 * expectOpen);
}

// Units and reach: a 32 × 32 layer of upward cosine-lobe VPLs (flux 1 each, 1 m cells) filling
// the bottom of an empty 32³ grid, propagated 32 times without blocking; irradiance at
// downward-facing receivers on the centre column, h cells above, against the exact irradiance of
// those VPLs (Σ Φ cos θ cos θ' / (π r²)). Close to the source the two agree within the l <= 1
// error (a missing π or s² would show here); farther up the LPV falls far below the exact value:
// the propagation re-emits every face's flux as a cosine lobe along that face's normal, so light
// turns by 90° at most steps and spreads like a random walk instead of travelling straight
// (docs/techniques/lpv.md, "Accuracy"). Asserted: the units (h = 2 within 10 %); printed: the rest.
TEST(LpvReach, UniformPlaneIrradianceAgainstExact) {
  cl::Context& ctx = test::context();
  const int n = 32;
  LpvVolume v(ctx, n, 1);
  v.begin({LpvCascade{glm::vec3(0.0f), 1.0f}}, 1.0f);
  lpvref::Grid g(n, 1);
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x)
      for (int ch = 0; ch < 3; ++ch) g.c[g.index(0, ch, {x, 0, z})] = lpvref::lobe({0, 1, 0}) / lpvref::kPi;
  v.setInjected(g.c);
  v.propagate(n, false);
  std::vector<glm::vec4> acc = v.readAccumulated();
  std::printf("uniform plane, %d^3, %d iterations: E_lpv / E_exact at h cells above:", n, n);
  for (int h : {1, 2, 3, 4, 6, 8, 12, 16}) {
    glm::vec4 c = acc[g.index(0, 0, {n / 2, h, n / 2})];
    double lpv = GI_SH_COSCONV0 * GI_SH_Y0 * c.x + GI_SH_COSCONV1 * GI_SH_Y1 * c.y;  // receiver facing down
    double exact = 0.0;
    for (int z = 0; z < n; ++z)
      for (int x = 0; x < n; ++x) {
        double dx = x - n / 2, dz = z - n / 2, r2 = dx * dx + h * h + dz * dz;
        exact += (h * h / r2) / (lpvref::kPi * r2);
      }
    std::printf(" %d: %.3g", h, lpv / exact);
    if (h == 2) EXPECT_NEAR(lpv / exact, 1.0, 0.1);
  }
  // The plane lighting itself: irradiance at an upward-facing point of the plane (its lookup reads
  // the VPL layer), relative to the plane's exitance (flux 1 per 1 m² cell); exact: 0.
  glm::vec4 own = acc[g.index(0, 0, {n / 2, 0, n / 2})];
  std::printf("; self-irradiance of the plane / its exitance: %.3f\n",
              GI_SH_COSCONV0 * GI_SH_Y0 * own.x - GI_SH_COSCONV1 * GI_SH_Y1 * own.y);
}

// Multiple bounces (lpv.bounces, lpv.cl lpv_face_albedo and lpv_reflect_blocked): the 3 steps of
// PropagationMatchesHost with reflection after each blocked step (lpvref::reflectBlocked), random
// surfel albedo sums, a fifth of the nodes without camera surfels (albedo 0 there).
TEST(LpvBounces, ReflectionMatchesHost) { propagationMatchesHost(kN, true); }

// Energy: a wall of albedo ρ (per channel) reflects ρ times the flux it blocks. One blocked step
// from a cosine lobe aimed at a wall of occluders (the plane x = 6, facing −x): the flux after the
// step with reflection minus without it equals ρ times the flux the wall took (open step minus
// blocked step; the open step keeps all flux inside the grid, LpvEnergy). The reflected light
// travels back, away from the wall (its x coefficient is negative).
TEST(LpvBounces, BlockerReflectsAlbedoTimesBlockedFlux) {
  cl::Context& ctx = test::context();
  const int n = 8;
  const glm::vec3 rho(0.8f, 0.5f, 0.2f);
  lpvref::Grid g(n, 1);
  for (int ch = 0; ch < 3; ++ch) g.c[g.index(0, ch, {4, 4, 4})] = lpvref::lobe({1, 0, 0}) / lpvref::kPi;  // Φ = 1
  size_t m = n + 1;
  std::vector<glm::vec4> wall(m * m * m, glm::vec4(0.0f)), albedo(m * m * m, glm::vec4(rho, 1.0f));
  for (int z = 0; z <= n; ++z)
    for (int y = 0; y <= n; ++y) wall[lpvref::nodeIndex(n, 0, {6, y, z})] = lpvref::lobe({-1, 0, 0});
  auto afterTwoSteps = [&](bool blocking, bool bounces) {
    LpvVolume v(ctx, n, 1, LpvLookupStorage::Buffer, bounces);
    v.begin({LpvCascade{glm::vec3(0.0f), 1.0f}}, 1.0f);
    v.resolve(false);
    v.setGeometry(wall);
    if (bounces) v.setSurfelAlbedo(albedo);
    v.setInjected(g.c);
    v.propagate(2, blocking);  // step 1 (never blocked) reaches x = 5, step 2 crosses the plane x = 6
    lpvref::Grid out(n, 1);
    out.c = v.readCurrent();
    return out;
  };
  lpvref::Grid open = afterTwoSteps(false, false), blocked = afterTwoSteps(true, false),
               reflected = afterTwoSteps(true, true);
  for (int ch = 0; ch < 3; ++ch) {
    double took = lpvref::totalFlux(open, 0, ch) - lpvref::totalFlux(blocked, 0, ch);
    double gave = lpvref::totalFlux(reflected, 0, ch) - lpvref::totalFlux(blocked, 0, ch);
    std::printf("channel %d: the wall took %.5f of flux 1, reflected %.5f = %.4f of it (albedo %.2f)\n", ch, took, gave,
                gave / took, rho[ch]);
    EXPECT_GT(took, 0.05);
    // Both steps round T_f to half precision; the open step does not: ΔΩ_f/π − T_f of the unblocked
    // faces is then up to 2^-12 of ΔΩ_f/π of either sign, which the reflection clamps at 0.
    EXPECT_NEAR(gave, rho[ch] * took, 2e-3 * took);
    double x = 0.0;
    for (size_t i = 0; i < reflected.cells(); ++i) x += reflected.c[reflected.index(0, ch, glm::ivec3(0)) + i].w -
                                                      blocked.c[blocked.index(0, ch, glm::ivec3(0)) + i].w;
    EXPECT_LT(x, 0.0);
  }
}

TEST(LpvDeterminism, SameBitsTwice) {
  CornellOptions o;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  Scene s = makeCornellBox(o);
  for (const char* cascades : {"lpv.cascades=0", "lpv.cascades=3", "lpv.bounces=true"}) {
    RenderSettings rs;
    rs.width = 64;
    rs.height = 64;
    rs.technique = "lpv";
    rs.sets = {cascades, "lpv.resolution=16", "rsm.resolution=128", "lpv.rsm_size=64", "shadow.resolution=256",
               "shadow.cube_resolution=128"};
    Renderer a(test::context(), s, rs), b(test::context(), s, rs);
    a.renderFrame();
    b.renderFrame();
    Image ia = a.indirectRadiance(), ib = b.indirectRadiance();
    a.renderFrame();
    Image ia2 = a.indirectRadiance();
    ASSERT_EQ(ia.pixels.size(), ib.pixels.size());
    EXPECT_EQ(0, std::memcmp(ia.pixels.data(), ib.pixels.data(), ia.pixels.size() * sizeof(float))) << cascades;
    EXPECT_EQ(0, std::memcmp(ia.pixels.data(), ia2.pixels.data(), ia.pixels.size() * sizeof(float))) << cascades;
    double sum = 0;
    for (float v : ia.pixels) sum += v;
    EXPECT_GT(sum, 0.0) << cascades;
  }
}

TEST(LpvParams, AbsurdValuesAreRejectedByName) {
  Scene s = makeCornellBox();
  RenderSettings rs;
  rs.width = 16;
  rs.height = 16;
  rs.technique = "lpv";
  for (const char* bad : {"lpv.resolution=7", "lpv.cascades=9", "lpv.rsm_size=300", "lpv.injection_bias=-1",
                          "lpv.lookup_storage=texture"}) {
    rs.sets = {bad};
    try {
      Renderer r(test::context(), s, rs);
      ADD_FAILURE() << bad << " accepted";
    } catch (const std::exception& e) {
      std::string name = std::string(bad).substr(0, std::string(bad).find('='));
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

}  // namespace
