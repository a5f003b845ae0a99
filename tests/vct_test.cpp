// Voxel cone tracing kernels (ALGORITHMS.md §5) against independent oracles and host
// implementations of the same formulas: conservative voxelization (dense-sampling oracle and a
// double-precision separating-axis test), a closed mesh gives a closed shell, injection of a lit
// plane, mip levels (isotropic: mean of 8 children conserves Σ premultiplied radiance; anisotropic:
// front-to-back compositing), cones through an empty grid and into a solid wall, the cone march
// against a host mirror, bit-identical frames, directional voxels (level 0 and its mips against the
// host, a lone lit plane that neither lights nor occludes the cones leaving it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <queue>
#include <random>

#include "cl/gather_width.h"
#include "gi/vct/vct_technique.h"
#include "gi/vct/voxel_scene.h"
#include "accuracy_support.h"
#include "reference_scenes.h"
#include "scene_builders.h"
#include "render/renderer.h"
#include "scene/cornell_box.h"
#include "scene/textures.h"
#include "test_support.h"
#include "util/error.h"

using namespace gi;

namespace {

using dvec3 = glm::dvec3;

// Separating-axis triangle–box test in double (box centred at 0, half-size h).
bool satOverlap(dvec3 a, dvec3 b, dvec3 c, double h) {
  for (int k = 0; k < 3; ++k) {
    if (std::min({a[k], b[k], c[k]}) > h || std::max({a[k], b[k], c[k]}) < -h) return false;
  }
  dvec3 e[3] = {b - a, c - b, a - c};
  dvec3 n = glm::cross(e[0], e[1]);
  if (std::abs(glm::dot(n, a)) > h * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z))) return false;
  for (const dvec3& ed : e)
    for (int k = 0; k < 3; ++k) {
      dvec3 axis(0.0);
      axis[k] = 1.0;
      dvec3 u = glm::cross(ed, axis);
      double pa = glm::dot(u, a), pb = glm::dot(u, b), pc = glm::dot(u, c);
      double r = h * (std::abs(u.x) + std::abs(u.y) + std::abs(u.z));
      if (std::min({pa, pb, pc}) > r || std::max({pa, pb, pc}) < -r) return false;
    }
  return true;
}

dvec3 toVoxels(const GiVoxelGrid& g, glm::vec3 p) {
  return (dvec3(p) - dvec3(g.origin[0], g.origin[1], g.origin[2])) / double(g.voxel_size);
}

std::vector<uint32_t> voxelCounts(VoxelScene& vs, const Scene& scene) {
  DeviceScene ds(test::context(), scene);
  vs.voxelize(ds);
  std::vector<uint32_t> acc = test::context().download<uint32_t>(vs.accumulators());
  std::vector<uint32_t> count(vs.voxelCount());
  for (size_t v = 0; v < count.size(); ++v) count[v] = acc[v * GI_VOX_RECORD + GI_VOX_COUNT];
  return count;
}

Scene boundsScene(glm::vec3 lo, glm::vec3 hi) {
  Scene s;
  s.bounds.extend(lo);
  s.bounds.extend(hi);
  return s;
}

// Random sparse level 0: a quarter of the voxels occupied, premultiplied radiance ≤ α.
// Writes a level 0 built by a test and the occupancy bits of its non-zero voxels, as voxelize
// leaves them (buildMips' contract: level 0 is zero wherever the bit is clear).
void writeLevel0(cl::Context& ctx, VoxelScene& vs, const std::vector<glm::vec4>& level0) {
  ctx.write(vs.iso(), level0.data(), level0.size() * 16);
  std::vector<uint32_t> bits(vs.voxelCount() / 32, 0u);
  for (size_t v = 0; v < vs.voxelCount() && v < level0.size(); ++v)
    if (level0[v] != glm::vec4(0.0f)) bits[v >> 5] |= 1u << (v & 31);
  ctx.write(vs.occupancy(), bits.data(), bits.size() * 4);
}

std::vector<glm::vec4> randomLevel0(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  std::vector<glm::vec4> v(n, glm::vec4(0.0f));
  for (auto& x : v)
    if (U(rng) < 0.25f) {
      float a = U(rng);
      x = glm::vec4(a * U(rng), a * U(rng), a * U(rng), a);
    }
  return v;
}

size_t levelOffset(int N, int level) {
  size_t off = 0;
  for (int l = 0; l < level; ++l) off += size_t(N >> l) * (N >> l) * (N >> l);
  return off;
}

// Mirrors VctTraceParams in kernels/gi/vct/cone_trace.cl.
struct TraceParams {
  float startOffset = 0, maxDistance = 0, stepFactor = 0.5f, aoLambda = 0;
  int32_t anisotropic = 0, applyAo = 0, footprintInFront = 0, levelSteps = 0, specularLevelSteps = 0;
};

struct ConeOut {
  std::vector<glm::vec4> radiance;
  std::vector<float> occlusion;
};

// sh: read the SH voxels (vct.voxels=sh) instead of the isotropic radiance. borderEdge: the
// grid's border repeats its edge voxels (vct.border=edge). Directional voxels when vs was built
// with them (VoxelScene::directional).
ConeOut traceCones(VoxelScene& vs, const TraceParams& tp, const std::vector<glm::vec4>& cones,
                   const std::vector<glm::vec4>& dirs, bool sh = false, bool borderEdge = false) {
  cl::Context& ctx = test::context();
  cl::Program prog = ctx.buildProgram("kernels/gi/vct/cone_trace.cl",
                                      {{"GI_VCT_CONES", "6"}, {"GI_DOWN", "1"}, {"GI_VCT_SH", sh ? "1" : "0"},
                                       {"GI_VCT_DIRECTIONAL", vs.directional() ? "1" : "0"},
                                       {"GI_VCT_BORDER_EDGE", borderEdge ? "1" : "0"}});
  cl::Kernel k = prog.kernel("vct_trace_cones");
  cl::Buffer c = ctx.upload(cones, "cones"), d = ctx.upload(dirs, "dirs");
  cl::Buffer out(ctx, cones.size() * 16), occ(ctx, cones.size() * 4);
  const cl::Buffer& aniso = tp.anisotropic ? vs.aniso() : vs.iso();
  const cl::Buffer& shIso = sh ? vs.sh() : vs.iso();
  const cl::Buffer& shAniso = sh && tp.anisotropic ? vs.shAniso() : shIso;
  k.args(vs.grid(), tp, vs.iso(), aniso, shIso, shAniso, c, d, int(cones.size()), out, occ);
  ctx.launch(k, cl::NDRange::d1(cl::roundUp(cones.size(), 64), 64));
  ConeOut r;
  r.radiance = ctx.download<glm::vec4>(out);
  r.occlusion = ctx.download<float>(occ);
  ctx.profiler().discard();
  return r;
}

// ---- host mirror of voxel_grid.h / cone.h ---------------------------------------------------
// l <= 1 real SH basis of ALGORITHMS.md §4 at unit d.
glm::vec4 shBasis(glm::vec3 d) { return glm::vec4(0.282095f, 0.488603f * d.y, 0.488603f * d.z, 0.488603f * d.x); }

struct HostMips {
  int N = 0, levels = 0;
  std::vector<glm::vec4> iso, aniso;
  bool shVoxels = false;            // radiance from the SH chains (3 float4 per voxel), opacity from iso/aniso
  std::vector<glm::vec4> sh, shAniso;
  bool borderEdge = false;  // vct.border=edge: positions clamped to the outermost voxel centres ahead of d
  // Trilinear filter of fetch(voxel index) over a volume of n³ voxels for a cone along d
  // (outside: 0; with borderEdge, along each axis d heads out on, the edge voxels).
  template <class Fetch>
  glm::vec4 trilinear(int n, glm::vec3 p, glm::vec3 d, float scale, Fetch fetch) const {
    glm::vec3 u = p * scale - 0.5f;
    if (borderEdge)
      for (int k = 0; k < 3; ++k) {
        if (d[k] < 0.0f) u[k] = std::max(u[k], 0.0f);
        if (d[k] > 0.0f) u[k] = std::min(u[k], float(n - 1));
      }
    glm::vec3 fl = glm::floor(u), f = u - fl;
    glm::ivec3 i0(fl);
    glm::vec4 acc(0.0f);
    for (int dz = 0; dz < 2; ++dz)
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          int x = i0.x + dx, y = i0.y + dy, z = i0.z + dz;
          if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n) continue;
          float w = (dz ? f.z : 1 - f.z) * (dy ? f.y : 1 - f.y) * (dx ? f.x : 1 - f.x);
          acc += w * fetch((size_t(z) * n + y) * n + x);
        }
    return acc;
  }
  size_t anisoOffset(int level, int dir) const {
    size_t n = size_t(N >> level);
    return 6 * (levelOffset(N, level) - size_t(N) * N * N) + size_t(dir) * n * n * n;
  }
  // One volume: premultiplied radiance and opacity; SH voxels: the coefficients filtered, then
  // evaluated towards the cone's apex (−d).
  glm::vec4 volume(bool isoChain, size_t offset, int n, glm::vec3 p, float scale, glm::vec3 d) const {
    const glm::vec4* radiance = (isoChain ? iso : aniso).data() + offset;
    glm::vec4 c = trilinear(n, p, d, scale, [&](size_t i) { return radiance[i]; });
    if (!shVoxels) return c;
    const glm::vec4* coeffs = (isoChain ? sh : shAniso).data() + 3 * offset;
    glm::vec4 Y = shBasis(-d);
    for (int ch = 0; ch < 3; ++ch)
      c[ch] = glm::dot(trilinear(n, p, d, scale, [&](size_t i) { return coeffs[3 * i + ch]; }), Y);
    return c;
  }
  glm::vec4 levelSample(int level, glm::vec3 p, glm::vec3 d, bool an) const {
    int n = N >> level;
    float scale = 1.0f / float(1 << level);
    if (!an || level == 0) return volume(true, levelOffset(N, level), n, p, scale, d);
    glm::vec3 w = d * d;
    return w.x * volume(false, anisoOffset(level, d.x >= 0 ? 0 : 1), n, p, scale, d) +
           w.y * volume(false, anisoOffset(level, d.y >= 0 ? 2 : 3), n, p, scale, d) +
           w.z * volume(false, anisoOffset(level, d.z >= 0 ? 4 : 5), n, p, scale, d);
  }
  glm::vec4 sample(glm::vec3 p, glm::vec3 d, float level, bool an) const {
    level = std::clamp(level, 0.0f, float(levels - 1));
    int l0 = int(std::floor(level));
    float f = level - float(l0);
    glm::vec4 c = levelSample(l0, p, d, an);
    if (f > 0 && l0 + 1 < levels) c = glm::mix(c, levelSample(l0 + 1, p, d, an), f);
    if (shVoxels)
      for (int ch = 0; ch < 3; ++ch) c[ch] = std::max(c[ch], 0.0f);  // l <= 1 ringing behind surfaces
    return c;
  }
  // cone.h's march, written independently from its comment.
  glm::vec4 cone(glm::vec3 o, glm::vec3 d, float tanHalf, float maxDist, float sf, bool an) const {
    glm::vec3 c(0.0f);
    float a = 0, t = 0;
    while (true) {
      float step = std::max(0.5f, sf * std::max(1.0f, 2 * tanHalf * t));
      t += step;
      if (t > maxDist) break;
      glm::vec3 p = o + d * t;
      float D = std::max(1.0f, 2 * tanHalf * t);
      if (glm::any(glm::lessThan(p, glm::vec3(-0.5f * D))) || glm::any(glm::greaterThan(p, glm::vec3(N + 0.5f * D))))
        break;
      glm::vec4 s = sample(p, d, std::log2(D), an);
      if (s.w > 1e-6f) {
        float alpha = std::min(s.w, 1.0f);
        float ac = 1.0f - std::pow(1.0f - alpha, step / D);
        c += (1 - a) * glm::vec3(s) * (ac / s.w);
        a += (1 - a) * ac;
        if (a >= 0.99f) break;
      }
    }
    return glm::vec4(c, a);
  }
};

// Front and back child (indices in the child volume of edge nc) of column (i, j) of parent
// (x, y, z) seen along direction dir (+x, −x, +y, −y, +z, −z): voxel_light.cl's comment.
std::pair<size_t, size_t> columnChildren(int dir, int i, int j, int x, int y, int z, int nc) {
  int axis = dir / 2;
  bool positive = dir % 2 == 0;
  glm::ivec3 cf, cb;
  for (int k = 0, o = 0; k < 3; ++k) {
    if (k == axis) {
      cf[k] = positive ? 0 : 1;
      cb[k] = positive ? 1 : 0;
    } else {
      cf[k] = cb[k] = o++ == 0 ? i : j;
    }
  }
  glm::ivec3 b(2 * x, 2 * y, 2 * z);
  return {(size_t(b.z + cf.z) * nc + b.y + cf.y) * nc + b.x + cf.x,
          (size_t(b.z + cb.z) * nc + b.y + cb.y) * nc + b.x + cb.x};
}

// n random cones in a 32³ grid: (origin in voxels, tan of the half-angle 0.02-1.02) and
// (direction, max distance 8-48 voxels).
void randomCones(int n, uint32_t seed, std::vector<glm::vec4>& cones, std::vector<glm::vec4>& dirs) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  for (int i = 0; i < n; ++i) {
    glm::vec3 d = glm::normalize(glm::vec3(U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f) + glm::vec3(1e-3f));
    cones.emplace_back(U(rng) * 32, U(rng) * 32, U(rng) * 32, 0.02f + U(rng));
    dirs.emplace_back(d, 8.0f + 40.0f * U(rng));
  }
}

