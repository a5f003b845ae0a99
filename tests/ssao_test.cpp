// `ssao` (ALGORITHMS.md §6, docs/techniques/ssao.md):
//   - a flat floor is never occluded;
//   - next to a 90° corner (floor meeting a wall) the occlusion is the fraction of each kernel
//     sample's rotations that the wall blocks — analytic, ½ at the corner itself, where the wall
//     covers half of the hemisphere's solid angle — within 5 % of that corner value;
//   - the depth-aware blur never mixes values across a depth discontinuity;
//   - the 4-byte depth-plane records equal their host encoding and hold the tangent plane of the
//     G-buffer within the encoding's stated precision;
//   - the occlusion kernel equals a host implementation of the same formulas (occlusion and the
//     eq. 3.5 colour-bleeding irradiance; the planes rounded as the records round them), and the
//     blur + composition equals its host mirror;
//   - chains: `vpl+ssao` is (1 − occlusion) × `vpl`; malformed chains are rejected;
//   - the first four again with ssao.downsample = 2 (occlusion on the half-resolution grid, the
//     depth-aware blur per camera pixel over the grid).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
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

SsaoSettings settingsFor(const Renderer& r, float radius, bool bleeding, int downsample) {
  SsaoSettings s = ssaoSettings(r.params(), Bounds{}, true);
  s.radius = radius;
  s.bias = 0.01f * radius;
  s.bleeding = bleeding;
  s.downsample = downsample;
  return s;
}

// The occlusion grid of ssao.downsample = D: grid pixel (u, v) is camera pixel (D·u, D·v).
struct Grid {
  int D, W, H, gw, gh;
  Grid(int d, int w, int h) : D(d), W(w), H(h), gw((w + d - 1) / d), gh((h + d - 1) / d) {}
  int camera(int u, int v) const { return D * v * W + D * u; }
};

// The half-resolution blur's acceptance test, from the G-buffer: camera pixel p's depth relative to
// the depth of the tangent plane of the surface seen at camera pixel q on p's view ray,
// n_q·(P − C)/n_q·(Q − C) − 1 (C the camera position; P lies on p's ray).
struct PlaneTest {
  std::vector<float> pos, gn;
  glm::vec3 C;
  explicit PlaneTest(const GBuffer& g)
      : pos(download<float>(g.position)), gn(download<float>(g.geoNormal)),
        C(glm::inverse(glm::make_mat4(g.view.view))[3]) {}
  float offset(int p, int q) const {
    glm::vec3 P(pos[4 * p], pos[4 * p + 1], pos[4 * p + 2]), Q(pos[4 * q], pos[4 * q + 1], pos[4 * q + 2]);
    glm::vec3 n(gn[4 * q], gn[4 * q + 1], gn[4 * q + 2]);
    return glm::dot(n, P - C) / glm::dot(n, Q - C) - 1.0f;
  }
  bool accepts(int p, int q, float tau) const { return pos[4 * q + 3] != 0.0f && std::fabs(offset(p, q)) <= tau; }
};

