#include "render/views.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace gi {

GiView makeView(const glm::mat4& view, const glm::mat4& proj, int width, int height, bool orthographic,
                const glm::vec3& eye, float znear, float zfar, float texelWorldSize) {
  GiView v{};
  glm::mat4 vp = proj * view;
  glm::mat4 inv = glm::inverse(vp);
  std::memcpy(v.view_proj, glm::value_ptr(vp), sizeof v.view_proj);
  std::memcpy(v.inv_view_proj, glm::value_ptr(inv), sizeof v.inv_view_proj);
  std::memcpy(v.view, glm::value_ptr(view), sizeof v.view);
  v.eye[0] = eye.x; v.eye[1] = eye.y; v.eye[2] = eye.z;
  v.orthographic = orthographic ? 1 : 0;
  v.width = width;
  v.height = height;
  v.cull_backfaces = 1;
  v.texel_world_size = texelWorldSize;
  v.znear = znear;
  v.zfar = zfar;
  return v;
}

namespace {
glm::vec3 pickUp(const glm::vec3& forward) {
  return std::fabs(forward.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
}
}  // namespace

GiView makeCameraView(const Camera& c, int width, int height) {
  glm::vec3 fwd = glm::normalize(c.target - c.position);
  glm::vec3 up = glm::length(glm::cross(fwd, c.up)) > 1e-6f ? c.up : pickUp(fwd);
  glm::mat4 view = glm::lookAt(c.position, c.target, up);
  float aspect = float(width) / float(height);
  glm::mat4 proj = glm::perspective(c.yfov, aspect, c.znear, c.zfar);
  return makeView(view, proj, width, height, false, c.position, c.znear, c.zfar,
                  2.0f * std::tan(0.5f * c.yfov) / float(height));
}

GiView makeDirectionalLightView(const glm::vec3& direction, const Bounds& b, int size) {
  glm::vec3 d = glm::normalize(direction);
  float r = std::max(b.radius(), 1e-3f);
  glm::vec3 centre = b.center();
  glm::vec3 eye = centre - d * (2.0f * r);
  glm::mat4 view = glm::lookAt(eye, centre, pickUp(d));
  glm::mat4 proj = glm::ortho(-r, r, -r, r, r * 0.5f, r * 3.5f);
  return makeView(view, proj, size, size, true, eye, r * 0.5f, r * 3.5f, 2.0f * r / float(size));
}

GiView makePerspectiveLightView(const glm::vec3& position, const glm::vec3& direction, float fovY, const Bounds& b,
                                int size) {
  glm::vec3 d = glm::normalize(direction);
  glm::mat4 view = glm::lookAt(position, position + d, pickUp(d));
  // Far plane: the farthest bounds corner; near plane: a small fraction of it (depth precision).
  float farthest = 0.0f;
  for (int i = 0; i < 8; ++i) {
    glm::vec3 corner((i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z);
    farthest = std::max(farthest, glm::length(corner - position));
  }
  float zfar = std::max(farthest * 1.01f, 1e-2f);
  float znear = std::max(zfar * 1e-4f, 1e-4f);
  glm::mat4 proj = glm::perspective(fovY, 1.0f, znear, zfar);
  return makeView(view, proj, size, size, false, position, znear, zfar, 2.0f * std::tan(0.5f * fovY) / float(size));
}

}  // namespace gi