// Host anisotropic chain of levels ≥ 1 from level 0 (the compositing rule of voxel_light.cl's
// comment): from the isotropic level0, or (directional voxels) from level 0's 6 directional volumes
// of N³ voxels each, in direction order.
std::vector<glm::vec4> hostAnisotropic(const std::vector<glm::vec4>& level0, int N, int levels,
                                       const std::vector<glm::vec4>* level0Directional = nullptr) {
  HostMips h;
  h.N = N;
  std::vector<glm::vec4> out;
  for (int l = 1; l < levels; ++l) out.resize(out.size() + 6 * size_t(N >> l) * (N >> l) * (N >> l));
  for (int l = 1; l < levels; ++l) {
    int n = N >> l, nc = 2 * n;
    for (int dir = 0; dir < 6; ++dir) {
      const glm::vec4* child = l > 1 ? out.data() + h.anisoOffset(l - 1, dir)
                               : level0Directional ? level0Directional->data() + size_t(dir) * N * N * N
                                                   : level0.data();
      for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) {
            glm::vec4 sum(0.0f);
            for (int j = 0; j < 2; ++j)
              for (int i = 0; i < 2; ++i) {
                auto [f, b] = columnChildren(dir, i, j, x, y, z, nc);
                sum += child[f] + (1.0f - child[f].w) * child[b];
              }
            out[h.anisoOffset(l, dir) + (size_t(z) * n + y) * n + x] = sum * 0.25f;
          }
    }
  }
  return out;
}

// Host SH chains (3 float4 per voxel) from SH level 0, by the same rules on the coefficients:
// isotropic = mean of the 8 children; anisotropic = per column front + (1 − α_front)·back, α from
// the radiance mips (isoLevel0 below level 1, else the radiance volume of the same direction).
std::vector<glm::vec4> hostShIsotropic(const std::vector<glm::vec4>& shLevel0, int N, int levels) {
  std::vector<glm::vec4> out(3 * levelOffset(N, levels), glm::vec4(0.0f));
  std::copy(shLevel0.begin(), shLevel0.end(), out.begin());
  for (int l = 1; l < levels; ++l) {
    int n = N >> l, nc = 2 * n;
    size_t child = levelOffset(N, l - 1), parent = levelOffset(N, l);
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          for (int ch = 0; ch < 3; ++ch) {
            glm::vec4 sum(0.0f);
            for (int k = 0; k < 8; ++k)
              sum += out[3 * (child + (size_t(2 * z + (k >> 2)) * nc + 2 * y + ((k >> 1) & 1)) * nc + 2 * x + (k & 1)) + ch];
            out[3 * (parent + (size_t(z) * n + y) * n + x) + ch] = sum / 8.0f;
          }
  }
  return out;
}

std::vector<glm::vec4> hostShAnisotropic(const std::vector<glm::vec4>& shLevel0, const std::vector<glm::vec4>& isoLevel0,
                                         const std::vector<glm::vec4>& radianceAniso, int N, int levels) {
  HostMips h;
  h.N = N;
  std::vector<glm::vec4> out(3 * radianceAniso.size(), glm::vec4(0.0f));
  for (int l = 1; l < levels; ++l) {
    int n = N >> l, nc = 2 * n;
    for (int dir = 0; dir < 6; ++dir) {
      const glm::vec4* alpha = l == 1 ? isoLevel0.data() : radianceAniso.data() + h.anisoOffset(l - 1, dir);
      const glm::vec4* child = l == 1 ? shLevel0.data() : out.data() + 3 * h.anisoOffset(l - 1, dir);
      for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x)
            for (int ch = 0; ch < 3; ++ch) {
              glm::vec4 sum(0.0f);
              for (int j = 0; j < 2; ++j)
                for (int i = 0; i < 2; ++i) {
                  auto [f, b] = columnChildren(dir, i, j, x, y, z, nc);
                  sum += child[3 * f + ch] + (1.0f - alpha[f].w) * child[3 * b + ch];
                }
              out[3 * (h.anisoOffset(l, dir) + (size_t(z) * n + y) * n + x) + ch] = sum * 0.25f;
            }
    }
  }
  return out;
}

// Random SH level 0 for the voxels of `level0` that are occupied: per channel random
// coefficients times the voxel's opacity (premultiplied, as vct_sh_project writes them).
std::vector<glm::vec4> randomShLevel0(const std::vector<glm::vec4>& level0, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-1.0f, 1.0f);
  std::vector<glm::vec4> sh(3 * level0.size(), glm::vec4(0.0f));
  for (size_t v = 0; v < level0.size(); ++v)
    if (level0[v].w > 0)
      for (int ch = 0; ch < 3; ++ch)
        sh[3 * v + ch] = level0[v].w * glm::vec4(1.0f + 0.5f * U(rng), U(rng), U(rng), U(rng));
  return sh;
}

// `count` random triangles around centres in [-1, 1]³: every `largeEvery`-th of size `large`,
// the others `small`; every `planeEvery`-th flat in axis `planeAxis` (axis-aligned plane), every
// 7th a sliver; triangle i gets material(i).
void addMixedTriangles(Scene& s, std::mt19937& rng, int count, int largeEvery, float large, float small,
                       int planeEvery, int planeAxis, const std::function<uint32_t(int)>& material) {
  std::uniform_real_distribution<float> U(-1.0f, 1.0f);
  for (int i = 0; i < count; ++i) {
    glm::vec3 c(U(rng), U(rng), U(rng));
    float size = i % largeEvery == 0 ? large : small;
    glm::vec3 a = c + size * glm::vec3(U(rng), U(rng), U(rng)), b = c + size * glm::vec3(U(rng), U(rng), U(rng));
    glm::vec3 d = c + size * glm::vec3(U(rng), U(rng), U(rng));
    if (i % planeEvery == 0) a[planeAxis] = b[planeAxis] = d[planeAxis] = c[planeAxis];
    if (i % 7 == 0) d = a + 1e-3f * (b - a);
    test::addTriangle(s, a, b, d, material(i));
  }
}

}  // namespace

