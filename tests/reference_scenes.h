// Small procedural scenes for the Reference* tests (no file loading): a random triangle soup, a
// closed sphere seen from inside, a quad. Plain gi::Scene data, bounds computed.
#pragma once
#include <cmath>
#include <random>

#include "scene/scene.h"

namespace gi::test {

inline GiMaterial diffuseMaterial(float r, float g, float b) {
  GiMaterial m{};
  m.base_color[0] = r; m.base_color[1] = g; m.base_color[2] = b; m.base_color[3] = 1.0f;
  m.metallic = 0.0f;
  m.roughness = 1.0f;
  m.alpha_cutoff = 0.5f;
  m.normal_scale = 1.0f;
  m.alpha_mode = GI_ALPHA_OPAQUE;
  m.base_color_tex = m.metallic_roughness_tex = m.normal_tex = m.emissive_tex = GI_NO_TEXTURE;
  m.double_sided = 1;
  return m;
}

// Adds one triangle with flat normals (the geometric normal of the winding).
inline void addTriangle(Scene& s, glm::vec3 a, glm::vec3 b, glm::vec3 c, uint32_t material) {
  glm::vec3 n = glm::cross(b - a, c - a);
  float l = glm::length(n);
  n = l > 0 ? n / l : glm::vec3(0, 0, 1);
  uint32_t base = uint32_t(s.positions.size());
  for (auto p : {a, b, c}) {
    s.positions.push_back(p);
    s.normals.push_back(n);
    s.tangents.push_back(glm::vec4(0.0f));
    s.uvs.push_back(glm::vec2(0.0f));
  }
  s.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
  s.triangleMaterial.push_back(material);
  s.triangleInstance.push_back(0);
}

inline void addQuad(Scene& s, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, uint32_t material) {
  addTriangle(s, a, b, c, material);
  addTriangle(s, a, c, d, material);
}

// `count` random triangles in [-1,1]^3 of edge ~size; materials: 0 opaque, 1 alpha-masked fully
// cut out (alpha 0.3 < cutoff 0.5) for every `maskedEvery`-th triangle (0 = none).
inline Scene triangleSoup(int count, float size, uint32_t seed, int maskedEvery = 0) {
  Scene s;
  s.name = "soup";
  s.materials.push_back(diffuseMaterial(0.5f, 0.5f, 0.5f));
  GiMaterial cut = diffuseMaterial(0.5f, 0.5f, 0.5f);
  cut.alpha_mode = GI_ALPHA_MASK;
  cut.base_color[3] = 0.3f;
  s.materials.push_back(cut);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-1.0f, 1.0f);
  for (int i = 0; i < count; ++i) {
    glm::vec3 c(U(rng), U(rng), U(rng));
    glm::vec3 a = c + size * glm::vec3(U(rng), U(rng), U(rng));
    glm::vec3 b = c + size * glm::vec3(U(rng), U(rng), U(rng));
    glm::vec3 d = c + size * glm::vec3(U(rng), U(rng), U(rng));
    addTriangle(s, a, b, d, (maskedEvery > 0 && i % maskedEvery == 0) ? 1u : 0u);
  }
  s.computeBounds();
  return s;
}

// UV sphere of radius r around the origin, `rings` × 2·rings quads, vertex normals pointing
// inward (exact radial), material 0 = diffuse `albedo`.
inline Scene insideSphere(int rings, float r, float albedo) {
  Scene s;
  s.name = "furnace-sphere";
  s.materials.push_back(diffuseMaterial(albedo, albedo, albedo));
  int segs = 2 * rings;
  auto P = [&](int i, int j) {
    float th = float(M_PI) * float(i) / float(rings), ph = 2.0f * float(M_PI) * float(j) / float(segs);
    return glm::vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
  };
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j <= segs; ++j) {
      glm::vec3 p = P(i, j);
      s.positions.push_back(p * r);
      s.normals.push_back(-p);
      s.tangents.push_back(glm::vec4(0.0f));
      s.uvs.push_back(glm::vec2(float(j) / segs, float(i) / rings));
    }
  auto V = [&](int i, int j) { return uint32_t(i * (segs + 1) + j); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segs; ++j) {
      if (i > 0) {
        s.triangles.push_back(glm::uvec3(V(i, j), V(i, j + 1), V(i + 1, j)));
        s.triangleMaterial.push_back(0);
        s.triangleInstance.push_back(0);
      }
      if (i < rings - 1) {
        s.triangles.push_back(glm::uvec3(V(i, j + 1), V(i + 1, j + 1), V(i + 1, j)));
        s.triangleMaterial.push_back(0);
        s.triangleInstance.push_back(0);
      }
    }
  Camera cam;
  cam.name = "centre";
  cam.position = glm::vec3(0.0f);
  cam.target = glm::vec3(0.0f, 0.0f, -1.0f);
  cam.yfov = 1.2f;
  cam.znear = 0.01f;
  cam.zfar = 10.0f;
  s.cameras.push_back(cam);
  s.computeBounds();
  return s;
}

inline GiLight pointLight(glm::vec3 p, float intensity) {
  GiLight l{};
  l.type = GI_LIGHT_POINT;
  l.position[0] = p.x; l.position[1] = p.y; l.position[2] = p.z;
  l.direction[1] = -1.0f;
  for (int c = 0; c < 3; ++c) l.intensity[c] = intensity;
  l.cos_inner = 1.0f;
  l.cos_outer = 0.0f;
  l.falloff = GI_SPOT_FALLOFF_GLTF;
  l.shadow_map = -1;
  return l;
}

}  // namespace gi::test
