// The built-in thin-wall scene ("builtin:thin_wall"): two rooms side by side, separated by a wall
// thinner than a light-propagation-volume cell, with a spot light in one room only. It exists to
// measure light leaking through thin geometry (LPV, voxel cone tracing): the path tracer's image
// of the dark room is exactly black, so any light a technique puts there is leak.
//
// - Box x 0..2 m, y 0..1 m, z 0..1 m; the front (z = 0) is open, where the camera looks in.
// - Room A (lit): x 0..0.99; room B (dark): x 1.01..2. Each has its own floor, ceiling, back wall
//   and outer side wall, all facing into the room.
// - The wall: x 0.99..1.01 (2 cm thick), floor to ceiling, back wall to the open front; three
//   quads (the face towards A, the face towards B, the front edge), all facing outwards. A 32³
//   grid over the scene bounds has 6.25 cm cells, 64³ has 3.1 cm: the wall is thinner than both.
// - Light "thin_wall_spot": a KHR spot light at (0.5, 0.98, 0.5) in room A pointing straight
//   down, 2 W/sr, cone half-angles 40° / 70° (its cone reaches the lower part of the wall's A face).
// - Materials: one diffuse white (0.725, 0.71, 0.68), single-sided, metallic 0, roughness 1.
// - Camera "thin_wall": (1, 0.5, -1.3) looking along +z, yfov 2·atan(0.5/1.3) (the open front
//   fills the image height); 512×256, exposure 1. +x points left in the image: room A is the
//   right half, room B the left half.
#pragma once
#include "scene/scene.h"

namespace gi {

// Facts of the scene for tests and documentation (metres).
struct ThinWallLayout {
  static constexpr float kRoomAMinX = 0.0f;
  static constexpr float kWallMinX = 0.99f;  // the wall's face towards room A
  static constexpr float kWallMaxX = 1.01f;  // the wall's face towards room B
  static constexpr float kRoomBMaxX = 2.0f;
  static constexpr float kHeight = 1.0f;
  static constexpr float kDepth = 1.0f;
};

Scene makeThinWallScene();

}  // namespace gi