TEST(VctVoxelize, ConservativeAgainstSamplingOracleAndExactOverlap) {
  // 3000 random triangles of mixed sizes (slivers included) plus 300 axis-aligned ones, 32³.
  Scene s = test::triangleSoup(2500, 0.12f, 7);
  std::mt19937 rng(11);
  addMixedTriangles(s, rng, 500, 5, 0.8f, 0.25f, 2, 2, [](int) { return 0u; });
  s.computeBounds();
  VoxelScene vs(test::context(), s, 32);
  std::vector<uint32_t> device = voxelCounts(vs, s);
  const GiVoxelGrid& g = vs.grid();
  int N = g.resolution;
  std::vector<uint32_t> dense(device.size(), 0), exact(device.size(), 0), grown(device.size(), 0);
  std::vector<int> stamp(device.size(), -1);
  for (size_t t = 0; t < s.triangles.size(); ++t) {
    dvec3 v0 = toVoxels(g, s.positions[s.triangles[t].x]), v1 = toVoxels(g, s.positions[s.triangles[t].y]);
    dvec3 v2 = toVoxels(g, s.positions[s.triangles[t].z]);
    // Dense barycentric samples at most 1/8 voxel apart.
    double edge = std::max({glm::length(v1 - v0), glm::length(v2 - v1), glm::length(v0 - v2)});
    int m = int(std::ceil(edge * 8)) + 1;
    for (int i = 0; i <= m; ++i)
      for (int j = 0; i + j <= m; ++j) {
        dvec3 p = v0 + (v1 - v0) * (double(i) / m) + (v2 - v0) * (double(j) / m);
        glm::ivec3 q(glm::floor(p));
        if (glm::any(glm::lessThan(q, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(q, glm::ivec3(N)))) continue;
        size_t v = (size_t(q.z) * N + q.y) * N + q.x;
        if (stamp[v] != int(t)) {
          stamp[v] = int(t);
          ++dense[v];
        }
      }
    glm::ivec3 lo(glm::floor(glm::min(v0, glm::min(v1, v2)))), hi(glm::floor(glm::max(v0, glm::max(v1, v2))));
    for (int z = std::max(lo.z - 1, 0); z <= std::min(hi.z + 1, N - 1); ++z)
      for (int y = std::max(lo.y - 1, 0); y <= std::min(hi.y + 1, N - 1); ++y)
        for (int x = std::max(lo.x - 1, 0); x <= std::min(hi.x + 1, N - 1); ++x) {
          dvec3 c(x + 0.5, y + 0.5, z + 0.5);
          size_t v = (size_t(z) * N + y) * N + x;
          if (satOverlap(v0 - c, v1 - c, v2 - c, 0.5)) ++exact[v];
          if (satOverlap(v0 - c, v1 - c, v2 - c, 0.5 + 2e-4)) ++grown[v];
        }
  }
  size_t missedDense = 0, missedExact = 0, extra = 0, occupied = 0;
  for (size_t v = 0; v < device.size(); ++v) {
    missedDense += dense[v] > device[v];
    missedExact += exact[v] > device[v];
    extra += device[v] > grown[v];
    occupied += device[v] > 0;
  }
  std::printf("%zu triangles, 32^3: %zu voxels occupied; voxels missing a dense-sample hit %zu, "
              "missing an exact overlap %zu, marked without overlap %zu\n",
              s.triangles.size(), occupied, missedDense, missedExact, extra);
  EXPECT_GT(occupied, 1000u);
  EXPECT_EQ(missedDense, 0u);
  EXPECT_EQ(missedExact, 0u);
  EXPECT_EQ(extra, 0u);
}

TEST(VctVoxelize, LanesMatchOneTriangleAtATime) {
  // vct_voxelize (columns of triangles in SIMD lanes) against vct_voxelize_trianglewise (one
  // work-item per triangle), every accumulator word: random triangles from sub-voxel to ~25
  // voxels across (axis-aligned ones and slivers included), random UVs outside [0, 1] and
  // perturbed vertex normals, on four materials: plain, alpha-masked, textured (sRGB base colour
  // with alpha mask, metallic-roughness map) and emissive (textured emission), 32³.
  Scene s = test::triangleSoup(1200, 0.1f, 5, 9);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> U(-1.0f, 1.0f);
  addMixedTriangles(s, rng, 300, 3, 0.8f, 0.3f, 4, 1, [](int i) { return 2u + uint32_t(i % 2); });
  for (size_t v = 0; v < s.positions.size(); ++v) {
    s.uvs[v] = glm::vec2(1.5f + 2.5f * U(rng), 0.5f + 2.0f * U(rng));
    s.normals[v] = glm::normalize(s.normals[v] + 0.3f * glm::vec3(U(rng), U(rng), U(rng)));
  }
  auto randomTexture = [&](const char* name, int w, int h, bool srgb) {
    std::vector<uint8_t> texels(size_t(w) * h * 4);
    for (uint8_t& b : texels) b = uint8_t(std::uniform_int_distribution<int>(0, 255)(rng));
    s.textures.push_back(makeTexture(name, w, h, texels.data(), srgb));
    return int(s.textures.size()) - 1;
  };
  GiMaterial textured = test::diffuseMaterial(0.9f, 0.8f, 0.7f);
  textured.base_color_tex = randomTexture("base", 16, 8, true);
  textured.metallic_roughness_tex = randomTexture("mr", 8, 8, false);
  textured.metallic = 0.7f;
  textured.alpha_mode = GI_ALPHA_MASK;
  textured.alpha_cutoff = 0.4f;
  GiMaterial emissive = test::diffuseMaterial(0.3f, 0.6f, 0.9f);
  emissive.emissive[0] = 2.0f;
  emissive.emissive[1] = 30.0f;
  emissive.emissive[2] = 400.0f;
  emissive.emissive_tex = randomTexture("emission", 4, 16, true);
  s.materials.push_back(textured);
  s.materials.push_back(emissive);
  s.computeBounds();
  VoxelScene vs(test::context(), s, 32);
  DeviceScene ds(test::context(), s);
  vs.voxelize(ds, VoxelScene::VoxelizeKernel::Trianglewise);
  std::vector<uint32_t> one = test::context().download<uint32_t>(vs.accumulators());
  vs.voxelize(ds, VoxelScene::VoxelizeKernel::Lanes);
  std::vector<uint32_t> lanes = test::context().download<uint32_t>(vs.accumulators());
  size_t occupied = 0, emitting = 0, differing = 0;
  for (size_t v = 0; v < vs.voxelCount(); ++v) {
    const uint32_t* a = &one[v * GI_VOX_RECORD];
    occupied += a[GI_VOX_COUNT] > 0;
    emitting += a[GI_VOX_EMISSION + 2] > 0;
    differing += std::memcmp(a, &lanes[v * GI_VOX_RECORD], GI_VOX_RECORD * 4) != 0;
  }
  std::printf("%zu triangles, 32^3: %zu voxels occupied, %zu emitting, %zu records differ\n", s.triangles.size(),
              occupied, emitting, differing);
  EXPECT_GT(occupied, 2000u);
  EXPECT_GT(emitting, 200u);
  EXPECT_EQ(differing, 0u);
}

TEST(VctVoxelize, ClosedMeshGivesClosedShell) {
  const float r = 0.8f;
  const int rings = 24;
  Scene s = test::insideSphere(rings, r, 0.5f);
  VoxelScene vs(test::context(), s, 32);
  std::vector<uint32_t> count = voxelCounts(vs, s);
  const GiVoxelGrid& g = vs.grid();
  int N = g.resolution;
  // Flood the empty voxels from the grid's corner (6-connected): the shell must keep it out.
  std::vector<char> reached(count.size(), 0);
  std::queue<glm::ivec3> q;
  q.push(glm::ivec3(0));
  reached[0] = 1;
  const glm::ivec3 steps[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (!q.empty()) {
    glm::ivec3 p = q.front();
    q.pop();
    for (const glm::ivec3& d : steps) {
      glm::ivec3 n = p + d;
      if (glm::any(glm::lessThan(n, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(n, glm::ivec3(N)))) continue;
      size_t v = (size_t(n.z) * N + n.y) * N + n.x;
      if (reached[v] || count[v] > 0) continue;
      reached[v] = 1;
      q.push(n);
    }
  }
  size_t inside = 0, shell = 0, far = 0;
  double sag = r * (1.0 - std::cos(M_PI / rings));
  for (int z = 0; z < N; ++z)
    for (int y = 0; y < N; ++y)
      for (int x = 0; x < N; ++x) {
        size_t v = (size_t(z) * N + y) * N + x;
        glm::dvec3 c = dvec3(g.origin[0], g.origin[1], g.origin[2]) + (dvec3(x, y, z) + 0.5) * double(g.voxel_size);
        if (count[v] > 0) {
          ++shell;
          if (std::abs(glm::length(c) - r) > 0.87 * g.voxel_size + sag) ++far;
        } else if (!reached[v]) {
          ++inside;
          EXPECT_LT(glm::length(c), r) << "unreached empty voxel outside the sphere";
        }
      }
  size_t centre = (size_t(N / 2) * N + N / 2) * N + N / 2;
  std::printf("sphere r=%.2f in 32^3: shell %zu voxels, enclosed empty %zu, shell voxels off the surface %zu\n", r,
              shell, inside, far);
  EXPECT_FALSE(reached[centre]) << "the flood from outside reached the centre: the shell has a hole";
  EXPECT_GT(inside, 1000u);
  EXPECT_EQ(far, 0u);
}

namespace {

// A horizontal 2 m × 2 m quad at height y with diffuse albedo rho, lit by a directional light
// along sunDir of irradiance E on a plane facing it; no shadow map.
Scene sunlitPlane(glm::vec3 rho, float y, glm::vec3 sunDir, glm::vec3 E) {
  Scene s;
  s.name = "plane";
  s.materials.push_back(test::diffuseMaterial(rho.x, rho.y, rho.z));
  glm::vec3 a(-1, y, -1), b(1, y, -1), c(1, y, 1), d(-1, y, 1);
  test::addTriangle(s, a, d, c, 0);
  test::addTriangle(s, a, c, b, 0);
  s.computeBounds();
  GiLight sun{};
  sun.type = GI_LIGHT_DIRECTIONAL;
  glm::vec3 dir = glm::normalize(sunDir);
  for (int k = 0; k < 3; ++k) {
    sun.direction[k] = dir[k];
    sun.intensity[k] = E[k];
  }
  sun.shadow_map = -1;
  s.lights.push_back(sun);
  return s;
}

// A lone sunlit plane (albedo 0.8, sun straight down) seen from 1.5 m above.
Scene lonePlaneSeenFromAbove() {
  Scene s = sunlitPlane(glm::vec3(0.8f), 0.0f, glm::vec3(0, -1, 0), glm::vec3(3.0f));
  Camera cam;
  cam.position = glm::vec3(0, 1.5f, 0.01f);
  cam.target = glm::vec3(0, 0, 0);
  cam.yfov = 0.9f;
  s.cameras.push_back(cam);
  return s;
}

// Sum over a 32×32 frame of vct's indirect radiance with the given parameters.
double vctIndirectSum(const Scene& s, std::vector<std::string> sets) {
  RenderSettings rs;
  rs.width = 32;
  rs.height = 32;
  rs.technique = "vct";
  rs.sets = std::move(sets);
  Renderer r(test::context(), s, rs);
  r.renderFrame();
  double sum = 0;
  for (float v : r.indirectRadiance().pixels) sum += v;
  return sum;
}

// An empty shadow-map set, for scenes whose lights have none (shadow_map = -1).
ShadowMapSet noShadowMaps(cl::Context& ctx) {
  ShadowMapSet shadows;
  shadows.viewTable = ctx.upload(std::vector<GiView>{}, "views");
  shadows.offsetTable = ctx.upload(std::vector<uint32_t>{}, "offsets");
  shadows.depths = cl::Buffer(ctx, 4);
  return shadows;
}

// Directional voxels: accumulator records (voxel_types.h) of one opaque triangle–voxel pair per
// non-empty voxel of level0, with mean normal normals[v] (shorter than 0.5: a two-sided voxel,
// VoxelSurface.twoSided) and no offset; what vct_directional_level0 reads through vox_resolve.
void writeNormals(cl::Context& ctx, VoxelScene& vs, const std::vector<glm::vec4>& level0,
                  const std::vector<glm::vec3>& normals) {
  std::vector<uint32_t> acc(vs.voxelCount() * GI_VOX_RECORD, 0u);
  for (size_t v = 0; v < level0.size(); ++v) {
    if (level0[v] == glm::vec4(0.0f)) continue;
    uint32_t* r = &acc[v * GI_VOX_RECORD];
    r[GI_VOX_OPACITY] = uint32_t(GI_VOX_UNIT);
    r[GI_VOX_COUNT] = 1;
    for (int k = 0; k < 3; ++k) {
      r[GI_VOX_ALBEDO + k] = uint32_t(0.5f * GI_VOX_UNIT);
      r[GI_VOX_NORMAL + k] = uint32_t(int32_t(std::lround(normals[v][k] * GI_VOX_UNIT / 4)) + int32_t(GI_VOX_SIGNED_BIAS));
      r[GI_VOX_OFFSET + k] = GI_VOX_SIGNED_BIAS;
    }
  }
  ctx.write(vs.accumulators(), acc.data(), acc.size() * 4);
}

// The mean normal as vox_resolve reads it back from writeNormals' fixed-point records.
glm::vec3 storedNormal(glm::vec3 n) {
  return glm::vec3(std::lround(n.x * GI_VOX_UNIT / 4), std::lround(n.y * GI_VOX_UNIT / 4),
                   std::lround(n.z * GI_VOX_UNIT / 4)) * (4.0f / GI_VOX_UNIT);
}

// Random unit normals for the non-empty voxels of level0: every 7th axis-aligned, every 5th
// shortened to length 0.3 (two-sided).
std::vector<glm::vec3> randomNormals(const std::vector<glm::vec4>& level0, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-1.0f, 1.0f);
  std::vector<glm::vec3> normals(level0.size(), glm::vec3(0.0f));
  for (size_t v = 0, k = 0; v < level0.size(); ++v) {
    if (level0[v] == glm::vec4(0.0f)) continue;
    glm::vec3 n = glm::normalize(glm::vec3(U(rng), U(rng), U(rng)) + glm::vec3(1e-3f));
    if (k % 7 == 3) {
      n = glm::vec3(0.0f);
      n[k % 3] = k % 2 ? 1.0f : -1.0f;
    }
    if (k % 5 == 0) n *= 0.3f;
    normals[v] = n;
    ++k;
  }
  return normals;
}

// What a cone travelling along axis direction dir (+x, −x, +y, −y, +z, −z) sees of a level-0 voxel
// with mean normal meanN, from voxel_grid.h's definition: the projected coverage |n·e| / max_i |n_i|
// of a plane facing the cone (n·e < 0), nothing of one facing away, all of a two-sided voxel.
// A slab (vct.voxels=directional_slab): opaque from every side but to a cone leaving through the
// front, by the same projected coverage: 1 − that of the plane seen from behind.
float hostCoverage(glm::vec3 meanN, int dir, bool slab) {
  if (glm::length(meanN) < 0.5f) return 1.0f;
  glm::vec3 n = glm::normalize(meanN), e(0.0f);
  e[dir / 2] = dir % 2 ? -1.0f : 1.0f;
  float dominant = std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  float front = std::clamp(-glm::dot(n, e) / dominant, 0.0f, 1.0f), back = std::clamp(glm::dot(n, e) / dominant, 0.0f, 1.0f);
  return slab ? 1.0f - back : front;
}

// A 32×32 direct-lit frame: what the injection tests render for the shadow maps.
RenderSettings smallDirectFrame(int shadowResolution) {
  RenderSettings rs;
  rs.width = 32;
  rs.height = 32;
  rs.technique = "direct";
  rs.sets = {"shadow.resolution=" + std::to_string(shadowResolution)};
  return rs;
}

}  // namespace

TEST(VctInject, LitPlaneGetsAlbedoOverPiTimesIrradiance) {
  // A horizontal quad, albedo (0.5, 0.6, 0.7), under a directional light of irradiance (2, 3, 4)
  // at 60° from the normal; no shadow map. Every voxel it touches: L = ρ/π·E·cos θ, α = 1.
  Scene s = sunlitPlane(glm::vec3(0.5f, 0.6f, 0.7f), 0.13f,
                        glm::vec3(std::sin(M_PI / 3), -std::cos(M_PI / 3), 0.0), glm::vec3(2, 3, 4));
  s.bounds.extend(glm::vec3(0, 1, 0));
  s.bounds.extend(glm::vec3(0, -1, 0));
  cl::Context& ctx = test::context();
  DeviceScene ds(ctx, s);
  ShadowMapSet shadows = noShadowMaps(ctx);
  VoxelScene vs(ctx, s, 32);
  vs.voxelize(ds);
  vs.inject(ds, shadows);
  std::vector<glm::vec4> iso = ctx.download<glm::vec4>(vs.iso());
  ctx.profiler().discard();
  glm::vec3 expected = glm::vec3(0.5f, 0.6f, 0.7f) / float(M_PI) * glm::vec3(2, 3, 4) * 0.5f;
  size_t lit = 0;
  for (size_t v = 0; v < vs.voxelCount(); ++v) {
    if (iso[v].w == 0.0f) continue;
    ++lit;
    ASSERT_NEAR(iso[v].w, 1.0f, 1e-6f);
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(iso[v][k], expected[k], 1e-4f * expected[k]) << "voxel " << v;
  }
  EXPECT_GE(lit, size_t(30 * 30));
}

TEST(VctVoxelize, RevoxelizingClearsWhatThePreviousSceneTouched) {
  // Voxelization clears only the voxels the previous one listed as occupied. A grid that held a
  // tilted lit plane and is re-voxelized with a different plane must equal, bit for bit, a fresh
  // grid voxelized with the second plane only: accumulators and injected level 0.
  auto plane = [](float y, glm::vec3 sun) {
    Scene s = sunlitPlane(glm::vec3(0.5f, 0.6f, 0.7f), y, sun, glm::vec3(2, 3, 4));
    s.bounds.extend(glm::vec3(0, 1, 0));
    s.bounds.extend(glm::vec3(0, -1, 0));
    return s;
  };
  Scene first = plane(0.37f, glm::vec3(0.3f, -1.0f, 0.2f)), second = plane(-0.21f, glm::vec3(-0.5f, -1.0f, 0.1f));
  for (glm::vec3& p : first.positions) p.y += 0.4f * p.x;  // tilted: other voxels than the second plane's
  cl::Context& ctx = test::context();
  DeviceScene dsFirst(ctx, first), dsSecond(ctx, second);
  ShadowMapSet shadows = noShadowMaps(ctx);
  VoxelScene reused(ctx, second, 32), fresh(ctx, second, 32);
  reused.voxelize(dsFirst);
  reused.inject(dsFirst, shadows);
  size_t n = reused.voxelCount();
  std::vector<uint32_t> firstAcc = ctx.download<uint32_t>(reused.accumulators());
  reused.voxelize(dsSecond);
  reused.inject(dsSecond, shadows);
  fresh.voxelize(dsSecond);
  fresh.inject(dsSecond, shadows);
  std::vector<uint32_t> accReused = ctx.download<uint32_t>(reused.accumulators());
  std::vector<uint32_t> accFresh = ctx.download<uint32_t>(fresh.accumulators());
  std::vector<glm::vec4> isoReused = ctx.download<glm::vec4>(reused.iso());
  std::vector<glm::vec4> isoFresh = ctx.download<glm::vec4>(fresh.iso());
  ctx.profiler().discard();
  size_t firstOnly = 0;
  for (size_t v = 0; v < n; ++v)
    if (firstAcc[v * GI_VOX_RECORD + GI_VOX_COUNT] > 0 && accFresh[v * GI_VOX_RECORD + GI_VOX_COUNT] == 0) ++firstOnly;
  std::printf("voxels of the first plane only: %zu\n", firstOnly);
  EXPECT_GT(firstOnly, 500u);  // the clear has something to do
  // Injection walks the occupied list: every voxel with coverage, and only those, got radiance.
  size_t covered = 0, mismatched = 0;
  for (size_t v = 0; v < n; ++v) {
    bool hasOpacity = accReused[v * GI_VOX_RECORD + GI_VOX_OPACITY] > 0;
    covered += hasOpacity;
    mismatched += hasOpacity != (isoReused[v].w > 0.0f);
  }
  EXPECT_GT(covered, 500u);
  EXPECT_EQ(mismatched, 0u);
  EXPECT_EQ(accReused, accFresh);
  ASSERT_EQ(std::memcmp(isoReused.data(), isoFresh.data(), n * sizeof(glm::vec4)), 0)
      << "level 0 differs from a fresh voxelization";
}

TEST(VctInject, LanesMatchOneVoxelAtATime) {
  // vct_inject (GI_VW occupied voxels per work-item, lane-wise resolve, lights and footprint
  // shadows) against vct_inject_voxelwise (vox_resolve, light_incident, shadow_voxel_visibility one
  // voxel at a time over the whole grid), with the frame's shadow maps: the Cornell box with its
  // spot light (one view), the same light as a point light (6 cube faces) and as a directional
  // light (orthographic view).
  cl::Context& ctx = test::context();
  cl::Program prog = ctx.buildProgram("kernels/gi/vct/voxel_light.cl");
  cl::Kernel voxelwise = prog.kernel("vct_inject_voxelwise");
  for (int variant = 0; variant < 3; ++variant) {
    Scene s = test::cornellWithSpot(true);
    ASSERT_FALSE(s.lights.empty());
    if (variant == 1) s.lights[0].type = GI_LIGHT_POINT;
    if (variant == 2) {
      s.lights[0].type = GI_LIGHT_DIRECTIONAL;
      glm::vec3 d = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
      for (int k = 0; k < 3; ++k) {
        s.lights[0].direction[k] = d[k];
        s.lights[0].intensity[k] = 2.0f;
      }
    }
    Renderer r(ctx, s, smallDirectFrame(256));
    r.renderFrame();
    const DeviceScene& ds = r.deviceScene();
    VoxelScene vs(ctx, s, 32);
    vs.voxelize(ds);
    size_t n = vs.voxelCount();
    cl::Buffer reference(ctx, n * 16);
    voxelwise.args(vs.grid(), vs.accumulators(), ds.lights, int(ds.lightCount), r.shadowMaps().viewTable,
                   r.shadowMaps().offsetTable, r.shadowMaps().depths, reference);
    ctx.launch(voxelwise, cl::NDRange::d1(cl::roundUp(n, 64), 64));
    std::vector<glm::vec4> ref = ctx.download<glm::vec4>(reference);
    // The default launch (one block of the list per work-item at this size) and 8 work-items, each
    // a run of many blocks (vct_inject's loop; CPU devices), must give the same level 0.
    vs.inject(ds, r.shadowMaps());
    std::vector<glm::vec4> lanes = ctx.download<glm::vec4>(vs.iso());
    ctx.fill(vs.iso(), 0.0f);
    vs.inject(ds, r.shadowMaps(), 8);
    std::vector<glm::vec4> runs = ctx.download<glm::vec4>(vs.iso());
    ctx.profiler().discard();
    EXPECT_EQ(0, std::memcmp(lanes.data(), runs.data(), n * sizeof(glm::vec4))) << "8 work-items vs the default launch";
    float worst = 0, largest = 0;
    size_t occupied = 0, partlyShadowed = 0;
    for (size_t v = 0; v < n; ++v) {
      occupied += ref[v].w > 0;
      for (int c = 0; c < 4; ++c) {
        worst = std::max(worst, std::abs(lanes[v][c] - ref[v][c]));
        largest = std::max(largest, std::abs(ref[v][c]));
      }
    }
    for (size_t v = 0; v < n; ++v) partlyShadowed += ref[v].x > 0.01f * largest && ref[v].x < 0.5f * largest;
    std::printf("inject, %s light: %zu occupied voxels, lanes vs one voxel at a time: max abs difference %.2e "
                "(largest %.3f)\n", variant == 0 ? "spot" : (variant == 1 ? "point" : "directional"), occupied, worst,
                largest);
    EXPECT_GT(occupied, 2000u);
    EXPECT_GT(largest, 0.0f);
    EXPECT_GT(partlyShadowed, 0u);
    EXPECT_LE(worst, 1e-5f * largest);
  }
}

namespace {

// Host mirror of kernels/common/shadow.h's shadow_voxel_view (the same float operations).
float hostVoxelVisibility(const GiView& v, const float* map, glm::vec3 centre, float h) {
  const float* m = v.view;
  float hx = h * (std::fabs(m[0]) + std::fabs(m[4]) + std::fabs(m[8]));
  float hy = h * (std::fabs(m[1]) + std::fabs(m[5]) + std::fabs(m[9]));
  float hz = h * (std::fabs(m[2]) + std::fabs(m[6]) + std::fabs(m[10]));
  auto row = [&](const float* a, int r) { return a[r] * centre.x + a[4 + r] * centre.y + a[8 + r] * centre.z + a[12 + r]; };
  float depth = -row(m, 2);
  float texel = v.orthographic ? v.texel_world_size : v.texel_world_size * std::max(depth, 0.0f);
  float front = depth - hz - 1.0f * texel;  // GI_SHADOW_DEPTH_BIAS
  float cw = row(v.view_proj, 3);
  if (cw <= 0.0f || texel <= 0.0f) return 1.0f;
  float fx = (row(v.view_proj, 0) / cw * 0.5f + 0.5f) * float(v.width);
  float fy = (0.5f - row(v.view_proj, 1) / cw * 0.5f) * float(v.height);
  float invTexel = 1.0f / texel;
  float stepX = 0.6666667f * hx * invTexel, stepY = 0.6666667f * hy * invTexel;
  float lit = 0.0f;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      float tx = fx + float(dx) * stepX, ty = fy + float(dy) * stepY;
      if (!(tx >= 0.0f && ty >= 0.0f && tx < float(v.width) && ty < float(v.height))) {
        lit += 1.0f;
        continue;
      }
      lit += front <= map[int(ty) * v.width + int(tx)] ? 1.0f : 0.0f;
    }
  return lit * (1.0f / 9.0f);
}

// A sunlit floor with a horizontal blocker 0.6 m above its x < 0 half, a sun at 17° off vertical.
Scene floorWithBlocker() {
  Scene s = sunlitPlane(glm::vec3(0.5f), 0.0f, glm::vec3(0.3f, -1.0f, 0.2f), glm::vec3(2.0f));
  s.materials.push_back(test::diffuseMaterial(0.5f, 0.5f, 0.5f));
  s.materials.back().double_sided = 1;
  test::addQuad(s, glm::vec3(-1.2f, 0.6f, 1.2f), glm::vec3(1.2f, 0, 0), glm::vec3(0, 0, -2.4f), 1);
  s.computeBounds();
  s.cameras.push_back(test::lookAtCamera(glm::vec3(0, 2.5f, 3.0f), glm::vec3(0), 0.9f));
  return s;
}

}  // namespace

TEST(VctInject, VoxelVisibilityMatchesHostMirror) {
  // The injection's shadow term (shadow_voxel_visibility: the fraction of 3×3 taps over the
  // voxel's footprint where the sun reaches the voxel's box) against a host mirror, read as the
  // ratio of each voxel's radiance injected with the shadow map and with an empty one; with the map at two
  // resolutions. The floor's own voxels are never shadowed by the floor, those under the middle
  // of the blocker's shadow get nothing, and the shadow's edge gives fractions.
  cl::Context& ctx = test::context();
  Scene s = floorWithBlocker();
  for (int resolution : {256, 2048}) {
    SCOPED_TRACE(::testing::Message() << "shadow.resolution " << resolution);
    Renderer r(ctx, s, smallDirectFrame(resolution));
    r.renderFrame();
    const DeviceScene& ds = r.deviceScene();
    VoxelScene vs(ctx, s, 32);
    vs.voxelize(ds);
    // The same views with nothing rendered in them (every depth far): every tap lit.
    ShadowMapSet clear;
    clear.viewTable = ctx.upload(r.shadowMaps().views, "views");
    clear.offsetTable = ctx.upload(r.shadowMaps().offsets, "offsets");
    clear.depths = cl::Buffer(ctx, r.shadowMaps().depths.bytes());
    ctx.fill(clear.depths, 1e30f);
    vs.inject(ds, clear);
    std::vector<glm::vec4> open = ctx.download<glm::vec4>(vs.iso());
    vs.inject(ds, r.shadowMaps());
    std::vector<glm::vec4> shadowed = ctx.download<glm::vec4>(vs.iso());
    std::vector<float> depths = ctx.download<float>(r.shadowMaps().depths);
    ctx.profiler().discard();
    const GiView& view = r.shadowMaps().views[0];
    const float* map = depths.data() + r.shadowMaps().offsets[0];
    GiVoxelGrid g = vs.grid();
    int N = g.resolution;
    size_t checked = 0, exact = 0, none = 0, full = 0, partial = 0;
    for (size_t v = 0; v < open.size(); ++v) {
      if (!(open[v].x > 1e-6f)) continue;
      glm::ivec3 cell(int(v % N), int(v / N % N), int(v / (size_t(N) * N)));
      glm::vec3 centre = glm::vec3(g.origin[0], g.origin[1], g.origin[2]) + (glm::vec3(cell) + 0.5f) * g.voxel_size;
      float host = hostVoxelVisibility(view, map, centre, 0.5f * g.voxel_size);
      float kernel = shadowed[v].x / open[v].x;
      ++checked;
      exact += std::abs(kernel - host) <= 1e-4f;
      ASSERT_LE(std::abs(kernel - host), 1.0f / 9.0f + 1e-4f) << "voxel " << v;  // one tap decided differently
      none += host == 0.0f;
      full += host == 1.0f;
      partial += host > 0.0f && host < 1.0f;
      bool floorVoxel = std::abs(centre.y) <= 0.5f * g.voxel_size + 1e-4f;
      bool deepInShadow = centre.x < -0.5f && centre.x > -0.8f && centre.z < 0.2f && centre.z > -0.5f;
      if (floorVoxel && deepInShadow) EXPECT_EQ(kernel, 0.0f) << "voxel " << v;
      if (floorVoxel && centre.x > 0.5f) EXPECT_EQ(kernel, 1.0f) << "voxel " << v;  // clear of the shadow
    }
    std::printf("voxel visibility, shadow map %d: %zu lit voxels, %zu match the host mirror exactly; %zu in shadow, "
                "%zu in full light, %zu partly\n", resolution, checked, exact, none, full, partial);
    EXPECT_GE(exact, checked * 99 / 100);
    EXPECT_GT(none, 20u);
    EXPECT_GT(full, 200u);
    EXPECT_GT(partial, 20u);
  }
}

namespace {

// Σ over level 0 of the injected radiance (r + g + b, premultiplied) of `s` on an N³ grid, the
// shadow maps at `resolution`² texels.
double injectedRadianceSum(const Scene& s, int N, int resolution) {
  cl::Context& ctx = test::context();
  Renderer r(ctx, s, smallDirectFrame(resolution));
  r.renderFrame();
  VoxelScene vs(ctx, s, N);
  vs.voxelize(r.deviceScene());
  vs.inject(r.deviceScene(), r.shadowMaps());
  std::vector<glm::vec4> level0 = ctx.download<glm::vec4>(vs.iso());
  ctx.profiler().discard();
  double sum = 0.0;
  for (const glm::vec4& v : level0) sum += double(v.x) + v.y + v.z;
  return sum;
}

// A floor with 3×3 blocks of several heights under a tilted sun.
Scene blocksUnderSun() {
  Scene s;
  s.name = "blocks";
  s.materials.push_back(test::diffuseMaterial(0.6f, 0.6f, 0.6f));
  test::addQuad(s, glm::vec3(-2, 0, 2), glm::vec3(4, 0, 0), glm::vec3(0, 0, -4), 0);
  for (int i = 0; i < 9; ++i) {
    float x0 = -1.5f + 1.2f * float(i % 3), z0 = -1.5f + 1.2f * float(i / 3), a = 0.45f, h = 0.3f + 0.25f * float(i % 4);
    test::addQuad(s, glm::vec3(x0, h, z0 + a), glm::vec3(a, 0, 0), glm::vec3(0, 0, -a), 0);      // +y
    test::addQuad(s, glm::vec3(x0 + a, 0, z0 + a), glm::vec3(0, 0, -a), glm::vec3(0, h, 0), 0);  // +x
    test::addQuad(s, glm::vec3(x0, 0, z0), glm::vec3(0, 0, a), glm::vec3(0, h, 0), 0);           // −x
    test::addQuad(s, glm::vec3(x0, 0, z0 + a), glm::vec3(a, 0, 0), glm::vec3(0, h, 0), 0);       // +z
    test::addQuad(s, glm::vec3(x0 + a, 0, z0), glm::vec3(-a, 0, 0), glm::vec3(0, h, 0), 0);      // −z
  }
  s.computeBounds();
  s.lights.push_back(test::directionalLight(glm::vec3(0.3f, -1.0f, 0.2f), glm::vec3(2.0f)));
  s.cameras.push_back(test::lookAtCamera(glm::vec3(0, 3, 4), glm::vec3(0), 0.9f));
  return s;
}

}  // namespace

TEST(VctInject, VoxelRadianceBarelyDependsOnShadowMapResolution) {
  // The injected radiance summed over the grid with coarse and fine shadow maps. The visibility is
  // taken over each voxel's whole footprint, so the map's texel size hardly matters. Measured
  // (printed): blocks on a floor under a tilted sun, 64³, 256² → 4096²: −0.6 % (the point
  // sample with a normal offset of 1.5 texels used before 3 Dec: −1.1 %); Sponza 128³ with its
  // sun, 1024² → 4096²: −1.2 % (before: −43.6 %; media needed).
  double blocks = injectedRadianceSum(blocksUnderSun(), 64, 4096) / injectedRadianceSum(blocksUnderSun(), 64, 256) - 1.0;
  std::printf("injected radiance, blocks under a sun, 64^3: shadow map 256 -> 4096 changes it by %+.2f %%\n",
              100.0 * blocks);
  EXPECT_LE(std::abs(blocks), 0.02);
  std::string why;
  std::optional<Scene> sponza = test::loadSponza(why);
  if (!sponza) GTEST_SKIP() << why;
  double change = injectedRadianceSum(*sponza, 128, 4096) / injectedRadianceSum(*sponza, 128, 1024) - 1.0;
  std::printf("injected radiance, Sponza, 128^3: shadow map 1024 -> 4096 changes it by %+.2f %%\n", 100.0 * change);
  EXPECT_LE(std::abs(change), 0.03);
}

TEST(VctMips, IsotropicMeanOfChildrenConservesPremultipliedRadiance) {
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  VoxelScene vs(ctx, s, 32);
  int N = 32, levels = vs.grid().levels;
  ASSERT_EQ(levels, 6);
  // Sparse like a voxelized scene (buildMips' contract: level 0 is zero where the occupancy bit
  // is clear): the upper half of the grid empty, every other voxel below it occupied at random,
  // so that the level-1 pass meets both parents it must skip and parents it must sum.
  std::vector<glm::vec4> level0 = randomLevel0(vs.voxelCount(), 5);
  std::mt19937 pick(11);
  for (size_t v = 0; v < level0.size(); ++v)
    if (v / (size_t(N) * N) >= size_t(N / 2) || !(pick() & 1u)) level0[v] = glm::vec4(0.0f);
  writeLevel0(ctx, vs, level0);
  vs.buildMips(false);
  std::vector<glm::vec4> iso = ctx.download<glm::vec4>(vs.iso());
  ctx.profiler().discard();
  glm::dvec4 total0(0.0);
  for (const auto& v : level0) total0 += glm::dvec4(v);
  for (int l = 1; l < levels; ++l) {
    int n = N >> l, nc = 2 * n;
    const glm::vec4* child = iso.data() + levelOffset(N, l - 1);
    const glm::vec4* parent = iso.data() + levelOffset(N, l);
    glm::dvec4 total(0.0);
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          glm::vec4 sum(0.0f);
          for (int k = 0; k < 8; ++k)
            sum += child[(size_t(2 * z + (k >> 2)) * nc + 2 * y + ((k >> 1) & 1)) * nc + 2 * x + (k & 1)];
          glm::vec4 p = parent[(size_t(z) * n + y) * n + x];
          for (int c = 0; c < 4; ++c) ASSERT_NEAR(p[c], sum[c] / 8.0f, 1e-6f) << "level " << l;
          total += glm::dvec4(p);
        }
    double scale = std::pow(8.0, l);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(total[c] * scale, total0[c], 1e-5 * total0[c]) << "level " << l;
  }
}

