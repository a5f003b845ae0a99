// Building GiView records (kernels/common/shared_types.h) for every rasterized view:
// the camera, directional-light (orthographic) and spot/point-light (perspective) shadow views.
//
// Conventions, used everywhere (rasterizer, path tracer, techniques):
// - world space is right-handed, y up (glTF); cameras look down their -z axis;
// - clip space is OpenGL's (x, y, z in [-w, w]); pixel (px, py) has its centre at
//   ndc = ((px + 0.5) / W · 2 − 1, 1 − (py + 0.5) / H · 2): row 0 is the top of the image;
// - "depth" in G-buffers is the positive view-space distance along the view axis.
#pragma once
#include <glm/glm.hpp>

#include "kernels/common/shared_types.h"
#include "scene/scene.h"

namespace gi {

GiView makeCameraView(const Camera& camera, int width, int height);

// Orthographic view looking along `direction`, fitted around the sphere bounding `bounds`
// (so every point of the scene is inside the view), `size`×`size` texels.
GiView makeDirectionalLightView(const glm::vec3& direction, const Bounds& bounds, int size);

// Orthographic shadow view looking along `direction`, fitted tightly around the bounds' footprint
// in the light's image plane (its sides along the world axes that give the smallest footprint)
// with square texels and about `size`² texels in all (so width ≠ height when the footprint is not
// square; neither side above 4·size or 16384). For the same texel count the texels are smaller than those
// of makeDirectionalLightView, whose square window holds the whole bounding sphere (docs/RENDERING.md).
GiView makeDirectionalShadowView(const glm::vec3& direction, const Bounds& bounds, int size);

// Perspective view from `position` along `direction` with full cone angle `fovY` (radians),
// near/far planes fitted to the scene bounds.
GiView makePerspectiveLightView(const glm::vec3& position, const glm::vec3& direction, float fovY,
                                const Bounds& bounds, int size);

// Fills the matrices of a view from view and projection matrices.
GiView makeView(const glm::mat4& view, const glm::mat4& proj, int width, int height, bool orthographic,
                const glm::vec3& eye, float znear, float zfar, float texelWorldSize);

}  // namespace gi
