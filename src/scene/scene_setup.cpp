// Final steps shared by every scene producer (see scene_setup.h).
#include "scene/scene_setup.h"

#include <algorithm>
#include <cmath>

#include "scene/lights.h"
#include "util/error.h"

namespace gi {

Camera makeFramingCamera(const Bounds& bounds, std::string name) {
  Camera c;
  c.name = std::move(name);
  c.yfov = glm::radians(60.0f);
  float radius = std::max(bounds.radius(), 1e-3f);
  // The bounding sphere fills the vertical field of view at distance radius / sin(yfov / 2).
  float distance = radius / std::sin(0.5f * c.yfov);
  c.target = bounds.center();
  c.position = c.target + distance * glm::normalize(glm::vec3(1.0f, 0.6f, 2.0f));
  c.up = glm::vec3(0, 1, 0);
  c.znear = 0.0f;
  c.zfar = 0.0f;
  fitClipPlanes(c, bounds);
  return c;
}

void fitClipPlanes(Camera& camera, const Bounds& bounds) {
  if (camera.zfar <= 0.0f) {
    float farthest = glm::length(camera.position - bounds.center()) + bounds.radius();
    camera.zfar = std::max(1.01f * farthest, 1e-3f);
  }
  if (camera.znear <= 0.0f) camera.znear = camera.zfar * 1e-3f;
}

void finishScene(Scene& s, const std::string& what) {
  size_t vertexCount = s.positions.size();
  if (s.normals.size() != vertexCount || s.uvs.size() != vertexCount || s.tangents.size() != vertexCount)
    throw Error(what + ": internal error: per-vertex arrays differ in length");
  if (s.triangleMaterial.size() != s.triangles.size() || s.triangleInstance.size() != s.triangles.size())
    throw Error(what + ": internal error: per-triangle arrays differ in length");
  if (s.triangles.empty()) throw Error(what + ": the scene has no triangles to render");

  s.computeBounds();
  if (s.cameras.empty()) s.cameras.push_back(makeFramingCamera(s.bounds));
  for (Camera& c : s.cameras) fitClipPlanes(c, s.bounds);
  s.defaultCamera = std::clamp(s.defaultCamera, 0, int(s.cameras.size()) - 1);
  addEmissiveStandInLights(s);
}

}  // namespace gi
