// The built-in thin-wall scene (see thin_wall.h for its layout and purpose).
#include "scene/thin_wall.h"

#include <cmath>

#include "scene/lights.h"
#include "scene/quad_builder.h"
#include "scene/scene_setup.h"

namespace gi {
namespace {

using L = ThinWallLayout;

// A quad in the plane x = const spanning the full height and depth.
Quad sideQuad(float x) { return {{{x, 0, 0}, {x, 0, L::kDepth}, {x, L::kHeight, L::kDepth}, {x, L::kHeight, 0}}}; }

// Floor (y = 0), ceiling (y = height) and back wall (z = depth) of the room between x0 and x1.
void addRoom(Scene& s, const std::string& name, float x0, float x1, float outerX, float inwardX, uint32_t material) {
  addQuad(s, {{{x0, 0, 0}, {x1, 0, 0}, {x1, 0, L::kDepth}, {x0, 0, L::kDepth}}}, {0, 1, 0}, material,
          addInstance(s, name + "_floor"));
  addQuad(s, {{{x0, L::kHeight, 0}, {x1, L::kHeight, 0}, {x1, L::kHeight, L::kDepth}, {x0, L::kHeight, L::kDepth}}},
          {0, -1, 0}, material, addInstance(s, name + "_ceiling"));
  addQuad(s, {{{x0, 0, L::kDepth}, {x1, 0, L::kDepth}, {x1, L::kHeight, L::kDepth}, {x0, L::kHeight, L::kDepth}}},
          {0, 0, -1}, material, addInstance(s, name + "_back_wall"));
  addQuad(s, sideQuad(outerX), {inwardX, 0, 0}, material, addInstance(s, name + "_outer_wall"));
}

}  // namespace

Scene makeThinWallScene() {
  Scene s;
  s.name = "thin_wall";
  s.source = "builtin:thin_wall";
  s.defaultWidth = 512;
  s.defaultHeight = 256;
  s.exposure = 1.0f;
  s.materials.push_back(makeDiffuseMaterial({0.725f, 0.71f, 0.68f}));
  const uint32_t white = 0;

  addRoom(s, "room_a", L::kRoomAMinX, L::kWallMinX, L::kRoomAMinX, 1.0f, white);
  addRoom(s, "room_b", L::kWallMaxX, L::kRoomBMaxX, L::kRoomBMaxX, -1.0f, white);
  uint32_t wall = addInstance(s, "thin_wall");
  addQuad(s, sideQuad(L::kWallMinX), {-1, 0, 0}, white, wall);
  addQuad(s, sideQuad(L::kWallMaxX), {1, 0, 0}, white, wall);
  addQuad(s, {{{L::kWallMinX, 0, 0}, {L::kWallMaxX, 0, 0}, {L::kWallMaxX, L::kHeight, 0}, {L::kWallMinX, L::kHeight, 0}}},
          {0, 0, -1}, white, wall);

  Camera camera;
  camera.name = "thin_wall";
  camera.position = glm::vec3(1.0f, 0.5f, -1.3f);
  camera.target = glm::vec3(1.0f, 0.5f, 0.0f);
  camera.up = glm::vec3(0, 1, 0);
  camera.yfov = 2.0f * std::atan(0.5f / 1.3f);
  camera.znear = 0.0f;  // fitted to the scene by finishScene
  camera.zfar = 0.0f;
  s.cameras.push_back(camera);

  finishScene(s, "builtin:thin_wall");

  s.lights.push_back(makeSpotLight({0.5f, 0.98f, 0.5f}, {0, -1, 0}, glm::vec3(2.0f), glm::radians(40.0f),
                                   glm::radians(70.0f)));
  s.lightNames.push_back("thin_wall_spot");
  return s;
}

}  // namespace gi
