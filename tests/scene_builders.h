// Hand-built scenes for kernel tests (no files): planes and boxes with chosen materials and lights.
#pragma once
#include <glm/glm.hpp>

#include "scene/scene.h"

namespace gi::test {

inline GiMaterial diffuseMaterial(glm::vec3 albedo, float roughness = 1.0f, float metallic = 0.0f) {
  GiMaterial m{};
  m.base_color[0] = albedo.x;
  m.base_color[1] = albedo.y;
  m.base_color[2] = albedo.z;
  m.base_color[3] = 1.0f;
  m.metallic = metallic;
  m.roughness = roughness;
  m.normal_scale = 1.0f;
  m.base_color_tex = m.metallic_roughness_tex = m.normal_tex = m.emissive_tex = GI_NO_TEXTURE;
  return m;
}

// Adds the quad (corner, corner + u, corner + u + v, corner + v) facing along cross(u, v).
inline void addQuad(Scene& s, glm::vec3 corner, glm::vec3 u, glm::vec3 v, uint32_t material) {
  uint32_t base = uint32_t(s.positions.size());
  glm::vec3 n = glm::normalize(glm::cross(u, v));
  glm::vec3 p[4] = {corner, corner + u, corner + u + v, corner + v};
  glm::vec2 t[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int i = 0; i < 4; ++i) {
    s.positions.push_back(p[i]);
    s.normals.push_back(n);
    s.uvs.push_back(t[i]);
    s.tangents.emplace_back(0.0f);
  }
  uint32_t inst = s.triangleInstance.empty() ? 0 : s.triangleInstance.back() + 1;
  s.triangles.emplace_back(base, base + 1, base + 2);
  s.triangles.emplace_back(base, base + 2, base + 3);
  for (int k = 0; k < 2; ++k) {
    s.triangleMaterial.push_back(material);
    s.triangleInstance.push_back(inst);
  }
}

inline GiLight pointLight(glm::vec3 pos, glm::vec3 intensity) {
  GiLight l{};
  l.type = GI_LIGHT_POINT;
  l.position[0] = pos.x; l.position[1] = pos.y; l.position[2] = pos.z;
  l.intensity[0] = intensity.x; l.intensity[1] = intensity.y; l.intensity[2] = intensity.z;
  l.direction[1] = -1.0f;
  l.shadow_map = -1;
  return l;
}

inline GiLight directionalLight(glm::vec3 dir, glm::vec3 irradiance) {
  GiLight l{};
  l.type = GI_LIGHT_DIRECTIONAL;
  glm::vec3 d = glm::normalize(dir);
  l.direction[0] = d.x; l.direction[1] = d.y; l.direction[2] = d.z;
  l.intensity[0] = irradiance.x; l.intensity[1] = irradiance.y; l.intensity[2] = irradiance.z;
  l.shadow_map = -1;
  return l;
}

inline Camera lookAtCamera(glm::vec3 pos, glm::vec3 target, float yfovRadians = 1.0f) {
  Camera c;
  c.name = "test";
  c.position = pos;
  c.target = target;
  c.yfov = yfovRadians;
  c.znear = 0.01f;
  c.zfar = 100.0f;
  return c;
}

}  // namespace gi::test