TEST(VctMips, AnisotropicCompositesFrontToBack) {
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  VoxelScene vs(ctx, s, 32);
  int N = 32, levels = vs.grid().levels;
  std::vector<glm::vec4> level0 = randomLevel0(vs.voxelCount(), 6);
  writeLevel0(ctx, vs, level0);
  vs.buildMips(true);
  std::vector<glm::vec4> aniso = ctx.download<glm::vec4>(vs.aniso());
  ctx.profiler().discard();
  std::vector<glm::vec4> host = hostAnisotropic(level0, N, levels);
  ASSERT_EQ(aniso.size(), host.size() + VoxelScene::kChainEndRecords);
  EXPECT_EQ(aniso.back(), glm::vec4(0.0f));  // the chain's end record
  float worst = 0;
  for (size_t i = 0; i < host.size(); ++i)
    for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(aniso[i][c] - host[i][c]));
  EXPECT_LT(worst, 1e-6f);
  // A wall along x: seen along ±x it is opaque at every level (α = 1), across it (±y) thin.
  std::vector<glm::vec4> wall(vs.voxelCount(), glm::vec4(0.0f));
  for (int z = 0; z < N; ++z)
    for (int y = 0; y < N; ++y)
      for (int x = 16; x < 18; ++x) wall[(size_t(z) * N + y) * N + x] = glm::vec4(0.5f, 0.5f, 0.5f, 1.0f);
  writeLevel0(ctx, vs, wall);
  vs.buildMips(true);
  aniso = ctx.download<glm::vec4>(vs.aniso());
  ctx.profiler().discard();
  HostMips h;
  h.N = N;
  // Level 1 voxel x = 8 holds the whole wall thickness: opaque along x.
  EXPECT_FLOAT_EQ(aniso[h.anisoOffset(1, 0) + 8].w, 1.0f);
  EXPECT_FLOAT_EQ(aniso[h.anisoOffset(2, 0) + 4].w, 1.0f);  // level 2 voxel x = 4 (x 16..19) along +x: opaque
  EXPECT_FLOAT_EQ(aniso[h.anisoOffset(2, 2) + 4].w, 0.5f);  // along +y: half its columns blocked
}

