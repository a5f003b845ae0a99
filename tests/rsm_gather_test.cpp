// `rsm` (RSM gather, ALGORITHMS.md §2.1) against a host implementation of the same estimator on a
// tiny image, and the geometry-aware upsampler's behaviour at full resolution.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "render/renderer.h"
#include "scene/cornell_box.h"
#include "scene_builders.h"
#include "test_support.h"
#include "util/halton.h"

using namespace gi;

namespace {

// The sample-centre form under test: per pixel (the paper's), or per 8×4-pixel block with a
// tolerance (texels) and an inner fraction of r_max whose samples stay per pixel
// (kernels/gi/rsm/rsm_gather.cl, rsm.sample_centre=block).
struct CentreForm {
  bool block = false;
  int tolerance = 0;
  float inner = 0.0f;
};

constexpr int kBlockW = 8, kBlockH = 4;  // GI_RSM_BLOCK_W × GI_RSM_ROWS

// Renders `s` with `rsm` at full resolution (40 samples, r_max = 0.3 of a 64² RSM) and compares
// every pixel with a host implementation of the estimator on the renderer's own RSM and G-buffer
// (float positions and normals, as ALGORITHMS.md §2.1 states it; the kernel reads the RSM packed
// into 16-byte records, see kernels/gi/rsm/rsm_gather.cl). Returns the number of lit pixels;
// with block centres, *shared and *own count the surface pixels that used the block's centre
// and their own (beyond the tolerance).
int expectRsmMatchesHost(const Scene& s, const CentreForm& form = {}, int* shared = nullptr, int* own = nullptr) {
  cl::Context& ctx = test::context();
  const int W = 21, H = 18, N = 40;
  RenderSettings rs;
  rs.width = W;
  rs.height = H;
  rs.technique = "rsm";
  rs.sets = {"rsm.resolution=64", "rsm.samples=40", "rsm.downsample=1", "rsm.radius=0.3", "shadow.resolution=256"};
  if (form.block) {
    rs.sets.push_back("rsm.sample_centre=block");
    rs.sets.push_back("rsm.block_tolerance=" + std::to_string(form.tolerance));
    rs.sets.push_back("rsm.block_inner=" + std::to_string(form.inner));
  }
  Renderer r(ctx, s, rs);
  r.renderFrame();
  Image ind = r.indirectRadiance();
  const ReflectiveShadowMap& m = r.rsms().at(0);
  int res = m.view.width;
  auto rp = ctx.download<glm::vec4>(m.position), rn = ctx.download<glm::vec4>(m.normal), rf = ctx.download<glm::vec4>(m.flux);
  auto gp = ctx.download<glm::vec4>(r.gbuffer().position), gn = ctx.download<glm::vec4>(r.gbuffer().normal),
       ga = ctx.download<glm::vec4>(r.gbuffer().albedo);
  const float* M = m.view.view_proj;
  glm::vec3 axis = -glm::vec3(m.view.view[2], m.view.view[6], m.view.view[10]), eye(m.view.eye[0], m.view.eye[1], m.view.eye[2]);
  float rmax = 0.3f * res;
  // Each pixel's projection into the RSM, and its texel (floor).
  std::vector<glm::vec2> proj(W * H);
  std::vector<glm::ivec2> texel(W * H);
  for (int p = 0; p < W * H; ++p) {
    glm::vec3 x(gp[p]);
    float cx = M[0] * x.x + M[4] * x.y + M[8] * x.z + M[12], cy = M[1] * x.x + M[5] * x.y + M[9] * x.z + M[13];
    float cw = M[3] * x.x + M[7] * x.y + M[11] * x.z + M[15];
    proj[p] = glm::vec2((cx / cw * 0.5f + 0.5f) * res, (0.5f - cy / cw * 0.5f) * res);
    texel[p] = glm::ivec2(int(std::floor(proj[p].x)), int(std::floor(proj[p].y)));
  }
  // Block centres: among the block's surface pixels in row order, starting at index n/2 + 4, the
  // first whose texel has the most texels of the block within the tolerance (x and y).
  auto blockCentre = [&](int bx, int by) {
    std::vector<glm::ivec2> t;
    for (int y = by * kBlockH; y < std::min(H, (by + 1) * kBlockH); ++y)
      for (int x = bx * kBlockW; x < std::min(W, (bx + 1) * kBlockW); ++x)
        if (gp[y * W + x].w > 0) t.push_back(texel[y * W + x]);
    int n = int(t.size()), start = (n / 2 + kBlockW / 2) % std::max(n, 1), best = start, bestCount = 0;
    for (int j = 0; j < n && bestCount < n; ++j) {
      int k = (start + j) % n, count = 0;
      for (int i = 0; i < n; ++i)
        count += std::abs(t[i].x - t[k].x) <= form.tolerance && std::abs(t[i].y - t[k].y) <= form.tolerance;
      if (count > bestCount) {
        bestCount = count;
        best = k;
      }
    }
    return n ? t[best] : glm::ivec2(0);
  };
  // L = ρ/π · E of pixel p, with every sample around its own projection when perPixel.
  auto estimate = [&](int p, bool perPixel) {
    glm::vec3 e(0.0f);
    if (!(gp[p].w > 0)) return e;
    glm::vec3 x(gp[p]), n(gn[p]);
    glm::ivec2 c = perPixel ? glm::ivec2(0) : blockCentre((p % W) / kBlockW, (p / W) / kBlockH);
    bool ownCentre = perPixel || std::abs(texel[p].x - c.x) > form.tolerance || std::abs(texel[p].y - c.y) > form.tolerance;
    if (!perPixel) ++*(ownCentre ? own : shared);
    for (int i = 0; i < N; ++i) {
      float x1 = radicalInverse(i + 1, 2), x2 = radicalInverse(i + 1, 3);
      float ox = rmax * x1 * std::sin(6.2831853f * x2), oy = rmax * x1 * std::cos(6.2831853f * x2);
      int tx, ty;
      if (ownCentre || x1 < form.inner) {
        tx = int(std::floor(proj[p].x + ox));
        ty = int(std::floor(proj[p].y + oy));
      } else {  // the pattern around the middle of the block's centre texel
        tx = c.x + int(std::floor(ox + 0.5f));
        ty = c.y + int(std::floor(oy + 0.5f));
      }
      if (tx < 0 || ty < 0 || tx >= res || ty >= res) continue;
      size_t t = size_t(ty) * res + tx;
      glm::vec3 q(rp[t]), v = q - x;
      float d2 = glm::dot(v, v), cp = -glm::dot(glm::vec3(rn[t]), v), cr = glm::dot(n, v);
      float fp = m.view.texel_world_size * (m.view.orthographic ? 1.0f : std::abs(glm::dot(q - eye, axis)));
      float g = std::max(cp, 0.0f) * std::max(cr, 0.0f) / (std::max(d2, 1e-20f) * std::max(d2, 0.25f * fp * fp));
      e += glm::vec3(rf[t]) * g * (6.2831853f * rmax * rmax * x1 / N);
    }
    return glm::vec3(ga[p]) * e * (0.31830988618379067154f * 0.31830988618379067154f);
  };
  int lit = 0;
  std::vector<glm::vec3> expectedAll(W * H);
  // The tolerance's absolute part is relative to the per-pixel form's image maximum in every form.
  float maxExpected = 0;
  for (int p = 0; p < W * H; ++p) {
    expectedAll[p] = estimate(p, !form.block);
    maxExpected = std::max(maxExpected, (form.block ? estimate(p, true) : expectedAll[p]).y);
  }
  for (int p = 0; p < W * H; ++p) {
    glm::vec3 expected = expectedAll[p];
    // 2e-3: the upsampler at factor 1 mixes in accepted neighbours with weight 1e-4; texel
    // choices at exact floor() boundaries may differ in rare cases; the packed RSM record rounds
    // the normal's direction (≤ 5e-5 rad) and the flux (≤ 2^-9 relative). Block centres: 1e-2,
    // because their texels include some within ≈ d_min of the receiver (spot case, pixel 338:
    // one sample at d = 2.6 cm carries 73 % of the pixel), where 1/(d²·max(d², d_min²)) turns the
    // record's reconstructed texel-centre position into a 0.7 % difference.
    float relative = form.block ? 1e-2f : 2e-3f;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(ind.pixels[p * 3 + c], expected[c], relative * expected[c] + 2e-3f * maxExpected) << "pixel " << p;
    lit += expected.y > 0;
  }
  return lit;
}

Scene cornellWithSun() {
  CornellOptions o;
  o.withBlocks = false;
  o.withAreaLight = false;
  Scene s = makeCornellBox(o);
  s.lights.push_back(test::directionalLight(glm::vec3(0.25f, -0.6f, 1.0f), glm::vec3(3.0f, 2.5f, 2.0f)));
  s.lightNames.push_back("sun");
  return s;
}

Scene cornellWithSpot() {
  CornellOptions o;
  o.withBlocks = false;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  return makeCornellBox(o);
}

}  // namespace

