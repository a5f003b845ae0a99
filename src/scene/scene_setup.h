// The steps every scene producer (glTF loader, Cornell box, scene config) ends with: bounds,
// a camera when there is none, clip planes from the bounds, emissive stand-in lights.
#pragma once
#include <string>

#include "scene/scene.h"

namespace gi {

// A camera that sees the whole bounding sphere: looks at the centre from the +z side, a little
// from above and the right (direction (1, 0.6, 2) normalised), yfov 60°, up +y.
Camera makeFramingCamera(const Bounds& bounds, std::string name = "auto");

// Sets znear / zfar where they are <= 0 (missing): zfar just past the farthest point of the
// bounding sphere seen from the camera, znear = zfar / 1000 (keeps depth precision usable).
void fitClipPlanes(Camera& camera, const Bounds& bounds);

// Checks the per-vertex/per-triangle arrays agree, computes the bounds, throws gi::Error if the
// scene has no triangles, adds a framing camera when there is none, fits missing clip planes and
// adds the emissive stand-in lights. `what` names the scene in messages (its file).
void finishScene(Scene& scene, const std::string& what);

}  // namespace gi
