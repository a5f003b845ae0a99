// Tangent generation (see tangents.h for the convention and the method).
#include "scene/tangents.h"

#include <cmath>

namespace gi {

namespace {

// A unit vector orthogonal to unit vector n: the cross product with a world axis that is far from
// parallel to n, which keeps the result well conditioned.
glm::vec3 anyOrthogonal(const glm::vec3& n) {
  glm::vec3 axis = std::abs(n.x) < 0.6f ? glm::vec3(1, 0, 0) : (std::abs(n.y) < 0.6f ? glm::vec3(0, 1, 0) : glm::vec3(0, 0, 1));
  return glm::normalize(glm::cross(n, axis));
}

float cornerAngle(const glm::vec3& toA, const glm::vec3& toB) {
  float la = glm::length(toA), lb = glm::length(toB);
  if (la <= 0.0f || lb <= 0.0f) return 0.0f;
  return std::acos(glm::clamp(glm::dot(toA, toB) / (la * lb), -1.0f, 1.0f));
}

}  // namespace

std::vector<glm::vec4> generateTangents(const std::vector<glm::vec3>& positions,
                                        const std::vector<glm::vec3>& normals,
                                        const std::vector<glm::vec2>& uvs,
                                        const std::vector<glm::uvec3>& triangles) {
  std::vector<glm::vec3> alongU(positions.size(), glm::vec3(0.0f));
  std::vector<glm::vec3> alongMinusV(positions.size(), glm::vec3(0.0f));

  for (const glm::uvec3& t : triangles) {
    const glm::vec3 p[3] = {positions[t[0]], positions[t[1]], positions[t[2]]};
    const glm::vec2 uv[3] = {uvs[t[0]], uvs[t[1]], uvs[t[2]]};
    glm::vec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
    glm::vec2 d1 = uv[1] - uv[0], d2 = uv[2] - uv[0];
    float det = d1.x * d2.y - d2.x * d1.y;
    if (!(std::abs(det) > 0.0f)) continue;  // no UV gradient (collapsed or missing UVs)
    glm::vec3 dPdu = (e1 * d2.y - e2 * d1.y) / det;
    glm::vec3 dPdv = (e2 * d1.x - e1 * d2.x) / det;
    float lu = glm::length(dPdu), lv = glm::length(dPdv);
    if (!(lu > 0.0f) || !(lv > 0.0f) || !std::isfinite(lu) || !std::isfinite(lv)) continue;
    glm::vec3 tangent = dPdu / lu, bitangent = -dPdv / lv;
    for (int k = 0; k < 3; ++k) {
      float w = cornerAngle(p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
      alongU[t[k]] += w * tangent;
      alongMinusV[t[k]] += w * bitangent;
    }
  }

  std::vector<glm::vec4> tangents(positions.size());
  for (size_t v = 0; v < positions.size(); ++v) {
    const glm::vec3& n = normals[v];
    glm::vec3 t = alongU[v] - n * glm::dot(n, alongU[v]);
    float len = glm::length(t);
    if (!(len > 1e-12f)) {
      tangents[v] = glm::vec4(anyOrthogonal(n), 1.0f);
      continue;
    }
    t /= len;
    float handedness = glm::dot(glm::cross(n, t), alongMinusV[v]) < 0.0f ? -1.0f : 1.0f;
    tangents[v] = glm::vec4(t, handedness);
  }
  return tangents;
}

}  // namespace gi
