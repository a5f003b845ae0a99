// Host implementation of the light-propagation-volume formulas (ALGORITHMS.md §4), written from
// the formulas, not from the kernels, for the LPV tests: injection, geometry surfels, one
// propagation step, lookup. Layouts as in kernels/gi/lpv/lpv.cl. Float arithmetic; sums that the
// kernels do in 64-bit fixed point are done in double here.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <glm/glm.hpp>

#include "kernels/common/sh.h"
#include "gi/lpv/lpv_volume.h"

namespace gi::lpvref {

constexpr float kMainFace = 0.4006696846f, kSideFace = 0.4234413544f;
constexpr float kPi = 3.14159265358979f;

inline glm::vec4 basis(glm::vec3 d) { return {GI_SH_Y0, GI_SH_Y1 * d.y, GI_SH_Y1 * d.z, GI_SH_Y1 * d.x}; }
inline glm::vec4 lobe(glm::vec3 n) { return {GI_SH_LOBE0, GI_SH_LOBE1 * n.y, GI_SH_LOBE1 * n.z, GI_SH_LOBE1 * n.x}; }

struct Grid {
  int n = 0, cascades = 1;
  std::vector<glm::vec4> c;  // [cascade][rgb][cell]
  Grid(int n_, int k) : n(n_), cascades(k), c(size_t(3) * k * n_ * n_ * n_, glm::vec4(0.0f)) {}
  size_t cells() const { return size_t(n) * n * n; }
  size_t index(int k, int ch, glm::ivec3 p) const { return (size_t(k) * 3 + ch) * cells() + (size_t(p.z) * n + p.y) * n + p.x; }
  bool inside(glm::ivec3 p) const { return glm::all(glm::greaterThanEqual(p, glm::ivec3(0))) && glm::all(glm::lessThan(p, glm::ivec3(n))); }
};

// Geometry volume nodes on cell corners: (n + 1)³ per cascade.
inline size_t nodeIndex(int n, int k, glm::ivec3 p) {
  size_t m = size_t(n) + 1;
  return size_t(k) * m * m * m + (size_t(p.z) * m + p.y) * m + p.x;
}

// The 5 faces a neighbour lights in the destination, for light travelling along axis d.
struct Face {
  glm::vec3 eval, emit;
  float solidAngle;
};
inline std::array<Face, 5> facesFor(glm::vec3 d) {
  std::array<Face, 5> f;
  f[0] = {d, d, kMainFace};
  int j = 1;
  for (int axis = 0; axis < 3; ++axis) {
    if (d[axis] != 0.0f) continue;
    for (float sign : {1.0f, -1.0f}) {
      glm::vec3 t(0.0f);
      t[axis] = sign;
      f[j++] = {glm::normalize(2.0f * d + t), t, kSideFace};
    }
  }
  return f;
}

inline std::array<glm::vec3, 6> axes() {
  return {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)};
}

// f rounded to the nearest half-precision value (ties to even), for |f| <= 65504: the spacing of
// halves is 2^(e − 10) for |f| in [2^e, 2^(e+1)), e >= −14, and 2^−24 below (subnormals).
inline float roundToHalf(float f) {
  int e = 0;
  std::frexp(f, &e);  // |f| in [2^(e−1), 2^e)
  float spacing = std::ldexp(1.0f, std::max(e - 1, -14) - 10);
  return std::nearbyint(f / spacing) * spacing;
}

// The 4 corner nodes of the face between cell c and c + d (d an axis direction), lower one first.
inline std::array<glm::ivec3, 4> faceCorners(glm::ivec3 c, glm::vec3 d) {
  int a = d.x != 0 ? 0 : d.y != 0 ? 1 : 2;
  glm::ivec3 corner = c;
  if (d[a] > 0) corner[a] += 1;
  glm::ivec3 eu(0), ev(0);  // the face's in-plane axes, lower one first
  eu[a == 0 ? 1 : 0] = 1;
  ev[a == 2 ? 1 : 2] = 1;
  return {corner, corner + eu, corner + ev, corner + eu + ev};
}

// Blocking potential of the face between cell c and c + d: average of its 4 corner nodes, summed
// in the kernel's order and stored in half precision as lpv_face_geometry does.
inline glm::vec4 sharedFace(int n, int k, const std::vector<glm::vec4>& geometry, glm::ivec3 c, glm::vec3 d) {
  std::array<glm::ivec3, 4> q = faceCorners(c, d);
  glm::vec4 sum = geometry[nodeIndex(n, k, q[0])] + geometry[nodeIndex(n, k, q[1])];
  sum = sum + geometry[nodeIndex(n, k, q[2])];
  sum = sum + geometry[nodeIndex(n, k, q[3])];
  glm::vec4 g;
  for (int i = 0; i < 4; ++i) g[i] = roundToHalf(std::clamp(0.25f * sum[i], -65504.0f, 65504.0f));
  return g;
}

