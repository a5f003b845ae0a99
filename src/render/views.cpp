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

GiView makeDirectionalShadowView(const glm::vec3& direction, const Bounds& b, int size) {
  glm::vec3 d = glm::normalize(direction);
  float r = std::max(b.radius(), 1e-3f);
  glm::vec3 centre = b.center();
  glm::vec3 eye = centre - d * (2.0f * r);
  // The light-space footprint of the bounds' 8 corners, for each world axis as the image's up
  // (an axis-aligned box projects to the smallest rectangle when the image is aligned with it).
  struct Fit {
    glm::mat4 view;
    glm::vec3 lo, hi;
  };
  Fit best{};
  float bestArea = -1.0f;
  const glm::vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const glm::vec3& up : axes) {
    if (glm::length(glm::cross(d, up)) < 1e-3f) continue;
    Fit f{glm::lookAt(eye, centre, up), glm::vec3(INFINITY), glm::vec3(-INFINITY)};
    for (int i = 0; i < 8; ++i) {
      glm::vec3 corner((i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z);
      glm::vec3 q = glm::vec3(f.view * glm::vec4(corner, 1.0f));
      f.lo = glm::min(f.lo, q);
      f.hi = glm::max(f.hi, q);
    }
    float area = std::max(f.hi.x - f.lo.x, 1e-3f * r) * std::max(f.hi.y - f.lo.y, 1e-3f * r);
    if (bestArea < 0.0f || area < bestArea) bestArea = area, best = f;
  }
  float ex = std::max(best.hi.x - best.lo.x, 1e-3f * r), ey = std::max(best.hi.y - best.lo.y, 1e-3f * r);
  // Square texels, size² of them over the footprint, no side longer than 4·size; two texels of
  // margin on every side so that the 3×3 PCF and the normal offset stay on the map at its edges.
  int maxSide = std::min(4 * size, 16384);  // the rasterizer's largest view side, as for images
  float texel = std::max({std::sqrt(ex * ey) / float(size), ex / float(maxSide - 5), ey / float(maxSide - 5)});
  int width = std::min(maxSide, int(std::ceil(ex / texel)) + 4), height = std::min(maxSide, int(std::ceil(ey / texel)) + 4);
  float cx = 0.5f * (best.lo.x + best.hi.x), cy = 0.5f * (best.lo.y + best.hi.y);
  float hx = 0.5f * texel * float(width), hy = 0.5f * texel * float(height);
  // View-space z is negative in front of the eye; the bounds lie between -hi.z and -lo.z.
  float znear = std::max(-best.hi.z - 0.01f * r, 1e-4f * r), zfar = -best.lo.z + 0.01f * r;
  glm::mat4 proj = glm::ortho(cx - hx, cx + hx, cy - hy, cy + hy, znear, zfar);
  return makeView(best.view, proj, width, height, true, eye, znear, zfar, texel);
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
