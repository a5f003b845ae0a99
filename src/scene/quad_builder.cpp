// Building blocks for the scenes made in code (see quad_builder.h).
#include "scene/quad_builder.h"

#include <utility>

namespace gi {

GiMaterial makeDiffuseMaterial(const glm::vec3& albedo) {
  GiMaterial m{};
  m.base_color[0] = albedo.x;
  m.base_color[1] = albedo.y;
  m.base_color[2] = albedo.z;
  m.base_color[3] = 1.0f;
  m.metallic = 0.0f;
  m.roughness = 1.0f;
  m.alpha_cutoff = 0.5f;
  m.normal_scale = 1.0f;
  m.alpha_mode = GI_ALPHA_OPAQUE;
  m.base_color_tex = m.metallic_roughness_tex = m.normal_tex = m.emissive_tex = GI_NO_TEXTURE;
  m.double_sided = 0;
  return m;
}

uint32_t addInstance(Scene& s, const std::string& name) {
  s.instanceNames.push_back(name);
  return static_cast<uint32_t>(s.instanceNames.size() - 1);
}

void addQuad(Scene& s, Quad q, const glm::vec3& facing, uint32_t material, uint32_t instance) {
  glm::vec3 quadNormal = glm::cross(q[2] - q[0], q[3] - q[1]);
  if (glm::dot(quadNormal, facing) < 0.0f) std::swap(q[1], q[3]);
  const glm::vec2 quadUv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const glm::ivec3& corner : {glm::ivec3(0, 1, 2), glm::ivec3(0, 2, 3)}) {
    glm::vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = q[corner[k]];
    glm::vec3 n = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
    uint32_t first = static_cast<uint32_t>(s.positions.size());
    for (int k = 0; k < 3; ++k) {
      s.positions.push_back(p[k]);
      s.normals.push_back(n);
      s.uvs.push_back(quadUv[corner[k]]);
      s.tangents.push_back(glm::vec4(0.0f));
    }
    s.triangles.push_back(glm::uvec3(first, first + 1, first + 2));
    s.triangleMaterial.push_back(material);
    s.triangleInstance.push_back(instance);
  }
}

}  // namespace gi