// Host mirror of the depth-plane record (ssao_encode_record in kernels/gi/ssao/ssao.cl): A = 1/depth
// in the upper 16 bits (5-bit exponent offset by the frame's base, 11 mantissa bits, rounded to
// nearest), the relative gradient g of 1/depth per pixel in the lower 16 bits (shared 4-bit
// exponent E, two 6-bit two's complement mantissas, g = m·2^(E−15)).
uint32_t bitsOf(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
float floatOf(uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
int invDepthBase(float znear) { return 224 - int(bitsOf(znear) >> 23); }
uint32_t encodeRecord(float A, float gx, float gy, int base) {
  int a = (int(bitsOf(A)) + 0x800) >> 12;
  uint32_t wa = uint32_t(std::clamp(a - (base << 11), 0, 0xffff));
  float M = std::max(std::fabs(gx), std::fabs(gy));
  int E = std::clamp(int(bitsOf(M) >> 23) - 116, 0, 15);
  if (E < 15 && M * floatOf(uint32_t(142 - E) << 23) >= 31.5f) ++E;  // rounding would reach 32
  float scale = floatOf(uint32_t(142 - E) << 23);                    // 2^(15−E)
  int mx = std::clamp(int(std::nearbyint(gx * scale)), -31, 31), my = std::clamp(int(std::nearbyint(gy * scale)), -31, 31);
  return wa << 16 | uint32_t(E) << 12 | uint32_t(mx & 63) << 6 | uint32_t(my & 63);
}
struct PlaneRecord {
  float A, gx, gy;
  int E;
};
PlaneRecord decodeRecord(uint32_t w, int base) {
  float scale = floatOf(((w << 11) & 0x07800000u) + (112u << 23));  // 2^(E−15)
  return {floatOf(((w >> 4) & 0x0ffff000u) + (uint32_t(base) << 23)), float(int32_t(w << 20) >> 26) * scale,
          float(int32_t(w << 26) >> 26) * scale, int((w >> 12) & 15)};
}

// The camera's pinhole projection from its matrices (not ssaoProjection, which the kernels use): a
// camera-space point (x, y, depth) projects to (cx + fx·x/depth, cy − fy·y/depth).
struct Pinhole {
  float fx, fy, cx, cy;
  Pinhole(const GiView& v, int W, int H) {
    glm::mat4 P = glm::make_mat4(v.view_proj) * glm::inverse(glm::make_mat4(v.view));
    fx = 0.5f * W * P[0][0], cx = 0.5f * W * (1.0f - P[2][0]);
    fy = 0.5f * H * P[1][1], cy = 0.5f * H * (1.0f + P[2][1]);
  }
  // The tangent plane of the surface seen at camera pixel (x, y) (1/depth A, camera-space normal
  // n facing the camera) as the record holds it: g = (n.x/fx, −n.y/fy)/(n·r), r the pixel centre's
  // ray with depth 1.
  void gradient(glm::vec3 n, int x, int y, float& gx, float& gy) const {
    glm::vec3 r((x + 0.5f - cx) / fx, (cy - y - 0.5f) / fy, 1.0f);
    float nr = glm::dot(n, r);
    nr = std::copysign(std::max(std::fabs(nr), 1e-12f), nr);
    gx = n.x / fx / nr, gy = -n.y / fy / nr;
  }
  // The plane 1/depth(s) = A·(1 + g·(s − centre of pixel (x, y))) as n'·c = 1 in camera space.
  glm::vec3 planeNormal(const PlaneRecord& p, int x, int y) const {
    return p.A * glm::vec3(p.gx * fx, -p.gy * fy, 1.0f - p.gx * (x + 0.5f - cx) - p.gy * (y + 0.5f - cy));
  }
};

void flatFloorHasNoOcclusion(int downsample) {
  Scene s = floorAndWall(false);
  s.cameras.push_back(lookAtCamera(glm::vec3(0.3f, 1.2f, 2.5f), glm::vec3(0, 0, -1.5f), 1.0f));
  Renderer r(context(), s, directSettings(96, 64));
  r.renderFrame();
  SsaoRun run = runSsao(r, settingsFor(r, 0.5f, false, downsample));
  auto pos = download<float>(r.gbuffer().position);
  Grid grid(downsample, r.width(), r.height());
  int floorPixels = 0;
  for (int v = 0; v < grid.gh; ++v)
    for (int u = 0; u < grid.gw; ++u)
      if (pos[4 * grid.camera(u, v) + 3] != 0.0f) ASSERT_EQ(run.raw[v * grid.gw + u], 0.0f) << "grid pixel " << u << "," << v;
  for (size_t i = 0; i < run.blurred.size(); ++i) {
    if (pos[4 * i + 3] == 0.0f) continue;
    ++floorPixels;
    ASSERT_EQ(run.blurred[i], 0.0f) << "pixel " << i;
  }
  EXPECT_GT(floorPixels, 3000);
}

void cornerOcclusionIsTheBlockedFraction(int downsample) {
  const float wallZ = -1.0f, R = 1.0f;
  Scene s = floorAndWall(true, wallZ);
  s.cameras.push_back(lookAtCamera(glm::vec3(0, 1.2f, 1.0f), glm::vec3(0, 0.2f, wallZ), 1.0f));
  Renderer r(context(), s, directSettings(200, 150));
  r.renderFrame();
  SsaoSettings st = settingsFor(r, R, false, downsample);
  SsaoRun run = runSsao(r, st);
  Grid grid(downsample, r.width(), r.height());
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
  // Raw values per grid pixel, blurred values per camera pixel, each against the analytic value at
  // its own surface point.
  for (int b = 0; b + 1 < int(std::size(edges)); ++b) {
    auto inBin = [&](size_t i) {
      float d = pos[4 * i + 2] - wallZ;
      return counted(i) && d >= edges[b] * R && d < edges[b + 1] * R;
    };
    double raw = 0, rawExp = 0, blurred = 0, exp = 0;
    int n = 0, nRaw = 0;
    for (int v = 0; v < grid.gh; ++v)
      for (int u = 0; u < grid.gw; ++u) {
        size_t i = size_t(grid.camera(u, v));
        if (!inBin(i)) continue;
        raw += run.raw[v * grid.gw + u];
        rawExp += expected(pos[4 * i + 2] - wallZ);
        ++nRaw;
      }
    for (size_t i = 0; i < run.blurred.size(); ++i) {
      if (!inBin(i)) continue;
      blurred += run.blurred[i];
      exp += expected(pos[4 * i + 2] - wallZ);
      ++n;
    }
    ASSERT_GT(n, 100) << "bin " << b;
    ASSERT_GT(nRaw, 100 / (downsample * downsample)) << "bin " << b;
    raw /= nRaw, rawExp /= nRaw, blurred /= n, exp /= n;
    std::printf("corner, downsample %d, d/R in [%.2f, %.2f): %5d px, occlusion raw %.4f (analytic %.4f), blurred %.4f "
                "(analytic %.4f)\n",
                downsample, edges[b], edges[b + 1], n, raw, rawExp, blurred, exp);
    EXPECT_NEAR(raw, rawExp, 0.05 * cornerValue) << "bin " << b;
    EXPECT_NEAR(blurred, exp, 0.05 * cornerValue) << "bin " << b;
  }
}

}  // namespace

TEST(Ssao, FlatFloorHasNoOcclusion) { flatFloorHasNoOcclusion(1); }
TEST(Ssao, FlatFloorHasNoOcclusionHalfResolution) { flatFloorHasNoOcclusion(2); }
TEST(Ssao, CornerOcclusionIsTheBlockedFractionOfTheHemisphere) { cornerOcclusionIsTheBlockedFraction(1); }
TEST(Ssao, CornerOcclusionIsTheBlockedFractionOfTheHemisphereHalfResolution) { cornerOcclusionIsTheBlockedFraction(2); }

namespace {

// A quad 1 m in front of the wall: its silhouette is a depth jump of ~1/3 of the view depth.
// Synthetic raw input per grid pixel: occlusion 1 and E = 1 on the near quad (instance 2), 0
// elsewhere; every blurred value must be its own surface's (at half resolution: 0 where no grid
// pixel of the window lies on the pixel's surface, checked on the host).
void blurNeverCrossesDepthDiscontinuities(int downsample) {
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
  SsaoSettings st = settingsFor(r, 0.3f, true, downsample);
  t.occlusionPass(f, st);  // builds the program; its raw output is replaced below
  auto depth = download<float>(r.gbuffer().visibility.depth);
  auto instance = download<uint32_t>(r.gbuffer().instance);
  size_t n = depth.size();
  Grid grid(downsample, r.width(), r.height());
  size_t gn = size_t(grid.gw) * grid.gh;
  std::vector<float> occ(gn), E(4 * gn, 0.0f);
  for (int v = 0; v < grid.gh; ++v)
    for (int u = 0; u < grid.gw; ++u) {
      size_t k = size_t(v) * grid.gw + u;
      occ[k] = instance[grid.camera(u, v)] == 2 ? 1.0f : 0.0f;
      for (int c = 0; c < 3; ++c) E[4 * k + c] = occ[k];
    }
  int near = 0, far = 0;
  for (size_t i = 0; i < n; ++i) {
    near += instance[i] == 2;
    far += instance[i] != 2 && std::isfinite(depth[i]);
  }
  ASSERT_GT(near, 200);
  ASSERT_GT(far, 1000);
  ctx.write(t.rawOcclusion(), occ.data(), gn * 4);
  ctx.write(t.rawIrradiance(), E.data(), gn * 16);
  cl::Buffer indirect(ctx, n * 16);
  ctx.fill(indirect, 1.0f);
  t.blurComposePass(f, st, true, indirect);
  auto blurred = download<float>(t.occlusion());
  auto out = download<float>(indirect);
  const float rhoOverPi = 0.6f / float(M_PI);
  const PlaneTest planes(r.gbuffer());
  int uncovered = 0;
  for (int y = 0; y < grid.H; ++y)
    for (int x = 0; x < grid.W; ++x) {
      size_t i = size_t(y) * grid.W + x;
      if (!std::isfinite(depth[i])) continue;
      float own = instance[i] == 2 ? 1.0f : 0.0f;
      if (downsample == 2) {
        // Does the window hold a grid pixel of the pixel's surface? (Half-float rounding of the
        // kernel's plane gradients could flip a decision within ~1e-4 of tau; none here.)
        bool covered = false;
        for (int j = 0; j < 4; ++j)
          for (int k = 0; k < 4; ++k) {
            int u = (x + 1) / 2 - 2 + k, v = (y + 1) / 2 - 2 + j;
            if (u < 0 || v < 0 || u >= grid.gw || v >= grid.gh) continue;
            covered |= planes.accepts(int(i), grid.camera(u, v), st.blurTau);
          }
        if (!covered) {
          ++uncovered;
          ASSERT_EQ(blurred[i], 0.0f) << "pixel " << x << "," << y;
          ASSERT_EQ(out[4 * i], 1.0f) << "pixel " << x << "," << y;
          continue;
        }
      }
      ASSERT_EQ(blurred[i], own) << "pixel " << x << "," << y;
      // (1 − occlusion)·1 + ρ/π·E: ρ/π on the near quad, 1 elsewhere.
      ASSERT_NEAR(out[4 * i], own == 1.0f ? rhoOverPi : 1.0f, 1e-6f) << "pixel " << x << "," << y;
    }
  std::printf("downsample %d: %d pixels without a grid pixel of their surface in the window\n", downsample, uncovered);
  EXPECT_LE(uncovered, near / 50);
}

}  // namespace

TEST(Ssao, BlurNeverCrossesDepthDiscontinuities) { blurNeverCrossesDepthDiscontinuities(1); }
TEST(Ssao, BlurNeverCrossesDepthDiscontinuitiesHalfResolution) { blurNeverCrossesDepthDiscontinuities(2); }

namespace {

// With downsample = 2 the host evaluates grid pixel (u, v) at camera pixel (2u, 2v), and a sample
// projected to s reads the grid pixel ⌊s/2 + ¼⌋ (the one whose camera pixel centre is nearest),
// i.e. the surface seen at camera pixel 2⌊s/2 + ¼⌋.
void kernelMatchesHostImplementation(int downsample) {
  cl::Context& ctx = context();
  Scene s = makeCornellBox();
  const int W = 64, H = 64;
  Renderer r(ctx, s, directSettings(W, H));
  r.renderFrame();
  FrameResources f = r.frameResources(false);
  SsaoTechnique t;
  t.setup(f);
  SsaoSettings st = settingsFor(r, 0.08f, true, downsample);
  const Grid grid(downsample, W, H);
  const int D = downsample;
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
  const Pinhole pinhole(g.view, W, H);
  const int base = invDepthBase(g.view.znear);
  auto v3 = [](const std::vector<float>& b, int i) { return glm::vec3(b[4 * i], b[4 * i + 1], b[4 * i + 2]); };
  int exact = 0, surfaces = 0;
  for (int y = 0; y < grid.gh; ++y)
    for (int x = 0; x < grid.gw; ++x) {
      int p = grid.camera(x, y), k = y * grid.gw + x;  // camera pixel, grid pixel
      if (pos[4 * p + 3] == 0.0f) {
        ASSERT_EQ(occK[k], 0.0f);
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
        float tx = D == 1 ? sx : sx / D + 0.25f, ty = D == 1 ? sy : sy / D + 0.25f;
        if (!(tx >= 0 && tx < grid.gw && ty >= 0 && ty < grid.gh)) continue;
        int q = grid.camera(int(tx), int(ty));
        if (pos[4 * q + 3] == 0.0f) continue;
        // Occluded when S lies more than the bias behind the tangent plane of the surface seen at q
        // (G-buffer depth and geometric normal, which faces the camera), rounded as the record rounds
        // it: n'·S − 1 > bias·|n'| for the plane n'·c = 1, and the range check on its depth 1/A.
        int qx = D * int(tx), qy = D * int(ty);
        float gx, gy;
        pinhole.gradient(toCamera(v3(gn, q), 0.0f), qx, qy, gx, gy);
        PlaneRecord rec = decodeRecord(encodeRecord(1.0f / depth[q], gx, gy, base), base);
        glm::vec3 nq = pinhole.planeNormal(rec, qx, qy);
        if (!(glm::dot(nq, S) - 1.0f > st.bias * glm::length(nq))) continue;
        if (!(std::fabs(1.0f / rec.A - depth[p]) < st.radius)) continue;
        ++occluded;
        glm::vec3 v = v3(pos, q) - Pw;
        float d2 = glm::dot(v, v), invD = 1.0f / std::sqrt(std::max(d2, 1e-30f));
        float cosR = std::max(glm::dot(n, v) * invD, 0.0f), cosS = std::max(-glm::dot(v3(sn, q), v) * invD, 0.0f);
        E += v3(direct, q) * (As * cosS * cosR / std::max(d2, d2min));
      }
      float occH = float(occluded) / st.samples;
      // Rounding (FMA contraction, the kernel's depth-reconstructed P and projection) may flip a
      // sample lying on a decision boundary.
      ASSERT_LE(std::fabs(occK[k] - occH), 1.5f / st.samples) << "grid pixel " << x << "," << y;
      if (occK[k] != occH) continue;
      ++exact;
      for (int ch = 0; ch < 3; ++ch)
        ASSERT_NEAR(EK[4 * k + ch], E[ch], 1e-4f * E[ch] + 1e-7f) << "grid pixel " << x << "," << y << " channel " << ch;
    }
  std::printf("kernel vs host: %d of %d surface pixels with identical sample decisions\n", exact, surfaces);
  EXPECT_GE(exact, int(0.99 * surfaces));

  // Blur + compose against the host mirror, on the kernel's raw output (ssao alone: no upstream).
  cl::Buffer indirect(ctx, size_t(W) * H * 16);
  t.blurComposePass(f, st, false, indirect);
  auto blurK = download<float>(t.occlusion());
  auto outK = download<float>(indirect);
  const PlaneTest planes(g);
  auto albedo = download<float>(g.albedo);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      int p = y * W + x;
      if (!std::isfinite(depth[p])) continue;
      float occ = 0, cnt = 0;
      glm::vec3 E(0.0f);
      // The 4x4 window of grid pixels: offsets -2..1 around the pixel (around (x+1)/2 on the
      // half-resolution grid).
      const int cx = D == 1 ? x : (x + 1) / 2, cy = D == 1 ? y : (y + 1) / 2;
      for (int dy = -2; dy <= 1; ++dy)
        for (int dx = -2; dx <= 1; ++dx) {
          int u = cx + dx, v = cy + dy;
          if (u < 0 || v < 0 || u >= grid.gw || v >= grid.gh) continue;
          int q = v * grid.gw + u;
          bool accepted = D == 1 ? std::fabs(depth[q] - depth[p]) <= st.blurTau * depth[p]
                                 : planes.accepts(p, grid.camera(u, v), st.blurTau);
          if (!accepted) continue;
          occ += occK[q];
          E += v3(EK, q);
          cnt += 1;
        }
      if (cnt == 0) {  // half resolution only: no grid pixel of this depth in the window
        ASSERT_EQ(D, 2);
        ASSERT_EQ(blurK[p], 0.0f);
        continue;
      }
      ASSERT_NEAR(blurK[p], occ / cnt, 1e-6f);
      glm::vec3 out = v3(albedo, p) * float(1.0 / M_PI) * E / cnt;
      for (int ch = 0; ch < 3; ++ch) ASSERT_NEAR(outK[4 * p + ch], out[ch], 1e-5f * out[ch] + 1e-9f);
    }
}

}  // namespace