// T_f = ΔΩ_f/π · (1 − clamp(GV · Y(−ω_f), 0, 1)), stored by the device in half precision
// (lpv_face_factors).
inline float transmittance(const Face& f, glm::vec4 g) {
  return roundToHalf(f.solidAngle / kPi * (1.0f - std::clamp(glm::dot(g, basis(-f.eval)), 0.0f, 1.0f)));
}

// f(k, c, d) for every cascade k, cell c and axis direction d of `g`.
template <class F>
void forEachCellAndAxis(const Grid& g, F&& f) {
  for (int k = 0; k < g.cascades; ++k)
    for (int z = 0; z < g.n; ++z)
      for (int y = 0; y < g.n; ++y)
        for (int x = 0; x < g.n; ++x)
          for (glm::vec3 d : axes()) f(k, glm::ivec3(x, y, z), d);
}

// One gather step from `src`; `geometry` (per node, may be empty) blocks when `blocking`.
inline Grid propagate(const Grid& src, const std::vector<glm::vec4>& geometry, bool blocking) {
  Grid dst(src.n, src.cascades);
  forEachCellAndAxis(src, [&](int k, glm::ivec3 c, glm::vec3 d) {
    glm::ivec3 nb = c - glm::ivec3(d);
    if (!src.inside(nb)) return;
    glm::vec4 g = blocking ? sharedFace(src.n, k, geometry, nb, d) : glm::vec4(0.0f);
    for (const Face& f : facesFor(d)) {
      float w = blocking ? transmittance(f, g) : f.solidAngle / kPi;
      for (int ch = 0; ch < 3; ++ch) {
        float intensity = std::max(glm::dot(src.c[src.index(k, ch, nb)], basis(f.eval)), 0.0f);
        dst.c[dst.index(k, ch, c)] += intensity * w * lobe(f.emit);
      }
    }
  });
  return dst;
}

// Multiple bounces (lpv.bounces, lpv.cl lpv_reflect_blocked): the light of each cell of `src` that
// the faces to its neighbours block in a blocked step, Φ_b/π = Σ_f (ΔΩ_f/π − T_f) · max(0, I(ω_f)),
// reflected back into the cell by the blocker as ρ · Φ_b/π · lobe(n): ρ the area-weighted albedo
// of the face's 4 corner nodes (`albedo`: Σ ρ·w, Σ w per node), n the face potential's linear part
// normalized and turned towards the cell (−d where it is zero).
inline Grid reflectBlocked(const Grid& src, const std::vector<glm::vec4>& geometry, const std::vector<glm::vec4>& albedo) {
  Grid dst(src.n, src.cascades);
  forEachCellAndAxis(src, [&](int k, glm::ivec3 c, glm::vec3 d) {
    if (!src.inside(c + glm::ivec3(d))) return;  // the light leaves the grid
    glm::vec4 g = sharedFace(src.n, k, geometry, c, d);
    glm::vec4 sums(0.0);
    for (glm::ivec3 q : faceCorners(c, d)) sums += albedo[nodeIndex(src.n, k, q)];
    glm::vec3 rho = sums.w > 0.0f ? glm::vec3(sums) / sums.w : glm::vec3(0.0f);
    glm::vec3 normal(g.w, g.y, g.z);  // the linear coefficients in (y, z, x) order
    normal = glm::dot(normal, normal) > 1e-30f ? glm::normalize(normal) : -d;
    if (glm::dot(normal, d) > 0.0f) normal = -normal;
    for (int ch = 0; ch < 3; ++ch) {
      float blocked = 0.0f;
      for (const Face& f : facesFor(d)) {
        float open = f.solidAngle / kPi;
        blocked += std::max(open - transmittance(f, g), 0.0f) *
                   std::max(glm::dot(src.c[src.index(k, ch, c)], basis(f.eval)), 0.0f);
      }
      dst.c[dst.index(k, ch, c)] += rho[ch] * blocked * lobe(normal);
    }
  });
  return dst;
}

// Total flux (W) of channel ch of cascade k: ∫ I dω = 4π·Y00·c0 per cell.
inline double totalFlux(const Grid& g, int k, int ch) {
  double s = 0.0;
  for (size_t i = 0; i < g.cells(); ++i) s += g.c[(size_t(k) * 3 + ch) * g.cells() + i].x;
  return s * 4.0 * M_PI * GI_SH_Y0;
}

}  // namespace gi::lpvref
