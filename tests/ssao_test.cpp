// `ssao` (ALGORITHMS.md §6, docs/techniques/ssao.md):
//   - a flat floor is never occluded;
//   - next to a 90° corner (floor meeting a wall) the occlusion is the fraction of each kernel
//     sample's rotations that the wall blocks — analytic, ½ at the corner itself, where the wall
//     covers half of the hemisphere's solid angle — within 5 % of that corner value;
//   - the depth-aware blur never mixes values across a depth discontinuity;
//   - the occlusion kernel equals a host implementation of the same formulas (occlusion and the
//     eq. 3.5 colour-bleeding irradiance), and the blur + composition equals its host mirror;
//   - chains: `vpl+ssao` is (1 − occlusion) × `vpl`; malformed chains are rejected.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <glm/gtc/type_ptr.hpp>

#include "gi/ssao/ssao_technique.h"
#include "render/renderer.h"
#include "scene/cornell_box.h"
#include "scene_builders.h"
#include "test_support.h"

using namespace gi;
using namespace gi::test;

namespace {

RenderSettings directSettings(int w, int h) {
  RenderSettings rs;
  rs.width = w;
  rs.height = h;
  rs.technique = "direct";
  rs.sets = {"shadow.resolution=256"};
  return rs;
}

// Floor y = 0 (x, z in [-3, 3]); with a wall, also the plane z = wallZ facing +z.
Scene floorAndWall(bool wall, float wallZ = -1.0f) {
  Scene s;
  s.name = wall ? "corner" : "floor";
  s.materials.push_back(diffuseMaterial(glm::vec3(0.6f)));
  addQuad(s, glm::vec3(-3, 0, 3), glm::vec3(6, 0, 0), glm::vec3(0, 0, -6), 0);  // faces +y
  if (wall) addQuad(s, glm::vec3(-3, 0, wallZ), glm::vec3(6, 0, 0), glm::vec3(0, 3, 0), 0);  // faces +z
  s.computeBounds();
  s.lights.push_back(pointLight(glm::vec3(0, 2, 1), glm::vec3(5.0f)));
  return s;
}

template <typename T>
std::vector<T> download(const cl::Buffer& b) { return context().download<T>(b); }

// Runs the two SSAO passes on the renderer's frame with indirect input 1 everywhere, so the
// composed output is 1 − occlusion (bleeding off) — returns the blurred occlusion.
struct SsaoRun {
  std::vector<float> raw, blurred;
};
SsaoRun runSsao(Renderer& r, const SsaoSettings& s) {
  cl::Context& ctx = context();
  FrameResources f = r.frameResources(true);
  SsaoTechnique t;
  t.setup(f);
  cl::Buffer indirect(ctx, size_t(r.width()) * r.height() * 16);
  ctx.fill(indirect, 1.0f);
  t.occlusionPass(f, s);
  t.blurComposePass(f, s, true, indirect);
  return {download<float>(t.rawOcclusion()), download<float>(t.occlusion())};
}

SsaoSettings settingsFor(const Renderer& r, float radius, bool bleeding) {
  SsaoSettings s = ssaoSettings(r.params(), Bounds{}, true);
  s.radius = radius;
  s.bias = 0.01f * radius;
  s.bleeding = bleeding;
  return s;
}

}  // namespace

TEST(Ssao, FlatFloorHasNoOcclusion) {
  Scene s = floorAndWall(false);
  s.cameras.push_back(lookAtCamera(glm::vec3(0.3f, 1.2f, 2.5f), glm::vec3(0, 0, -1.5f), 1.0f));
  Renderer r(context(), s, directSettings(96, 64));
  r.renderFrame();
  SsaoRun run = runSsao(r, settingsFor(r, 0.5f, false));
  auto pos = download<float>(r.gbuffer().position);
  int floorPixels = 0;
  for (size_t i = 0; i < run.raw.size(); ++i) {
    if (pos[4 * i + 3] == 0.0f) continue;
    ++floorPixels;
    ASSERT_EQ(run.raw[i], 0.0f) << "pixel " << i;
    ASSERT_EQ(run.blurred[i], 0.0f) << "pixel " << i;
  }
  EXPECT_GT(floorPixels, 3000);
}