namespace {

// The records of ssao: depth planes against the G-buffer: every record equals its host encoding
// (up to rounding-boundary cases of the kernel's float arithmetic) and decodes to the exact tangent
// plane within the stated precision: A within 2⁻¹² relative, each gradient component within
// 2^(E−16), which is at most 1/31.5 of the larger component when E > 0.
void depthPlaneRecordsHoldTheTangentPlanes(const Scene& s, int W, int H) {
  Renderer r(context(), s, directSettings(W, H));
  r.renderFrame();
  FrameResources f = r.frameResources(false);
  SsaoTechnique t;
  t.setup(f);
  t.occlusionPass(f, settingsFor(r, 0.1f, false, 1));
  auto rec = download<uint32_t>(t.depthPlaneRecords());
  const GBuffer& g = r.gbuffer();
  auto depth = download<float>(g.visibility.depth), gn = download<float>(g.geoNormal);
  const glm::mat4 view = glm::make_mat4(g.view.view);
  const Pinhole pinhole(g.view, W, H);
  const int base = invDepthBase(g.view.znear);
  int surfaces = 0, identical = 0, maxE = 0;
  double worstA = 0, worstG = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      int p = y * W + x;
      if (!std::isfinite(depth[p])) {
        ASSERT_EQ(rec[p], 0u) << "background pixel " << x << "," << y;
        continue;
      }
      ++surfaces;
      glm::vec4 c = view * glm::vec4(gn[4 * p], gn[4 * p + 1], gn[4 * p + 2], 0.0f);
      float A = 1.0f / depth[p], gx, gy;
      pinhole.gradient(glm::vec3(c.x, c.y, -c.z), x, y, gx, gy);
      identical += rec[p] == encodeRecord(A, gx, gy, base);
      PlaneRecord d = decodeRecord(rec[p], base);
      double errA = std::fabs(double(d.A) - A) / A, errG = std::max(std::fabs(d.gx - gx), std::fabs(d.gy - gy));
      double M = std::max(std::fabs(gx), std::fabs(gy)), bound = std::ldexp(1.0, d.E - 16);
      // The kernel's 1/depth may differ from the host's by an ulp (1.2e-7 relative).
      ASSERT_LE(errA, std::ldexp(1.0, -12) + 2.5e-7) << "pixel " << x << "," << y;
      // The kernel's g differs from the host's by float rounding (1e-5 relative).
      ASSERT_LE(errG, bound + 1e-5 * M) << "pixel " << x << "," << y << ", E " << d.E;
      if (d.E > 0) ASSERT_LE(bound, M / 31.5 * 1.0001) << "pixel " << x << "," << y << ", E " << d.E;
      worstA = std::max(worstA, errA);
      worstG = std::max(worstG, M > 0 ? errG / M : 0.0);
      maxE = std::max(maxE, d.E);
    }
  std::printf("%s %dx%d: %d of %d records identical to the host encoding; largest errors: A %.2e relative, "
              "g %.2e of the larger component; largest E %d\n",
              s.name.c_str(), W, H, identical, surfaces, worstA, worstG, maxE);
  EXPECT_GE(identical, int(0.99 * surfaces));
}

}  // namespace

TEST(Ssao, DepthPlaneRecordsHoldTheTangentPlanes) {
  depthPlaneRecordsHoldTheTangentPlanes(makeCornellBox(), 64, 64);
  Scene corner = floorAndWall(true, -1.0f);
  corner.cameras.push_back(lookAtCamera(glm::vec3(0, 1.2f, 1.0f), glm::vec3(0, 0.2f, -1.0f), 1.0f));
  depthPlaneRecordsHoldTheTangentPlanes(corner, 200, 150);
}

TEST(Ssao, KernelMatchesHostImplementation) { kernelMatchesHostImplementation(1); }
TEST(Ssao, KernelMatchesHostImplementationHalfResolution) { kernelMatchesHostImplementation(2); }

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

  for (const char* bad : {"ssao+vpl", "vpl+ssao+ssao", "vpl+nonsense", "vpl+", "direct+ssao", "vpl+direct"}) {
    try {
      parseTechniqueChain(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
  // "direct" in a chain: said so, not "unknown technique 'direct' (available: direct, …)".
  try {
    parseTechniqueChain("direct+ssao");
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot be part of a chain"), std::string::npos) << e.what();
  }
}