TEST(VctCone, EmptyGridAccumulatesNothingAndSolidWallSaturates) {
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  VoxelScene vs(ctx, s, 32);
  int N = 32;
  std::vector<glm::vec4> grid(vs.voxelCount(), glm::vec4(0.0f));
  writeLevel0(ctx, vs, grid);
  vs.buildMips(false);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  std::vector<glm::vec4> cones, dirs;
  for (int i = 0; i < 256; ++i) {
    glm::vec3 d = glm::normalize(glm::vec3(U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f) + glm::vec3(1e-3f));
    cones.emplace_back(U(rng) * N, U(rng) * N, U(rng) * N, 0.05f + U(rng));
    dirs.emplace_back(d, 64.0f);
  }
  TraceParams tp;
  ConeOut empty = traceCones(vs, tp, cones, dirs);
  for (size_t i = 0; i < cones.size(); ++i) {
    ASSERT_EQ(empty.radiance[i], glm::vec4(0.0f));
    ASSERT_EQ(empty.occlusion[i], 0.0f);
  }
  // A solid wall (x in [16, 20), every y and z) of radiance (1, 2, 3): cones from x = 4 along +x.
  glm::vec3 L(1, 2, 3);
  for (int z = 0; z < N; ++z)
    for (int y = 0; y < N; ++y)
      for (int x = 16; x < 20; ++x) grid[(size_t(z) * N + y) * N + x] = glm::vec4(L, 1.0f);
  writeLevel0(ctx, vs, grid);
  float wideOpacity[2] = {0, 0};
  for (bool an : {false, true}) {
    vs.buildMips(an);
    tp.anisotropic = an;
    cones.assign(1, glm::vec4(4.0f, 16.0f, 16.0f, 0.05f));
    dirs.assign(1, glm::vec4(1.0f, 0.0f, 0.0f, 64.0f));
    cones.emplace_back(4.0f, 16.0f, 16.0f, std::tan(float(M_PI) / 6));  // a 60° diffuse cone
    dirs.emplace_back(1.0f, 0.0f, 0.0f, 64.0f);
    ConeOut wall = traceCones(vs, tp, cones, dirs);
    for (size_t i = 0; i < 2; ++i) {
      std::printf("%s, cone tan %.2f into a 4-voxel wall: a = %.4f, radiance (%.3f %.3f %.3f)\n",
                  an ? "anisotropic" : "isotropic", cones[i].w, wall.radiance[i].w, wall.radiance[i].x,
                  wall.radiance[i].y, wall.radiance[i].z);
    }
    // The narrow cone reads the wall at fine levels: saturated, radiance L.
    EXPECT_GE(wall.radiance[0].w, 0.99f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(wall.radiance[0][c], L[c], 0.011f * L[c]);
    // The 60° cone reads it at levels 3-4, where the isotropic average dilutes the 4-voxel wall
    // with empty space (the method's under-occlusion, docs/techniques/vct.md); the anisotropic
    // volumes composite it front to back and keep more of its opacity.
    wideOpacity[an] = wall.radiance[1].w;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(wall.radiance[1][c], L[c] * wall.radiance[1].w, 1e-3f * L[c]);
  }
  EXPECT_GT(wideOpacity[1], wideOpacity[0] + 0.2f);
}

TEST(VctCone, MarchMatchesHostMirror) {
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  VoxelScene vs(ctx, s, 32);
  HostMips h;
  h.N = 32;
  h.levels = vs.grid().levels;
  std::vector<glm::vec4> level0 = randomLevel0(vs.voxelCount(), 9);
  for (auto& v : level0) v *= 0.3f;  // keep cones from saturating in a step or two
  writeLevel0(ctx, vs, level0);
  std::vector<glm::vec4> cones, dirs;
  randomCones(200, 4, cones, dirs);
  for (bool an : {false, true}) {
    vs.buildMips(an);
    h.iso = ctx.download<glm::vec4>(vs.iso());
    if (an) h.aniso = ctx.download<glm::vec4>(vs.aniso());
    for (bool edge : {false, true}) {  // vct.border=zero / edge
      h.borderEdge = edge;
      TraceParams tp;
      tp.anisotropic = an;
      tp.stepFactor = 0.4f;
      ConeOut dev = traceCones(vs, tp, cones, dirs, false, edge);
      float worst = 0;
      for (size_t i = 0; i < cones.size(); ++i) {
        glm::vec4 ref = h.cone(glm::vec3(cones[i]), glm::vec3(dirs[i]), cones[i].w, dirs[i].w, tp.stepFactor, an);
        for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(ref[c] - dev.radiance[i][c]));
      }
      std::printf("%s cones, border %s, vs host march: max abs difference %.2e\n", an ? "anisotropic" : "isotropic",
                  edge ? "edge" : "zero", worst);
      EXPECT_LT(worst, 2e-4f);
    }
  }
}

TEST(VctCone, BorderEdgeShowsAWallAtTheBorderWhole) {
  // A lit opaque wall in the grid's last voxel layer (x = N − 1) and a wide cone (tan ½θ = 0.6)
  // along +x from the far side of the grid, anisotropic mips (which keep the wall opaque along x
  // at every level; isotropic ones dilute a one-voxel wall anyway, vct.md point 5): the cone's
  // last sample, at level 5 (one voxel), reaches past the border. With vct.border=zero the taps
  // past it are empty and dilute the wall: the cone leaves the grid unsaturated. With edge they
  // repeat the wall: the cone saturates (a ≥ 0.99) and carries the wall's radiance.
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  const int N = 32;
  VoxelScene vs(ctx, s, N);
  std::vector<glm::vec4> level0(size_t(N) * N * N, glm::vec4(0.0f));
  for (int z = 0; z < N; ++z)
    for (int y = 0; y < N; ++y) level0[(size_t(z) * N + y) * N + N - 1] = glm::vec4(0.5f, 0.4f, 0.3f, 1.0f);
  writeLevel0(ctx, vs, level0);
  std::vector<glm::vec4> cones = {glm::vec4(2.0f, 16.0f, 16.0f, 0.6f)}, dirs = {glm::vec4(1, 0, 0, 64.0f)};
  vs.buildMips(true);
  TraceParams tp;
  tp.anisotropic = 1;
  tp.specularLevelSteps = 1;  // vct_trace_cones: the level-aligned march
  glm::vec4 zero = traceCones(vs, tp, cones, dirs, false, false).radiance[0];
  glm::vec4 edge = traceCones(vs, tp, cones, dirs, false, true).radiance[0];
  std::printf("cone into a wall at the border: border zero a = %.3f, radiance %.3f; edge a = %.3f, radiance %.3f "
              "(wall 0.5)\n", zero.w, zero.x, edge.w, edge.x);
  EXPECT_LT(zero.w, 0.9f);
  EXPECT_GE(edge.w, 0.99f);
  EXPECT_NEAR(edge.x / edge.w, 0.5f, 0.01f);
}

TEST(Vct, FramesAreBitIdentical) {
  CornellOptions o;
  o.withAreaLight = false;
  o.spotLight = CornellSpotLight{};
  Scene s = makeCornellBox(o);
  const std::vector<std::vector<std::string>> modes = {
      {"vct.mips=isotropic"},
      {"vct.mips=anisotropic"},
      {"vct.mips=anisotropic", "vct.voxels=sh"},
      {"vct.mips=anisotropic", "vct.voxels=directional"},
      {"vct.mips=anisotropic", "vct.voxels=directional_slab"}};
  for (const std::vector<std::string>& mode : modes) {
    std::vector<std::vector<float>> images;
    for (int run = 0; run < 2; ++run) {
      RenderSettings rs;
      rs.width = 48;
      rs.height = 48;
      rs.technique = "vct";
      rs.sets = {"vct.resolution=64", "vct.bounces=2", "shadow.resolution=256"};
      rs.sets.insert(rs.sets.end(), mode.begin(), mode.end());
      Renderer r(test::context(), s, rs);
      r.renderFrame();
      images.push_back(r.indirectRadiance().pixels);
    }
    double sum = 0;
    for (float v : images[0]) sum += v;
    EXPECT_GT(sum, 0.0);
    EXPECT_EQ(0, std::memcmp(images[0].data(), images[1].data(), images[0].size() * sizeof(float))) << mode.back();
  }
}

TEST(Vct, EachBounceAddsOneSmallerOrderOfLight) {
  // L_k = L_direct + T·L_(k−1): the indirect light grows with k by increments that shrink (every
  // order is attenuated by albedo < 1 and the cones' losses). Re-injecting on top of the previous
  // bounce instead of the direct light (counting orders twice) would make the increments grow.
  Scene s = test::cornellWithSpot(true);
  std::vector<double> mean;
  for (int bounces = 1; bounces <= 4; ++bounces)
    mean.push_back(vctIndirectSum(s, {"vct.resolution=32", "vct.specular=0", "vct.bounces=" + std::to_string(bounces),
                                      "shadow.resolution=256"}));
  for (int k = 1; k < 4; ++k) {
    double inc = mean[k] - mean[k - 1];
    std::printf("bounces %d: indirect sum %.4f (+%.4f)\n", k + 1, mean[k], inc);
    EXPECT_GT(inc, 0.0) << "bounce " << k + 1;
    if (k > 1) EXPECT_LT(inc, mean[k - 1] - mean[k - 2]) << "bounce " << k + 1;
  }
}