TEST(Ssao, CornerOcclusionIsTheBlockedFractionOfTheHemisphere) {
  const float wallZ = -1.0f, R = 1.0f;
  Scene s = floorAndWall(true, wallZ);
  s.cameras.push_back(lookAtCamera(glm::vec3(0, 1.2f, 1.0f), glm::vec3(0, 0.2f, wallZ), 1.0f));
  Renderer r(context(), s, directSettings(200, 150));
  r.renderFrame();
  SsaoSettings st = settingsFor(r, R, false);
  SsaoRun run = runSsao(r, st);
  auto pos = download<float>(r.gbuffer().position);
  auto nrm = download<float>(r.gbuffer().geoNormal);
  // Kernel vector i (length s_i, horizontal part h_i = s_i·sin θ_i) rotated about the floor normal
  // by a uniform angle φ crosses the wall (distance d) by more than the bias when
  // R·h_i·cos φ > d + bias: a fraction acos((d + bias)/(R·h_i))/π of the rotations.
  std::vector<float> k = ssaoKernelVectors(st.samples);
  auto expected = [&](float d) {
    double sum = 0;
    for (int i = 0; i < st.samples; ++i) {
      double h = std::hypot(k[4 * i], k[4 * i + 1]);
      double c = (d + st.bias) / (R * h);
      sum += c >= 1.0 ? 0.0 : std::acos(c) / M_PI;
    }
    return sum / st.samples;
  };
  const double cornerValue = expected(0.0f);
  EXPECT_NEAR(cornerValue, 0.5, 0.02);  // the wall blocks half of the hemisphere
  // Bins of distance to the wall; each bin's mean over its floor pixels (all 16 rotations occur).
  const float edges[] = {0.0f, 0.1f, 0.2f, 0.35f, 0.5f, 0.75f, 1.1f};
  // Floor pixels whose samples all stay on screen (|x| < 0.6 m).
  auto counted = [&](size_t i) { return pos[4 * i + 3] != 0.0f && nrm[4 * i + 1] >= 0.99f && std::fabs(pos[4 * i]) < 0.6f; };
  for (int b = 0; b + 1 < int(std::size(edges)); ++b) {
    double raw = 0, blurred = 0, exp = 0;
    int n = 0;
    for (size_t i = 0; i < run.raw.size(); ++i) {
      if (!counted(i)) continue;
      float d = pos[4 * i + 2] - wallZ;
      if (d < edges[b] * R || d >= edges[b + 1] * R) continue;
      raw += run.raw[i];
      blurred += run.blurred[i];
      exp += expected(d);
      ++n;
    }
    ASSERT_GT(n, 100) << "bin " << b;
    raw /= n, blurred /= n, exp /= n;
    std::printf("corner, d/R in [%.2f, %.2f): %5d px, occlusion raw %.4f, blurred %.4f, analytic %.4f\n", edges[b],
                edges[b + 1], n, raw, blurred, exp);
    EXPECT_NEAR(raw, exp, 0.05 * cornerValue) << "bin " << b;
    EXPECT_NEAR(blurred, exp, 0.05 * cornerValue) << "bin " << b;
  }
}

TEST(Ssao, BlurNeverCrossesDepthDiscontinuities) {
  // A quad 1 m in front of the wall: its silhouette is a depth jump of ~1/3 of the view depth.
  Scene s = floorAndWall(true, -2.0f);
  addQuad(s, glm::vec3(-0.5f, 0.3f, -1.0f), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), 0);
  s.computeBounds();
  s.cameras.push_back(lookAtCamera(glm::vec3(0.2f, 1.0f, 2.0f), glm::vec3(0, 0.8f, -2.0f), 1.0f));
  cl::Context& ctx = context();
  Renderer r(ctx, s, directSettings(80, 60));
  r.renderFrame();
  FrameResources f = r.frameResources(true);
  SsaoTechnique t;
  t.setup(f);
  SsaoSettings st = settingsFor(r, 0.3f, true);
  t.occlusionPass(f, st);  // builds the program; its raw output is replaced below
  // Synthetic raw input: occlusion 1 and E = 1 on the near quad (instance 2), 0 elsewhere.
  auto depth = download<float>(r.gbuffer().visibility.depth);
  auto instance = download<uint32_t>(r.gbuffer().instance);
  size_t n = depth.size();
  std::vector<float> occ(n), E(4 * n, 0.0f);
  int near = 0, far = 0;
  for (size_t i = 0; i < n; ++i) {
    bool isNear = instance[i] == 2;
    near += isNear;
    far += !isNear && std::isfinite(depth[i]);
    occ[i] = isNear ? 1.0f : 0.0f;
    for (int c = 0; c < 3; ++c) E[4 * i + c] = occ[i];
  }
  ASSERT_GT(near, 200);
  ASSERT_GT(far, 1000);
  ctx.write(t.rawOcclusion(), occ.data(), n * 4);
  ctx.write(t.rawIrradiance(), E.data(), n * 16);
  cl::Buffer indirect(ctx, n * 16);
  ctx.fill(indirect, 1.0f);
  t.blurComposePass(f, st, true, indirect);
  auto blurred = download<float>(t.occlusion());
  auto out = download<float>(indirect);
  const float rhoOverPi = 0.6f / float(M_PI);
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(depth[i])) continue;
    ASSERT_EQ(blurred[i], occ[i]) << "pixel " << i;
    // (1 − occlusion)·1 + ρ/π·E: ρ/π on the near quad, 1 elsewhere.
    ASSERT_NEAR(out[4 * i], occ[i] == 1.0f ? rhoOverPi : 1.0f, 1e-6f) << "pixel " << i;
  }
}