// Spot light under the ceiling: a perspective RSM (kernel rsm_gather_perspective).
TEST(RsmGather, FullResolutionMatchesHostEstimator) { EXPECT_GT(expectRsmMatchesHost(cornellWithSpot()), 21 * 18 / 3); }

// A sun shining in through the open front: an orthographic RSM (kernel rsm_gather_ortho).
TEST(RsmGather, OrthographicRsmMatchesHostEstimator) { EXPECT_GT(expectRsmMatchesHost(cornellWithSun()), 21 * 18 / 3); }

// rsm.sample_centre=block (kernels rsm_gather_block_*): one centre texel per 8×4 block, pixels
// beyond the tolerance with their own centres, and (second case) the samples of radius
// < 0.3 r_max per pixel. Each case must use both the block's centre and pixels' own.
TEST(RsmGather, BlockCentresMatchHostEstimator) {
  struct Case {
    const char* what;
    Scene scene;
    CentreForm form;
  };
  for (const Case& c : {Case{"spot, tolerance 4", cornellWithSpot(), {true, 4, 0.0f}},
                        Case{"spot, tolerance 6, inner 0.3", cornellWithSpot(), {true, 6, 0.3f}},
                        Case{"sun, tolerance 4", cornellWithSun(), {true, 4, 0.0f}},
                        Case{"sun, tolerance 6, inner 0.3", cornellWithSun(), {true, 6, 0.3f}}}) {
    SCOPED_TRACE(c.what);
    int shared = 0, own = 0;
    EXPECT_GT(expectRsmMatchesHost(c.scene, c.form, &shared, &own), 21 * 18 / 3);
    std::printf("%s: %d pixels with the block's centre, %d with their own\n", c.what, shared, own);
    EXPECT_GT(shared, 21 * 18 / 4);
    EXPECT_GT(own, 0);
  }
}