TEST(VctCone, FootprintInFrontKeepsALitPlaneFromLightingItself) {
  // A lone sunlit plane cannot light itself: the path tracer's indirect light on it is exactly 0.
  // The cones' coarse samples reach back into the plane's own voxels (self-illumination: the
  // default march gathers part of the plane's radiance); with vct.footprint_in_front the sampled
  // footprint stays in front of the surface and gathers nothing.
  Scene s = lonePlaneSeenFromAbove();
  double indirect[2];
  for (int inFront = 0; inFront < 2; ++inFront)
    indirect[inFront] = vctIndirectSum(s, {"vct.resolution=32", "vct.specular=0",
                                           std::string("vct.footprint_in_front=") + (inFront ? "1" : "0")});
  std::printf("lit plane, indirect light on itself (sum over the image): default %.4f, footprint in front %.6f\n",
              indirect[0], indirect[1]);
  EXPECT_GT(indirect[0], 1.0);
  EXPECT_EQ(indirect[1], 0.0);
}

// ---- SH voxels (vct.voxels=sh, seed 003 §3.4.5) -----------------------------------------------

namespace {

// Host values of the two lobes (voxel_types.h), from their definitions: the l <= 1 projection of
// L on the front hemisphere is (2π·Y00, π·Y1·n) = (√π, √(3π)/2·n); of max(0, n·ω) it is
// (√π/2, √(π/3)·n).
const glm::vec2 kHemisphereLobe(std::sqrt(float(M_PI)), std::sqrt(3.0f * float(M_PI)) / 2.0f);
const glm::vec2 kCosineLobe(std::sqrt(float(M_PI)) / 2.0f, std::sqrt(float(M_PI) / 3.0f));

}  // namespace

TEST(VctShVoxels, ProjectionIsTheLobeOfTheVoxelSurface) {
  // Two horizontal strips under a sun at 60° from the vertical: x < 0 one-sided, facing up (+y);
  // x > 0.2 two-sided (the same quad with both windings: the normals cancel). Every occupied voxel
  // must hold L·α·(k0, k1·n_y, k1·n_z, k1·n_x) per channel, or (2·k0, 0, 0, 0) where two-sided.
  Scene s;
  s.name = "strips";
  s.materials.push_back(test::diffuseMaterial(0.5f, 0.6f, 0.7f));
  const float y = 0.13f;
  test::addTriangle(s, {-1, y, -1}, {-1, y, 1}, {0, y, 1}, 0);
  test::addTriangle(s, {-1, y, -1}, {0, y, 1}, {0, y, -1}, 0);
  for (int side = 0; side < 2; ++side) {
    glm::vec3 a(0.2f, y, -1), b(0.2f, y, 1), c(1, y, 1), d(1, y, -1);
    if (side == 0) {
      test::addTriangle(s, a, b, c, 0);
      test::addTriangle(s, a, c, d, 0);
    } else {
      test::addTriangle(s, a, c, b, 0);
      test::addTriangle(s, a, d, c, 0);
    }
  }
  s.computeBounds();
  s.bounds.extend(glm::vec3(0, 1, 0));
  s.bounds.extend(glm::vec3(0, -1, 0));
  GiLight sun{};
  sun.type = GI_LIGHT_DIRECTIONAL;
  glm::vec3 dir = glm::normalize(glm::vec3(std::sin(M_PI / 3), -std::cos(M_PI / 3), 0.0));
  for (int k = 0; k < 3; ++k) {
    sun.direction[k] = dir[k];
    sun.intensity[k] = 2.0f + k;
  }
  sun.shadow_map = -1;
  s.lights.push_back(sun);
  cl::Context& ctx = test::context();
  DeviceScene ds(ctx, s);
  ShadowMapSet shadows = noShadowMaps(ctx);
  VoxelScene vs(ctx, s, 32);
  vs.voxelize(ds);
  vs.inject(ds, shadows);
  const GiVoxelGrid& g = vs.grid();
  int N = g.resolution;
  for (ShLobe lobe : {ShLobe::Hemisphere, ShLobe::Cosine}) {
    vs.projectSh(lobe);
    std::vector<glm::vec4> iso = ctx.download<glm::vec4>(vs.iso()), sh = ctx.download<glm::vec4>(vs.sh());
    ctx.profiler().discard();
    glm::vec2 k = lobe == ShLobe::Hemisphere ? kHemisphereLobe : kCosineLobe;
    size_t oneSided = 0, twoSided = 0;
    for (size_t v = 0; v < vs.voxelCount(); ++v) {
      if (iso[v].w == 0.0f) {
        for (int ch = 0; ch < 3; ++ch) ASSERT_EQ(sh[3 * v + ch], glm::vec4(0.0f)) << "empty voxel " << v;
        continue;
      }
      float x = g.origin[0] + (float(v % N) + 0.5f) * g.voxel_size;
      ASSERT_TRUE(x < 0.05f || x > 0.15f) << "voxel " << v << " between the strips";
      bool both = x > 0.1f;
      (both ? twoSided : oneSided)++;
      glm::vec4 lobeN = both ? glm::vec4(2.0f * k.x, 0, 0, 0) : glm::vec4(k.x, k.y, 0, 0);  // n = +y
      for (int ch = 0; ch < 3; ++ch)
        for (int c = 0; c < 4; ++c)
          ASSERT_NEAR(sh[3 * v + ch][c], iso[v][ch] * lobeN[c], 2e-5f * iso[v][ch]) << "voxel " << v << " channel " << ch;
    }
    EXPECT_GE(oneSided, size_t(15 * 30));
    EXPECT_GE(twoSided, size_t(12 * 30));
  }
  // What the hemisphere lobe is for: the irradiance its l <= 1 reconstruction gives a plane facing
  // the voxel is exactly π·L (host quadrature: ∫ max(0, f(ω))·cos dω over the facing hemisphere).
  double E = 0;
  const int M = 2000;
  for (int i = 0; i < M; ++i) {
    double mu = (i + 0.5) / M;  // cosine between the arriving light's reverse direction and the voxel normal
    double f = kHemisphereLobe.x * 0.282095 + kHemisphereLobe.y * 0.488603 * mu;
    E += 2.0 * M_PI * std::max(f, 0.0) * mu / M;
  }
  EXPECT_NEAR(E, M_PI, 1e-4);
}

TEST(VctShVoxels, MipsMatchHostFilters) {
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  VoxelScene vs(ctx, s, 32);
  int N = 32, levels = vs.grid().levels;
  std::vector<glm::vec4> level0 = randomLevel0(vs.voxelCount(), 12);
  std::vector<glm::vec4> shLevel0 = randomShLevel0(level0, 13);
  writeLevel0(ctx, vs, level0);
  ctx.fill(vs.accumulators(), 0u);
  vs.projectSh(ShLobe::Hemisphere);  // allocates; level 0 is then replaced by the random one
  ctx.write(vs.sh(), shLevel0.data(), shLevel0.size() * 16);
  for (bool an : {false, true}) {
    vs.buildMips(an);
    vs.buildShMips(an);
    std::vector<glm::vec4> device = ctx.download<glm::vec4>(an ? vs.shAniso() : vs.sh());
    // The chains' zero end records (VoxelScene::kChainEndRecords) hold no voxels.
    size_t end = VoxelScene::kChainEndRecords;
    for (size_t i = device.size() - 3 * end; i < device.size(); ++i) EXPECT_EQ(device[i], glm::vec4(0.0f));
    device.resize(device.size() - 3 * end);
    std::vector<glm::vec4> radianceAniso;
    if (an) {
      radianceAniso = ctx.download<glm::vec4>(vs.aniso());
      radianceAniso.resize(radianceAniso.size() - end);
    }
    std::vector<glm::vec4> host =
        an ? hostShAnisotropic(shLevel0, level0, radianceAniso, N, levels) : hostShIsotropic(shLevel0, N, levels);
    ctx.profiler().discard();
    ASSERT_EQ(device.size(), host.size());
    float worst = 0;
    for (size_t i = 0; i < host.size(); ++i)
      for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(device[i][c] - host[i][c]));
    std::printf("SH voxel mips (%s) vs host: max abs difference %.2e\n", an ? "anisotropic" : "isotropic", worst);
    EXPECT_LT(worst, 1e-6f);
  }
}

TEST(VctShVoxels, MarchMatchesHostMirror) {
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  VoxelScene vs(ctx, s, 32);
  HostMips h;
  h.N = 32;
  h.levels = vs.grid().levels;
  h.shVoxels = true;
  std::vector<glm::vec4> level0 = randomLevel0(vs.voxelCount(), 14);
  for (auto& v : level0) v *= 0.3f;  // keep cones from saturating in a step or two
  std::vector<glm::vec4> shLevel0 = randomShLevel0(level0, 15);
  writeLevel0(ctx, vs, level0);
  ctx.fill(vs.accumulators(), 0u);
  vs.projectSh(ShLobe::Hemisphere);  // allocates; level 0 is then replaced by the random one
  ctx.write(vs.sh(), shLevel0.data(), shLevel0.size() * 16);
  std::vector<glm::vec4> cones, dirs;
  randomCones(200, 16, cones, dirs);
  for (bool an : {false, true}) {
    vs.buildMips(an);
    vs.buildShMips(an);
    h.iso = ctx.download<glm::vec4>(vs.iso());
    h.sh = ctx.download<glm::vec4>(vs.sh());
    if (an) {
      h.aniso = ctx.download<glm::vec4>(vs.aniso());
      h.shAniso = ctx.download<glm::vec4>(vs.shAniso());
    }
    TraceParams tp;
    tp.anisotropic = an;
    tp.stepFactor = 0.4f;
    ConeOut dev = traceCones(vs, tp, cones, dirs, true);
    float worst = 0, largest = 0;
    for (size_t i = 0; i < cones.size(); ++i) {
      glm::vec4 ref = h.cone(glm::vec3(cones[i]), glm::vec3(dirs[i]), cones[i].w, dirs[i].w, tp.stepFactor, an);
      for (int c = 0; c < 4; ++c) {
        worst = std::max(worst, std::abs(ref[c] - dev.radiance[i][c]));
        largest = std::max(largest, std::abs(ref[c]));
      }
    }
    std::printf("SH voxel cones (%s mips) vs host march: max abs difference %.2e (largest value %.3f)\n",
                an ? "anisotropic" : "isotropic", worst, largest);
    EXPECT_GT(largest, 0.1f);
    EXPECT_LT(worst, 2e-4f);
  }
}

TEST(VctShVoxels, WallLightsConesFromItsFrontOnly) {
  // A solid wall (x in [16, 20)) of radiance L whose surface faces −x (towards cones from x = 4
  // travelling along +x) or +x (away from them). Facing the cones it shows, through the hemisphere
  // lobe's l <= 1 reconstruction seen head-on, 0.5 + 0.75 = 1.25 × L (per unit accumulated
  // opacity); turned away, −0.25 × L clamped to 0. Narrow and 60° cones, both mip filters.
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  VoxelScene vs(ctx, s, 32);
  int N = 32;
  glm::vec3 L(1, 2, 3);
  std::vector<glm::vec4> level0(vs.voxelCount(), glm::vec4(0.0f));
  for (int z = 0; z < N; ++z)
    for (int y = 0; y < N; ++y)
      for (int x = 16; x < 20; ++x) level0[(size_t(z) * N + y) * N + x] = glm::vec4(L, 1.0f);
  writeLevel0(ctx, vs, level0);
  ctx.fill(vs.accumulators(), 0u);
  vs.projectSh(ShLobe::Hemisphere);  // allocates; level 0 is then written below
  std::vector<glm::vec4> cones = {glm::vec4(4.0f, 16.0f, 16.0f, 0.05f), glm::vec4(4.0f, 16.0f, 16.0f, std::tan(float(M_PI) / 6))};
  std::vector<glm::vec4> dirs(2, glm::vec4(1.0f, 0.0f, 0.0f, 64.0f));
  for (float facing : {-1.0f, 1.0f}) {
    std::vector<glm::vec4> shLevel0(3 * level0.size(), glm::vec4(0.0f));
    for (size_t v = 0; v < level0.size(); ++v)
      for (int ch = 0; ch < 3; ++ch)
        shLevel0[3 * v + ch] = level0[v][ch] * glm::vec4(kHemisphereLobe.x, 0, 0, kHemisphereLobe.y * facing);
    ctx.write(vs.sh(), shLevel0.data(), shLevel0.size() * 16);
    for (bool an : {false, true}) {
      vs.buildMips(an);
      vs.buildShMips(an);
      TraceParams tp;
      tp.anisotropic = an;
      ConeOut wall = traceCones(vs, tp, cones, dirs, true);
      ctx.profiler().discard();
      for (size_t i = 0; i < 2; ++i) {
        glm::vec4 r = wall.radiance[i];
        std::printf("SH wall facing %s, %s, cone tan %.2f: a = %.4f, radiance (%.3f %.3f %.3f)\n",
                    facing < 0 ? "the cone" : "away", an ? "anisotropic" : "isotropic", cones[i].w, r.w, r.x, r.y, r.z);
        if (i == 0) EXPECT_GE(r.w, 0.99f);
        EXPECT_GT(r.w, 0.1f);
        float expected = facing < 0 ? 1.25f : 0.0f;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(r[c], expected * L[c] * r.w, 1e-3f * L[c]);
      }
    }
  }
}

TEST(VctShVoxels, LitPlaneBarelyLightsItself) {
  // The lone sunlit plane of FootprintInFrontKeepsALitPlaneFromLightingItself (reference: no
  // indirect light at all). With isotropic voxels the wide cones gather the plane's own radiance;
  // SH voxels seen from above their surface at the cones' angles show little (hemisphere lobe:
  // 0.5 − 0.75·cos 60° = 1/8 of L in the side cones, nothing in the cone along n) or nothing
  // (ten Brug's cosine lobe: 0.25 − 0.5·cos 60° = 0).
  Scene s = lonePlaneSeenFromAbove();
  std::vector<std::string> common = {"vct.resolution=32", "vct.specular=0", "vct.mips=isotropic"};
  auto with = [&](std::vector<std::string> more) {
    more.insert(more.end(), common.begin(), common.end());
    return vctIndirectSum(s, more);
  };
  double isotropic = with({}), hemisphere = with({"vct.voxels=sh"}),
         cosine = with({"vct.voxels=sh", "vct.sh_lobe=cosine"});
  std::printf("lit plane, indirect light on itself (image sum): isotropic voxels %.4f, SH hemisphere %.4f (%.1f %%), "
              "SH cosine %.6f\n", isotropic, hemisphere, 100.0 * hemisphere / isotropic, cosine);
  EXPECT_GT(isotropic, 1.0);
  EXPECT_GT(hemisphere, 0.0);
  EXPECT_LT(hemisphere, 0.2 * isotropic);
  EXPECT_LT(cosine, 0.01 * isotropic);
}