TEST(Ssao, KernelMatchesHostImplementation) {
  cl::Context& ctx = context();
  Scene s = makeCornellBox();
  const int W = 64, H = 64;
  Renderer r(ctx, s, directSettings(W, H));
  r.renderFrame();
  FrameResources f = r.frameResources(false);
  SsaoTechnique t;
  t.setup(f);
  SsaoSettings st = settingsFor(r, 0.08f, true);
  t.occlusionPass(f, st);
  auto occK = download<float>(t.rawOcclusion());
  auto EK = download<float>(t.rawIrradiance());
  const GBuffer& g = r.gbuffer();
  auto pos = download<float>(g.position), gn = download<float>(g.geoNormal), sn = download<float>(g.normal);
  auto depth = download<float>(g.visibility.depth), direct = download<float>(r.directBuffer());
  auto kv = ssaoKernelVectors(st.samples);
  auto rot = ssaoRotations();
  // Camera space (x, y, depth) of ALGORITHMS.md's right-handed view space; the projection from
  // the camera's matrices directly (not ssaoProjection, which the kernels use).
  glm::mat4 view = glm::make_mat4(g.view.view), viewProj = glm::make_mat4(g.view.view_proj);
  auto toCamera = [&](glm::vec3 v, float w) {
    glm::vec4 c = view * glm::vec4(v, w);
    return glm::vec3(c.x, c.y, -c.z);
  };
  glm::mat4 invView = glm::inverse(view);
  auto v3 = [](const std::vector<float>& b, int i) { return glm::vec3(b[4 * i], b[4 * i + 1], b[4 * i + 2]); };
  int exact = 0, surfaces = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      int p = y * W + x;
      if (pos[4 * p + 3] == 0.0f) {
        ASSERT_EQ(occK[p], 0.0f);
        continue;
      }
      ++surfaces;
      // P from the G-buffer position (the kernel reconstructs it from the depth).
      glm::vec3 Pw = v3(pos, p), n = v3(sn, p), P = toCamera(Pw, 1.0f), ng = toCamera(v3(gn, p), 0.0f);
      // orthonormal_basis (Duff et al.) of the camera-space geometric normal, rotated by the tile's angle.
      float sgn = ng.z >= 0 ? 1.0f : -1.0f, a = -1.0f / (sgn + ng.z), c = ng.x * ng.y * a;
      glm::vec3 t0(1 + sgn * ng.x * ng.x * a, sgn * c, -sgn * ng.x), b0(c, sgn + ng.y * ng.y * a, -ng.y);
      float rc = rot[2 * ((y & 3) * 4 + (x & 3))], rs = rot[2 * ((y & 3) * 4 + (x & 3)) + 1];
      glm::vec3 tt = rc * t0 + rs * b0, bb = rc * b0 - rs * t0;
      float As = float(M_PI) * st.radius * st.radius / st.samples, d2min = As / float(M_PI);
      int occluded = 0;
      glm::vec3 E(0.0f);
      for (int i = 0; i < st.samples; ++i) {
        glm::vec3 S = P + st.radius * (kv[4 * i] * tt + kv[4 * i + 1] * bb + kv[4 * i + 2] * ng);
        if (S.z <= 0) continue;
        glm::vec4 clip = viewProj * (invView * glm::vec4(S.x, S.y, -S.z, 1.0f));
        float sx = (clip.x / clip.w * 0.5f + 0.5f) * W, sy = (0.5f - clip.y / clip.w * 0.5f) * H;
        if (!(sx >= 0 && sx < W && sy >= 0 && sy < H)) continue;
        int q = int(sy) * W + int(sx);
        if (pos[4 * q + 3] == 0.0f) continue;
        // Occluded when S lies more than the bias behind the tangent plane of the surface seen at q
        // (G-buffer position and geometric normal, which faces the camera).
        glm::vec3 Q = toCamera(v3(pos, q), 1.0f), nq = toCamera(v3(gn, q), 0.0f);
        if (!(glm::dot(S - Q, nq) < -st.bias)) continue;
        if (!(std::fabs(depth[q] - depth[p]) < st.radius)) continue;
        ++occluded;
        glm::vec3 v = v3(pos, q) - Pw;
        float d2 = glm::dot(v, v), invD = 1.0f / std::sqrt(std::max(d2, 1e-30f));
        float cosR = std::max(glm::dot(n, v) * invD, 0.0f), cosS = std::max(-glm::dot(v3(sn, q), v) * invD, 0.0f);
        E += v3(direct, q) * (As * cosS * cosR / std::max(d2, d2min));
      }
      float occH = float(occluded) / st.samples;
      // Rounding (FMA contraction, the kernel's depth-reconstructed P and half-float plane
      // gradients) may flip a sample lying on a decision boundary.
      ASSERT_LE(std::fabs(occK[p] - occH), 1.5f / st.samples) << "pixel " << x << "," << y;
      if (occK[p] != occH) continue;
      ++exact;
      for (int ch = 0; ch < 3; ++ch)
        ASSERT_NEAR(EK[4 * p + ch], E[ch], 1e-4f * E[ch] + 1e-7f) << "pixel " << x << "," << y << " channel " << ch;
    }
  std::printf("kernel vs host: %d of %d surface pixels with identical sample decisions\n", exact, surfaces);
  EXPECT_GE(exact, int(0.99 * surfaces));

  // Blur + compose against the host mirror, on the kernel's raw output (ssao alone: no upstream).
  cl::Buffer indirect(ctx, size_t(W) * H * 16);
  t.blurComposePass(f, st, false, indirect);
  auto blurK = download<float>(t.occlusion());
  auto outK = download<float>(indirect);
  auto albedo = download<float>(g.albedo);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      int p = y * W + x;
      if (!std::isfinite(depth[p])) continue;
      float occ = 0, cnt = 0;
      glm::vec3 E(0.0f);
      for (int dy = -2; dy <= 1; ++dy)
        for (int dx = -2; dx <= 1; ++dx) {
          int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
          int q = yy * W + xx;
          if (!(std::fabs(depth[q] - depth[p]) <= st.blurTau * depth[p])) continue;
          occ += occK[q];
          E += v3(EK, q);
          cnt += 1;
        }
      ASSERT_NEAR(blurK[p], occ / cnt, 1e-6f);
      glm::vec3 out = v3(albedo, p) * float(1.0 / M_PI) * E / cnt;
      for (int ch = 0; ch < 3; ++ch) ASSERT_NEAR(outK[4 * p + ch], out[ch], 1e-5f * out[ch] + 1e-9f);
    }
}

