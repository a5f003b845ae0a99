// The built-in Cornell box, made in code (no file): the measured geometry published by the
// Cornell University Program of Computer Graphics (www.graphics.cornell.edu/online/box/data.html,
// millimetres, converted to metres) with the colours of Morgan McGuire's CornellBox-Original.
//
// - Room: floor, ceiling, back wall, red left wall (x ≈ 0.55), green right wall (x = 0); the front
//   (z = 0) is open, where the camera looks in. Walls face into the room, block faces outwards,
//   front faces are counter-clockwise (glTF). The published quads are not all exactly planar or
//   rectangular; each quad is split in two triangles with their own exact face normals.
// - Materials: white (0.725, 0.71, 0.68), red (0.63, 0.065, 0.05), green (0.14, 0.45, 0.091),
//   light base colour 0.78 emitting radiance (17, 12, 4); metallic 0, roughness 1, single-sided.
// - Light: the quad x 0.213..0.343, z 0.227..0.332, 0.1 mm below the ceiling, facing down; its
//   spot stand-in "emitter:light" (lights.h) carries the same power π·L·A.
// - Camera "cornell": (0.278, 0.273, -0.800) looking along +z, up +y, yfov 2·atan(12.5/35)
//   (35 mm lens, 25 mm film); 512×512, exposure 1.
// - Instance ids: one per wall, the light, and one per block (all five faces; no bottom faces,
//   they sit on the floor).
#pragma once
#include <optional>

#include <glm/glm.hpp>

#include "scene/scene.h"

namespace gi {

// A KHR_lights_punctual spot light at the ceiling light's centre, 1 cm below the ceiling,
// pointing straight down (for tests that want a punctual light in the box).
struct CornellSpotLight {
  glm::vec3 intensity{0.232f, 0.164f, 0.0546f};  // W/sr on the axis; default = L·A of the area light
  float innerConeDeg = 30.0f;
  float outerConeDeg = 60.0f;
};

struct CornellOptions {
  bool withBlocks = true;      // false: the empty box, used by the accuracy tests
  bool withAreaLight = true;   // the emissive ceiling quad and its stand-in spot light
  std::optional<CornellSpotLight> spotLight;  // adds light "cornell_spot"
};

Scene makeCornellBox(const CornellOptions& options = {});

// Facts of the box for tests and documentation (metres, W/(m²·sr)).
glm::vec3 cornellLightCentre();    // centre of the emissive quad
float cornellLightArea();          // 0.130 m × 0.105 m
glm::vec3 cornellLightRadiance();  // (17, 12, 4)

}  // namespace gi