TEST(VctCone, DiffuseLanesMatchOneConeAtATime) {
  // vct_diffuse marches GI_VW pixels per work-item with one shared step schedule (cone_lanes.h);
  // it must give what the one-cone-at-a-time march (cone.h) gives at the same points, for every
  // voxel kind, mip filter, footprint mode and AO. A 37×5 "G-buffer" (37 is no multiple of the
  // lane count), every 7th pixel background; albedo π so that the output L = ρ/π·E is E. Two
  // layouts: random points and normals, where the lanes' lookups read different cells; and a
  // surface, neighbouring pixels 0.06 voxels apart with normals near an axis (a different axis
  // and sign every 4 columns) jittered by ±0.03, so that the lanes' stencils differ by at most a
  // cell and their directions' near-zero components differ in sign: the lookups the lanes share
  // (facing the same or opposite ways) and the window lookups (cone_lanes.h).
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  VoxelScene vs(ctx, s, 32), vsDirectional(ctx, s, 32, VoxelScene::Directional::Plane);
  const GiVoxelGrid& g = vs.grid();
  std::vector<glm::vec4> level0 = randomLevel0(vs.voxelCount(), 21);
  for (auto& v : level0) v *= 0.3f;
  std::vector<glm::vec4> shLevel0 = randomShLevel0(level0, 22);
  writeLevel0(ctx, vs, level0);
  ctx.fill(vs.accumulators(), 0u);
  vs.projectSh(ShLobe::Hemisphere);
  ctx.write(vs.sh(), shLevel0.data(), shLevel0.size() * 16);
  writeLevel0(ctx, vsDirectional, level0);
  writeNormals(ctx, vsDirectional, level0, randomNormals(level0, 24));
  const int W = 37, H = 5, count = W * H;
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  std::vector<glm::vec4> albedo(count, glm::vec4(float(M_PI), float(M_PI), float(M_PI), 0));
  cl::Buffer bAlb = ctx.upload(albedo, "albedo");
  cl::Buffer lanesOut(ctx, count * 16), scalarOut(ctx, count * 16);
  for (int surface = 0; surface < 2; ++surface) {
    std::vector<glm::vec4> pos(count), nrm(count);
    glm::vec3 origin(g.origin[0], g.origin[1], g.origin[2]);
    for (int i = 0; i < count; ++i) {
      glm::vec3 p, n;
      if (surface) {
        int u = i % W, v = i / W, axis = (u / 4) % 3;
        p = origin + (glm::vec3(13.3f, 14.6f, 15.2f) + 0.06f * glm::vec3(u, v, u + v)) * g.voxel_size;
        n = glm::vec3(U(rng), U(rng), U(rng)) * 0.06f - 0.03f;
        n[axis] = (u / 12) % 2 ? -1.0f : 1.0f;
      } else {
        p = origin + glm::vec3(2 + 28 * U(rng), 2 + 28 * U(rng), 2 + 28 * U(rng)) * g.voxel_size;
        n = glm::vec3(U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f) + glm::vec3(1e-3f);
      }
      pos[i] = glm::vec4(p, i % 7 == 3 ? 0.0f : 1.0f);
      nrm[i] = glm::vec4(glm::normalize(n), 0);
    }
    cl::Buffer bPos = ctx.upload(pos, "positions"), bNrm = ctx.upload(nrm, "normals");
    // The device's lane count, and 1 (the GPU code path).
    for (int lanes : {cl::gatherVectorWidth(ctx), 1}) {
      // Voxel kinds: 0 isotropic, 1 SH, 2 directional (anisotropic mips only), 3 isotropic with
      // vct.border=edge (the lookups' positions clamped in the stencil, vct_stencil_lanes).
      for (int kind = 0; kind < 4; ++kind) {
        int sh = kind == 1, directional = kind == 2, edge = kind == 3;
        VoxelScene& v = directional ? vsDirectional : vs;
        cl::Program prog = ctx.buildProgram("kernels/gi/vct/cone_trace.cl",
                                            {{"GI_VCT_CONES", "6"}, {"GI_DOWN", "1"}, {"GI_VCT_SH", sh ? "1" : "0"},
                                             {"GI_VCT_DIRECTIONAL", directional ? "1" : "0"},
                                             {"GI_VCT_BORDER_EDGE", edge ? "1" : "0"},
                                             {"GI_VW", std::to_string(lanes)}});
        cl::Kernel diffuse = prog.kernel("vct_diffuse"), points = prog.kernel("vct_irradiance_points");
        for (int an = directional; an < 2; ++an) {
          v.buildMips(an);
          if (sh) v.buildShMips(an);
          const cl::Buffer& aniso = an ? v.aniso() : v.iso();
          const cl::Buffer& shIso = sh ? v.sh() : v.iso();
          const cl::Buffer& shAniso = sh && an ? v.shAniso() : shIso;
          for (int variant = 0; variant < 3; ++variant) {
            TraceParams tp;
            tp.startOffset = 1.0f;
            tp.maxDistance = 32.0f;
            tp.anisotropic = an;
            tp.footprintInFront = variant == 1;  // variant 1: footprint in front and AO
            tp.levelSteps = variant == 2;        // variant 2: the level-aligned march and AO
            tp.applyAo = variant > 0;
            tp.aoLambda = 0.1f;
            diffuse.args(g, tp, v.iso(), aniso, shIso, shAniso, W, H, W, H, bPos, bNrm, bAlb, lanesOut);
            int tileW = vctLaneTileWidth(lanes), tileH = lanes / tileW;
            ctx.launch(diffuse, cl::NDRange::d2(cl::roundUp((W + tileW - 1) / tileW, 8),
                                                cl::roundUp((H + tileH - 1) / tileH, 8), 8, 8));
            points.args(g, tp, v.iso(), aniso, shIso, shAniso, bPos, bNrm, count, scalarOut);
            ctx.launch(points, cl::NDRange::d1(cl::roundUp(count, 64), 64));
            std::vector<glm::vec4> got = ctx.download<glm::vec4>(lanesOut), ref = ctx.download<glm::vec4>(scalarOut);
            ctx.profiler().discard();
            float worst = 0, largest = 0;
            for (int i = 0; i < count; ++i) {
              glm::vec3 expected = pos[i].w == 0 ? glm::vec3(0) : glm::vec3(ref[i]) * (tp.applyAo ? ref[i].w : 1.0f);
              for (int c = 0; c < 3; ++c) {
                worst = std::max(worst, std::abs(got[i][c] - expected[c]));
                largest = std::max(largest, std::abs(expected[c]));
              }
            }
            std::printf("diffuse cones, %s, %d lanes vs one cone at a time (%s voxels, %s mips, %s): max abs "
                        "difference %.2e (largest %.3f)\n", surface ? "surface" : "random points", lanes,
                        sh ? "SH" : directional ? "directional" : "isotropic", an ? "anisotropic" : "isotropic",
                        variant == 0   ? (edge ? "continuous march, border edge" : "continuous march")
                        : variant == 1 ? (edge ? "footprint in front + AO, border edge" : "footprint in front + AO")
                                       : (edge ? "level steps + AO, border edge" : "level steps + AO"),
                        worst, largest);
            EXPECT_GT(largest, 0.05f);
            EXPECT_LT(worst, 2e-4f * std::max(1.0f, largest));
          }
        }
      }
    }
  }
}

// vct_specular (GI_VW pixels per work-item, each lane its own aperture, cone_lanes.h) on a 37×5
// "G-buffer" of random points, normals, F0 and roughness (every 7th pixel background; the output
// holds 0.1 beforehand) over `level0` with anisotropic mips: it must add what the
// one-cone-at-a-time march (vct_trace_cones) along the host's mirror directions, times the host's
// Schlick Fresnel, gives, and skipping the lookups the empty-space map shows empty must change no
// bit (the same kernel with a map that marks every cell occupied). Both marches: continuous and
// level-aligned (tp.specularLevelSteps; that march takes no map, so for it the skip comparison only
// guards that the map stays unused).
void checkSpecularLanes(const std::vector<glm::vec4>& level0, uint32_t seed, const char* label) {
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  VoxelScene vs(ctx, s, 32);
  const GiVoxelGrid& g = vs.grid();
  glm::vec3 origin(g.origin[0], g.origin[1], g.origin[2]);
  writeLevel0(ctx, vs, level0);
  vs.buildMips(true);
  vs.buildEmptySpace();
  std::vector<uint8_t> map = ctx.download<uint8_t>(vs.emptySpace());
  size_t emptyCells = std::count(map.begin(), map.end(), uint8_t(0));
  cl::Buffer noEmptySpace = ctx.upload(std::vector<uint8_t>(map.size(), 1), "no empty space");
  const int W = 37, H = 5, count = W * H;
  GiView cam{};
  glm::vec3 eye = origin + glm::vec3(16.0f, 40.0f, 16.0f) * g.voxel_size;
  for (int k = 0; k < 3; ++k) cam.eye[k] = eye[k];
  cam.width = W;
  cam.height = H;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  std::vector<glm::vec4> pos(count), nrm(count), spec(count), base(count, glm::vec4(0.1f, 0.1f, 0.1f, 0.0f));
  for (int i = 0; i < count; ++i) {
    pos[i] = glm::vec4(origin + glm::vec3(2 + 28 * U(rng), 2 + 28 * U(rng), 2 + 28 * U(rng)) * g.voxel_size,
                       i % 7 == 3 ? 0.0f : 1.0f);
    nrm[i] = glm::vec4(glm::normalize(glm::vec3(U(rng) - 0.5f, U(rng), U(rng) - 0.5f) + glm::vec3(1e-3f)), 0);
    spec[i] = glm::vec4(0.02f + U(rng), 0.02f + U(rng), 0.02f + U(rng), 0.05f + 0.95f * U(rng));
  }
  TraceParams tp;
  tp.startOffset = 1.0f;
  tp.maxDistance = 32.0f;
  tp.anisotropic = 1;
  // Host: the mirror cones and Fresnel factors of the pixels that get a specular term.
  std::vector<glm::vec4> cones, dirs;
  std::vector<int> pixel;
  std::vector<glm::vec3> fresnel;
  for (int i = 0; i < count; ++i) {
    if (pos[i].w == 0) continue;
    glm::vec3 n(nrm[i]), wo = glm::normalize(eye - glm::vec3(pos[i]));
    float nv = glm::dot(n, wo);
    if (nv <= 0) continue;
    glm::vec3 r = 2.0f * nv * n - wo;
    float rough = spec[i].w;
    cones.emplace_back((glm::vec3(pos[i]) - origin) / g.voxel_size + n * tp.startOffset, std::max(rough * rough, 1e-3f));
    dirs.emplace_back(r, tp.maxDistance);
    float m = std::clamp(1.0f - nv, 0.0f, 1.0f);
    fresnel.push_back(glm::vec3(spec[i]) + (1.0f - glm::vec3(spec[i])) * std::pow(m, 5.0f));
    pixel.push_back(i);
  }
  ASSERT_GT(pixel.size(), size_t(count / 3));
  cl::Buffer bPos = ctx.upload(pos, "positions"), bNrm = ctx.upload(nrm, "normals"), bSpec = ctx.upload(spec, "specular");
  // The continuous march, then the level-aligned one (vct_trace_cones follows tp.specularLevelSteps).
  for (int levelSteps = 0; levelSteps < 2; ++levelSteps) {
    tp.specularLevelSteps = levelSteps;
    ConeOut ref = traceCones(vs, tp, cones, dirs);
    for (int lanes : {cl::gatherVectorWidth(ctx), 1}) {
      cl::Program prog = ctx.buildProgram("kernels/gi/vct/cone_trace.cl",
                                          {{"GI_VCT_CONES", "6"}, {"GI_DOWN", "1"}, {"GI_VW", std::to_string(lanes)}});
      cl::Kernel k = prog.kernel("vct_specular");
      std::vector<glm::vec4> got[2];
      for (int skip = 0; skip < 2; ++skip) {
        cl::Buffer out = ctx.upload(base, "indirect", CL_MEM_READ_WRITE);  // the kernel adds to it
        k.args(g, tp, vs.iso(), vs.aniso(), vs.iso(), vs.iso(), skip ? vs.emptySpace() : noEmptySpace, cam, bPos, bNrm,
               bSpec, out);
        int tileW = vctLaneTileWidth(lanes), tileH = lanes / tileW;
        ctx.launch(k, cl::NDRange::d2(cl::roundUp((W + tileW - 1) / tileW, 8), cl::roundUp((H + tileH - 1) / tileH, 8), 8, 8));
        got[skip] = ctx.download<glm::vec4>(out);
        ctx.profiler().discard();
      }
      std::vector<glm::vec4> expected = base;
      for (size_t j = 0; j < pixel.size(); ++j)
        expected[pixel[j]] += glm::vec4(fresnel[j] * glm::vec3(ref.radiance[j]), 0.0f);
      float worst = 0, largest = 0;
      int changedBySkipping = 0;
      for (int i = 0; i < count; ++i)
        for (int c = 0; c < 4; ++c) {
          worst = std::max(worst, std::abs(got[1][i][c] - expected[i][c]));
          largest = std::max(largest, std::abs(expected[i][c] - base[i][c]));
          changedBySkipping += got[1][i][c] != got[0][i][c];
        }
      std::printf("specular cone, %s march, %s, %d lanes vs one cone at a time (anisotropic mips, %zu of %d pixels, "
                  "%zu of %zu map cells empty): max abs difference %.2e (largest term %.3f); %d values changed by the "
                  "empty-space skip\n", levelSteps ? "level-aligned" : "continuous", label, lanes, pixel.size(), count,
                  emptyCells, map.size(), worst, largest, changedBySkipping);
      EXPECT_GT(largest, 0.05f);
      EXPECT_LT(worst, 2e-4f * std::max(1.0f, largest));
      EXPECT_EQ(changedBySkipping, 0);
    }
  }
}