TEST(Ssao, ChainOccludesTheIndirectTermOfTheTechniqueBeforeIt) {
  cl::Context& ctx = context();
  CornellOptions o;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  Scene s = makeCornellBox(o);
  auto settings = [](const std::string& tech) {
    RenderSettings rs = directSettings(48, 40);
    rs.technique = tech;
    rs.sets.insert(rs.sets.end(), {"vpl.count=64", "rsm.resolution=64", "ssao.radius=0.06"});
    return rs;
  };
  Renderer plain(ctx, s, settings("vpl"));
  plain.renderFrame();
  Image base = plain.indirectRadiance();
  SsaoRun occ = runSsao(plain, ssaoSettings(plain.params(), s.bounds, true));
  Renderer chained(ctx, s, settings("vpl+ssao"));
  chained.renderFrame();
  Image out = chained.indirectRadiance();
  int occludedPixels = 0;
  for (size_t i = 0; i < out.pixelCount(); ++i) {
    occludedPixels += occ.blurred[i] > 0.0f;
    for (int c = 0; c < 3; ++c) {
      float want = (1.0f - occ.blurred[i]) * base.pixels[3 * i + c];
      ASSERT_NEAR(out.pixels[3 * i + c], want, 1e-6f * want + 1e-9f) << "pixel " << i;
    }
  }
  EXPECT_GT(occludedPixels, 50);

  for (const char* bad : {"ssao+vpl", "vpl+ssao+ssao", "vpl+nonsense", "vpl+"}) {
    try {
      parseTechniqueChain(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}
