// The built-in thin-wall scene: layout, light, and that the wall really separates the rooms
// (every straight path from the light into room B is blocked), so any light a technique puts
// into room B is a leak.
#include <gtest/gtest.h>

#include <cmath>

#include "reference/bvh.h"
#include "scene/scene_loader.h"
#include "scene/thin_wall.h"

namespace gi {
namespace {

using L = ThinWallLayout;

// Closest hit along the segment o -> o + d (t in (tmin, 1)), brute force over all triangles.
bool segmentBlocked(const Scene& s, const glm::vec3& o, const glm::vec3& d) {
  for (const glm::uvec3& tri : s.triangles) {
    glm::vec3 v0 = s.positions[tri.x];
    float t, u, v;
    if (intersectTriangle(o, d, v0, s.positions[tri.y] - v0, s.positions[tri.z] - v0, 1e-4f, 1.0f - 1e-4f, t, u, v))
      return true;
  }
  return false;
}

TEST(SceneThinWall, LayoutAndLight) {
  Scene s = makeBuiltinScene("thin_wall");
  EXPECT_EQ(s.source, "builtin:thin_wall");
  EXPECT_EQ(s.triangleCount(), 2u * (4 + 4 + 3));  // two rooms of four quads, the wall's three
  EXPECT_EQ(s.bounds.lo, glm::vec3(0.0f));
  EXPECT_EQ(s.bounds.hi, glm::vec3(2.0f, 1.0f, 1.0f));
  // Thinner than a cell of a 32³ or 64³ grid fitted to the bounds (longest edge 2 m).
  float thickness = L::kWallMaxX - L::kWallMinX;
  EXPECT_LT(thickness, 2.0f / 64.0f);
  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_EQ(s.lightNames[0], "thin_wall_spot");
  EXPECT_EQ(s.lights[0].type, GI_LIGHT_SPOT);
  EXPECT_LT(s.lights[0].position[0], L::kWallMinX);
  ASSERT_EQ(s.cameras.size(), 1u);
  EXPECT_GT(s.cameras[0].zfar, 2.0f);
}

TEST(SceneThinWall, WallBlocksEveryPathFromTheLightIntoRoomB) {
  Scene s = makeBuiltinScene("thin_wall");
  glm::vec3 light(s.lights[0].position[0], s.lights[0].position[1], s.lights[0].position[2]);
  // Points on a grid through room B's volume, and on its surfaces just inside the room.
  int blocked = 0, total = 0;
  const int n = 9;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        glm::vec3 f = (glm::vec3(i, j, k) + 0.5f) / float(n);
        glm::vec3 p(L::kWallMaxX + 1e-3f + f.x * (L::kRoomBMaxX - L::kWallMaxX - 2e-3f), f.y * L::kHeight,
                    f.z * L::kDepth);
        ++total;
        blocked += segmentBlocked(s, light, p - light) ? 1 : 0;
      }
  EXPECT_EQ(blocked, total);
  // And the same test is not trivially true: points in room A are visible from the light.
  EXPECT_FALSE(segmentBlocked(s, light, glm::vec3(0.3f, 0.01f, 0.5f) - light));
  EXPECT_FALSE(segmentBlocked(s, light, glm::vec3(L::kWallMinX - 1e-3f, 0.2f, 0.5f) - light));
}

}  // namespace
}  // namespace gi