TEST(VctCone, SpecularLanesMatchOneConeAtATime) {
  std::vector<glm::vec4> level0 = randomLevel0(32 * 32 * 32, 31);
  for (auto& v : level0) v *= 0.3f;
  checkSpecularLanes(level0, 32, "random voxels (a quarter occupied)");
}

TEST(VctCone, SpecularEmptySpaceSkipChangesNothing) {
  // Mostly empty space: three walls (one lit, one 3 voxels thick and half transparent, one thin
  // at the grid's edge) and a sparse scatter of small voxels, so that most cones cross long empty
  // stretches at every level before they meet something.
  const int N = 32;
  std::vector<glm::vec4> level0(N * N * N, glm::vec4(0.0f));
  std::mt19937 rng(41);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  auto at = [&](int x, int y, int z) -> glm::vec4& { return level0[(size_t(z) * N + y) * N + x]; };
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b) {
      at(a, 30, b) = glm::vec4(0.6f, 0.5f, 0.4f, 1.0f);  // a lit ceiling
      for (int x = 5; x < 8; ++x) at(x, a, b) = glm::vec4(0.05f, 0.1f, 0.2f, 0.4f);
      at(a, b, 0) = glm::vec4(0.2f, 0.3f, 0.1f, 1.0f);
    }
  for (int k = 0; k < 60; ++k) {
    float alpha = 0.2f + 0.8f * U(rng);
    at(int(U(rng) * N) % N, int(U(rng) * N) % N, int(U(rng) * N) % N) = glm::vec4(glm::vec3(U(rng), U(rng), U(rng)) * alpha, alpha);
  }
  checkSpecularLanes(level0, 42, "mostly empty space");
}

TEST(VctMips, EmptySpaceMapMatchesHost) {
  // Per level l and cell i: 0 exactly when no occupancy bit is set under the cells i … i + 1 of
  // the level (inside the volume) — the host's count from the bits, level by level.
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  for (int N : {32, 64}) {
    VoxelScene vs(ctx, s, N);
    std::mt19937 rng(51 + N);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    std::vector<glm::vec4> level0(size_t(N) * N * N, glm::vec4(0.0f));
    for (auto& v : level0)
      if (U(rng) < 0.002f) v = glm::vec4(0.1f, 0.1f, 0.1f, 0.5f);
    level0[size_t(N) * N * N - 1] = glm::vec4(1.0f);  // the far corner
    writeLevel0(ctx, vs, level0);
    vs.buildEmptySpace();
    std::vector<uint8_t> map = ctx.download<uint8_t>(vs.emptySpace());
    ctx.profiler().discard();
    std::vector<uint8_t> occupied(level0.size());
    for (size_t v = 0; v < level0.size(); ++v) occupied[v] = level0[v] != glm::vec4(0.0f);
    size_t offset = 0, mismatches = 0, empty = 0, cells = 0;
    for (int n = N; n >= 1; n /= 2) {
      if (n < N) {  // occupied cells of this level from the level below
        std::vector<uint8_t> parent(size_t(n) * n * n, 0);
        for (int z = 0; z < 2 * n; ++z)
          for (int y = 0; y < 2 * n; ++y)
            for (int x = 0; x < 2 * n; ++x)
              parent[(size_t(z / 2) * n + y / 2) * n + x / 2] |= occupied[(size_t(z) * 2 * n + y) * 2 * n + x];
        occupied = parent;
      }
      for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) {
            uint8_t any = 0;
            for (int k = 0; k < 8; ++k) {
              int cx = x + (k & 1), cy = y + ((k >> 1) & 1), cz = z + (k >> 2);
              if (cx < n && cy < n && cz < n) any |= occupied[(size_t(cz) * n + cy) * n + cx];
            }
            uint8_t got = map[offset + (size_t(z) * n + y) * n + x];
            mismatches += got != any;
            empty += any == 0;
            ++cells;
          }
      offset += size_t(n) * n * n;
    }
    std::printf("empty-space map %d^3: %zu of %zu cells empty, %zu mismatches\n", N, empty, cells, mismatches);
    EXPECT_EQ(offset, map.size());
    EXPECT_GT(empty, cells / 2);
    EXPECT_EQ(mismatches, 0u);
  }
}

// ---- directional voxels (vct.voxels=directional) -----------------------------------------------

TEST(VctDirectionalVoxels, Level0AndMipsMatchHost) {
  // vct_directional_level0 and the anisotropic mips built on it against the host: volume dir of
  // level 0 = the isotropic (L·α, α) × the coverage of the voxel's mean normal seen along dir
  // (hostCoverage: plane and slab), every level above composited front to back per direction
  // (hostAnisotropic). Random sparse level 0 and normals (some axis-aligned, some two-sided).
  cl::Context& ctx = test::context();
  Scene s = boundsScene(glm::vec3(0), glm::vec3(1));
  for (bool slab : {false, true}) {
    VoxelScene vs(ctx, s, 32, slab ? VoxelScene::Directional::Slab : VoxelScene::Directional::Plane);
    int N = 32, levels = vs.grid().levels;
    size_t n3 = vs.voxelCount();
    std::vector<glm::vec4> level0 = randomLevel0(n3, 31);
    std::vector<glm::vec3> normals = randomNormals(level0, 32);
    writeLevel0(ctx, vs, level0);
    writeNormals(ctx, vs, level0, normals);
    vs.buildMips(true);
    std::vector<glm::vec4> aniso = ctx.download<glm::vec4>(vs.aniso());
    ctx.profiler().discard();
    std::vector<glm::vec4> host(6 * n3, glm::vec4(0.0f));
    size_t seen = 0, hidden = 0, partly = 0;
    for (int dir = 0; dir < 6; ++dir)
      for (size_t v = 0; v < n3; ++v) {
        if (level0[v] == glm::vec4(0.0f)) continue;
        float k = hostCoverage(storedNormal(normals[v]), dir, slab);
        host[dir * n3 + v] = k * level0[v];
        (k == 1.0f ? seen : k == 0.0f ? hidden : partly)++;
      }
    std::vector<glm::vec4> above = hostAnisotropic(level0, N, levels, &host);
    host.insert(host.end(), above.begin(), above.end());
    ASSERT_EQ(aniso.size(), host.size() + VoxelScene::kChainEndRecords);
    EXPECT_EQ(aniso.back(), glm::vec4(0.0f));  // the chain's end record
    float worst0 = 0, worst = 0;
    for (size_t i = 0; i < host.size(); ++i) {
      float& w = i < 6 * n3 ? worst0 : worst;
      for (int c = 0; c < 4; ++c) w = std::max(w, std::abs(aniso[i][c] - host[i][c]));
    }
    std::printf("directional level 0 (%s: %zu voxel-directions seen whole, %zu hidden, %zu partly): max abs "
                "difference %.2e; levels >= 1: %.2e\n", slab ? "slab" : "plane", seen, hidden, partly, worst0, worst);
    EXPECT_GT(hidden, 1000u);
    EXPECT_GT(partly, 1000u);
    EXPECT_LT(worst0, 1e-6f);
    EXPECT_LT(worst, 1e-6f);
  }
}

TEST(VctDirectionalVoxels, LitPlaneNeitherLightsNorOccludesConesLeavingIt) {
  // A lone sunlit plane facing up (+y), voxelized and injected (L = ρ/π·E). Cones that leave it
  // (from its surface, upwards) must gather nothing from it and not be occluded by it: nothing
  // else is in the scene, so radiance and opacity are exactly 0. Cones arriving at its front from
  // above must be blocked by it and see its radiance. Isotropic voxels for contrast: the leaving
  // cones are occluded and lit by the plane's own voxels. Then the whole technique: the plane
  // gathers no indirect light from itself (the path tracer's answer: none).
  const float y = 0.13f;
  Scene s = sunlitPlane(glm::vec3(0.8f), y, glm::vec3(0, -1, 0), glm::vec3(3.0f));
  s.bounds.extend(glm::vec3(0, 1, 0));
  s.bounds.extend(glm::vec3(0, -1, 0));
  cl::Context& ctx = test::context();
  DeviceScene ds(ctx, s);
  ShadowMapSet shadows = noShadowMaps(ctx);
  const float L = 0.8f / float(M_PI) * 3.0f;
  const float tan60 = std::tan(float(M_PI) / 6);  // the diffuse cones' half-angle
  float isotropicArriving = 0;  // opacity of the cone arriving along −n, isotropic voxels
  for (bool directional : {false, true}) {
    VoxelScene vs(ctx, s, 32, directional ? VoxelScene::Directional::Plane : VoxelScene::Directional::Off);
    vs.voxelize(ds);
    vs.inject(ds, shadows);
    vs.buildMips(true);
    const GiVoxelGrid& g = vs.grid();
    float surface = (y - g.origin[1]) / g.voxel_size;  // the plane's height in voxels
    // Leaving: from the surface at the grid's centre, along the normal and at 30°, 60° and 80°
    // from it, narrow and 60° cones. Arriving: from 10 voxels above, down along −n and at 30° and
    // 45° from it, narrow.
    std::vector<glm::vec4> cones, dirs;
    for (float tanHalf : {0.05f, tan60})
      for (float deg : {0.0f, 30.0f, 60.0f, 80.0f}) {
        float a = glm::radians(deg);
        cones.emplace_back(16.0f, surface, 16.0f, tanHalf);
        dirs.emplace_back(std::sin(a) * 0.6f, std::cos(a), std::sin(a) * 0.8f, 64.0f);
      }
    size_t leaving = cones.size();
    for (float deg : {0.0f, 30.0f, 45.0f}) {
      float a = glm::radians(deg);
      cones.emplace_back(16.0f, surface + 10.0f, 16.0f, 0.05f);
      dirs.emplace_back(std::sin(a), -std::cos(a), 0.0f, 64.0f);
    }
    TraceParams tp;
    tp.anisotropic = 1;
    ConeOut out = traceCones(vs, tp, cones, dirs);
    float leftOpacity = 0, leftRadiance = 0;
    for (size_t i = 0; i < leaving; ++i) {
      leftOpacity = std::max(leftOpacity, out.radiance[i].w);
      leftRadiance = std::max(leftRadiance, out.radiance[i].x);
    }
    std::printf("lit plane, %s voxels: cones leaving it: largest opacity %.4f, radiance %.4f (L = %.4f); arriving "
                "at 0/30/45 deg from the normal: opacity %.4f / %.4f / %.4f, radiance / opacity %.4f / %.4f / %.4f\n",
                directional ? "directional" : "isotropic", leftOpacity, leftRadiance, L, out.radiance[leaving].w,
                out.radiance[leaving + 1].w, out.radiance[leaving + 2].w, out.radiance[leaving].x / out.radiance[leaving].w,
                out.radiance[leaving + 1].x / out.radiance[leaving + 1].w,
                out.radiance[leaving + 2].x / out.radiance[leaving + 2].w);
    if (directional) {
      EXPECT_EQ(leftOpacity, 0.0f);
      EXPECT_EQ(leftRadiance, 0.0f);
    } else {
      EXPECT_GT(leftOpacity, 0.3f);
      EXPECT_GT(leftRadiance, 0.1f * L);
    }
    // Arriving along −n: the one-voxel plane occludes as much as it does as isotropic voxels (not
    // fully: the half-voxel steps' trilinear samples blend it with the empty voxels around it);
    // obliquely, the −y volume weighs cos² of the angle, the edge-on ±x volumes see nothing.
    if (directional)
      EXPECT_NEAR(out.radiance[leaving].w, isotropicArriving, 1e-6f);
    else
      isotropicArriving = out.radiance[leaving].w;
    EXPECT_GT(out.radiance[leaving].w, 0.85f);
    for (size_t i = leaving; i < cones.size(); ++i) {
      EXPECT_GT(out.radiance[i].w, 0.5f) << "arriving cone " << i - leaving;
      EXPECT_NEAR(out.radiance[i].x / out.radiance[i].w, L, 1e-3f * L) << "arriving cone " << i - leaving;
    }
  }
  double isotropic = vctIndirectSum(lonePlaneSeenFromAbove(), {"vct.resolution=32", "vct.specular=0"});
  double directional =
      vctIndirectSum(lonePlaneSeenFromAbove(), {"vct.resolution=32", "vct.specular=0", "vct.voxels=directional"});
  std::printf("lit plane, indirect light on itself (image sum): isotropic voxels %.4f, directional %.6f\n", isotropic,
              directional);
  EXPECT_GT(isotropic, 1.0);
  EXPECT_EQ(directional, 0.0);
}

TEST(VctDirectionalVoxels, NeedAnisotropicMips) {
  Scene s = lonePlaneSeenFromAbove();
  EXPECT_THROW(vctIndirectSum(s, {"vct.resolution=32", "vct.voxels=directional", "vct.mips=isotropic"}), Error);
}
