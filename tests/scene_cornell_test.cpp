// The built-in Cornell box: parts, closed room, orientation of every face, camera, light power.
#include <cmath>
#include <map>
#include <tuple>

#include <gtest/gtest.h>

#include "scene/cornell_box.h"
#include "scene/scene_loader.h"

namespace gi {
namespace {

glm::vec3 faceNormal(const Scene& s, size_t t) {
  const glm::uvec3& tri = s.triangles[t];
  return glm::normalize(glm::cross(s.positions[tri[1]] - s.positions[tri[0]], s.positions[tri[2]] - s.positions[tri[0]]));
}
float area(const Scene& s, size_t t) {
  const glm::uvec3& tri = s.triangles[t];
  return 0.5f * glm::length(glm::cross(s.positions[tri[1]] - s.positions[tri[0]], s.positions[tri[2]] - s.positions[tri[0]]));
}
glm::vec3 centroid(const Scene& s, size_t t) {
  const glm::uvec3& tri = s.triangles[t];
  return (s.positions[tri[0]] + s.positions[tri[1]] + s.positions[tri[2]]) / 3.0f;
}
bool isBlock(const Scene& s, size_t t) {
  const std::string& name = s.instanceNames[s.triangleInstance[t]];
  return name == "short_block" || name == "tall_block";
}

TEST(SceneCornell, HasFiveWallsLightAndTwoBlocks) {
  Scene s = makeCornellBox();
  EXPECT_EQ(s.source, "builtin:cornell");
  EXPECT_EQ(s.triangleCount(), 32u);  // 5 walls + light: 2 each; 2 blocks × 5 faces × 2
  std::vector<std::string> expected = {"floor", "ceiling", "back_wall", "red_wall", "green_wall", "light", "short_block", "tall_block"};
  EXPECT_EQ(s.instanceNames, expected);
  std::map<uint32_t, int> trianglesPerInstance;
  for (uint32_t i : s.triangleInstance) ++trianglesPerInstance[i];
  EXPECT_EQ(trianglesPerInstance.size(), 8u);
  EXPECT_EQ(trianglesPerInstance[6], 10);
  EXPECT_EQ(s.defaultWidth, 512);
  EXPECT_EQ(s.defaultHeight, 512);
  EXPECT_EQ(s.exposure, 1.0f);
  EXPECT_NEAR(s.bounds.lo.x, 0.0f, 1e-6f);
  EXPECT_NEAR(s.bounds.hi.x, 0.556f, 1e-6f);
  EXPECT_NEAR(s.bounds.hi.y, 0.5488f, 1e-6f);
  EXPECT_NEAR(s.bounds.hi.z, 0.5592f, 1e-6f);
  for (const GiMaterial& m : s.materials) {
    EXPECT_EQ(m.metallic, 0.0f);
    EXPECT_EQ(m.roughness, 1.0f);
  }
  const GiMaterial& red = s.materials[s.triangleMaterial[6]];
  EXPECT_FLOAT_EQ(red.base_color[0], 0.63f);
  EXPECT_FLOAT_EQ(red.base_color[1], 0.065f);
}

TEST(SceneCornell, RoomIsClosedExceptTheFrontOpening) {
  Scene s = makeCornellBox({.withBlocks = false, .withAreaLight = false});
  ASSERT_EQ(s.triangleCount(), 10u);
  auto key = [](glm::vec3 a, glm::vec3 b) {
    if (std::tie(b.x, b.y, b.z) < std::tie(a.x, a.y, a.z)) std::swap(a, b);
    return std::make_tuple(a.x, a.y, a.z, b.x, b.y, b.z);
  };
  std::map<std::tuple<float, float, float, float, float, float>, int> edgeUses;
  for (const glm::uvec3& t : s.triangles)
    for (int k = 0; k < 3; ++k) ++edgeUses[key(s.positions[t[k]], s.positions[t[(k + 1) % 3]])];
  int openEdges = 0;
  for (const auto& [edge, uses] : edgeUses) {
    bool onFront = std::get<2>(edge) == 0.0f && std::get<5>(edge) == 0.0f;
    if (onFront) {
      EXPECT_EQ(uses, 1);
      ++openEdges;
    } else {
      EXPECT_EQ(uses, 2) << "edge shared by " << uses << " triangles: the room has a gap";
    }
  }
  EXPECT_EQ(openEdges, 4);  // the four sides of the front opening
}

TEST(SceneCornell, WallsFaceIntoTheRoomBlocksOutwardCounterClockwise) {
  Scene s = makeCornellBox();
  const glm::vec3 roomCentre(0.278f, 0.2744f, 0.2796f);
  std::map<uint32_t, std::pair<glm::vec3, int>> blockCentres;
  for (size_t t = 0; t < s.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      auto& [sum, n] = blockCentres[s.triangleInstance[t]];
      sum += s.positions[s.triangles[t][k]];
      ++n;
    }
  for (size_t t = 0; t < s.triangleCount(); ++t) {
    glm::vec3 geometric = faceNormal(s, t);
    for (int k = 0; k < 3; ++k)  // counter-clockwise seen from where the normal points
      EXPECT_GT(glm::dot(s.normals[s.triangles[t][k]], geometric), 0.9999f) << s.instanceNames[s.triangleInstance[t]];
    if (isBlock(s, t)) {
      auto [sum, n] = blockCentres[s.triangleInstance[t]];
      EXPECT_GT(glm::dot(geometric, centroid(s, t) - sum / float(n)), 0.0f) << "block faces point outwards";
    } else {
      EXPECT_GT(glm::dot(geometric, roomCentre - centroid(s, t)), 0.0f)
          << s.instanceNames[s.triangleInstance[t]] << " must face into the room";
    }
  }
}

TEST(SceneCornell, CameraIsTheCornellCamera) {
  Scene s = loadScene("", "");
  ASSERT_EQ(s.cameras.size(), 1u);
  const Camera& c = s.cameras[s.defaultCamera];
  EXPECT_EQ(c.name, "cornell");
  EXPECT_EQ(c.position, glm::vec3(0.278f, 0.273f, -0.800f));
  EXPECT_EQ(c.target, glm::vec3(0.278f, 0.273f, 0.0f));
  EXPECT_EQ(c.up, glm::vec3(0, 1, 0));
  EXPECT_NEAR(c.yfov, 0.686048f, 1e-5f);
  EXPECT_GT(c.znear, 0.0f);
  EXPECT_LT(c.znear, 0.8f);
  EXPECT_GT(c.zfar, 0.8f + 0.5592f);
}

TEST(SceneCornell, StandInLightCarriesTheAreaLightPower) {
  Scene s = makeCornellBox();
  glm::dvec3 areaLightPower(0.0);  // Φ = π · L · A over the emissive triangles
  double lightArea = 0;
  for (size_t t = 0; t < s.triangleCount(); ++t) {
    const GiMaterial& m = s.materials[s.triangleMaterial[t]];
    glm::dvec3 L(m.emissive[0], m.emissive[1], m.emissive[2]);
    if (L == glm::dvec3(0.0)) continue;
    EXPECT_EQ(L, glm::dvec3(17, 12, 4));
    EXPECT_EQ(faceNormal(s, t), glm::vec3(0, -1, 0));
    EXPECT_NEAR(centroid(s, t).y, 0.5487f, 1e-6f);
    areaLightPower += M_PI * L * double(area(s, t));
    lightArea += area(s, t);
  }
  EXPECT_NEAR(lightArea, cornellLightArea(), 1e-8);
  EXPECT_NEAR(lightArea, 0.13 * 0.105, 1e-8);

  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_EQ(s.lightNames[0], "emitter:light");
  const GiLight& l = s.lights[0];
  EXPECT_EQ(l.type, GI_LIGHT_SPOT);
  EXPECT_EQ(l.falloff, GI_SPOT_FALLOFF_COSINE);
  EXPECT_EQ(glm::vec3(l.direction[0], l.direction[1], l.direction[2]), glm::vec3(0, -1, 0));
  // A cosine emitter of on-axis intensity I0 emits π·I0 into its hemisphere.
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(M_PI * l.intensity[c], areaLightPower[c], 1e-5 * areaLightPower[c]);
  glm::vec3 centre = cornellLightCentre();
  EXPECT_NEAR(l.position[0], centre.x, 1e-6f);
  EXPECT_NEAR(l.position[2], centre.z, 1e-6f);
  EXPECT_LT(l.position[1], centre.y);  // just in front of the emitter
  EXPECT_GT(l.position[1], centre.y - 1e-3f);
}

TEST(SceneCornell, OptionsForEmptyBoxAndSpotLight) {
  Scene empty = makeBuiltinScene("cornell_empty");
  EXPECT_EQ(empty.triangleCount(), 12u);
  EXPECT_EQ(empty.lights.size(), 1u);

  CornellSpotLight spot;
  spot.outerConeDeg = 50.0f;
  Scene spotOnly = makeCornellBox({.withBlocks = true, .withAreaLight = false, .spotLight = spot});
  EXPECT_EQ(spotOnly.triangleCount(), 30u);
  ASSERT_EQ(spotOnly.lights.size(), 1u);
  EXPECT_EQ(spotOnly.lightNames[0], "cornell_spot");
  const GiLight& l = spotOnly.lights[0];
  EXPECT_EQ(l.type, GI_LIGHT_SPOT);
  EXPECT_EQ(l.falloff, GI_SPOT_FALLOFF_GLTF);
  EXPECT_NEAR(l.cos_outer, std::cos(glm::radians(50.0f)), 1e-6f);
  EXPECT_NEAR(l.cos_inner, std::cos(glm::radians(30.0f)), 1e-6f);
  EXPECT_EQ(glm::vec3(l.direction[0], l.direction[1], l.direction[2]), glm::vec3(0, -1, 0));
  EXPECT_LT(l.position[1], 0.5488f);
}

}  // namespace
}  // namespace gi
