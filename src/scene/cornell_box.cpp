// The built-in Cornell box (see cornell_box.h for the data and its source).
#include "scene/cornell_box.h"

#include <array>
#include <cmath>

#include "scene/lights.h"
#include "scene/quad_builder.h"
#include "scene/scene_setup.h"

namespace gi {
namespace {

constexpr float kMillimetre = 0.001f;
constexpr float kLightY = 548.8f - 0.1f;  // 0.1 mm below the ceiling, so the two never z-fight

// Published data (corners in millimetres): https://www.graphics.cornell.edu/online/box/data.html
const Quad kFloor = {{{552.8f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 559.2f}, {549.6f, 0.0f, 559.2f}}};
const Quad kCeiling = {{{556.0f, 548.8f, 0.0f}, {556.0f, 548.8f, 559.2f}, {0.0f, 548.8f, 559.2f}, {0.0f, 548.8f, 0.0f}}};
const Quad kBackWall = {{{549.6f, 0.0f, 559.2f}, {0.0f, 0.0f, 559.2f}, {0.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 559.2f}}};
const Quad kGreenWall = {{{0.0f, 0.0f, 559.2f}, {0.0f, 0.0f, 0.0f}, {0.0f, 548.8f, 0.0f}, {0.0f, 548.8f, 559.2f}}};
const Quad kRedWall = {{{552.8f, 0.0f, 0.0f}, {549.6f, 0.0f, 559.2f}, {556.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 0.0f}}};
const Quad kLight = {{{343.0f, kLightY, 227.0f}, {343.0f, kLightY, 332.0f}, {213.0f, kLightY, 332.0f}, {213.0f, kLightY, 227.0f}}};

const std::array<Quad, 5> kShortBlock = {{
    {{{130.0f, 165.0f, 65.0f}, {82.0f, 165.0f, 225.0f}, {240.0f, 165.0f, 272.0f}, {290.0f, 165.0f, 114.0f}}},
    {{{290.0f, 0.0f, 114.0f}, {290.0f, 165.0f, 114.0f}, {240.0f, 165.0f, 272.0f}, {240.0f, 0.0f, 272.0f}}},
    {{{130.0f, 0.0f, 65.0f}, {130.0f, 165.0f, 65.0f}, {290.0f, 165.0f, 114.0f}, {290.0f, 0.0f, 114.0f}}},
    {{{82.0f, 0.0f, 225.0f}, {82.0f, 165.0f, 225.0f}, {130.0f, 165.0f, 65.0f}, {130.0f, 0.0f, 65.0f}}},
    {{{240.0f, 0.0f, 272.0f}, {240.0f, 165.0f, 272.0f}, {82.0f, 165.0f, 225.0f}, {82.0f, 0.0f, 225.0f}}},
}};
const std::array<Quad, 5> kTallBlock = {{
    {{{423.0f, 330.0f, 247.0f}, {265.0f, 330.0f, 296.0f}, {314.0f, 330.0f, 456.0f}, {472.0f, 330.0f, 406.0f}}},
    {{{423.0f, 0.0f, 247.0f}, {423.0f, 330.0f, 247.0f}, {472.0f, 330.0f, 406.0f}, {472.0f, 0.0f, 406.0f}}},
    {{{472.0f, 0.0f, 406.0f}, {472.0f, 330.0f, 406.0f}, {314.0f, 330.0f, 456.0f}, {314.0f, 0.0f, 456.0f}}},
    {{{314.0f, 0.0f, 456.0f}, {314.0f, 330.0f, 456.0f}, {265.0f, 330.0f, 296.0f}, {265.0f, 0.0f, 296.0f}}},
    {{{265.0f, 0.0f, 296.0f}, {265.0f, 330.0f, 296.0f}, {423.0f, 330.0f, 247.0f}, {423.0f, 0.0f, 247.0f}}},
}};

const glm::vec3 kLightRadiance(17.0f, 12.0f, 4.0f);

void addMillimetreQuad(Scene& s, Quad q, const glm::vec3& facing, uint32_t material, uint32_t instance) {
  for (glm::vec3& corner : q) corner *= kMillimetre;
  addQuad(s, q, facing, material, instance);
}

void addBlock(Scene& s, const std::array<Quad, 5>& faces, uint32_t material, const std::string& name) {
  uint32_t instance = addInstance(s, name);
  glm::vec3 centre(0.0f);
  for (const Quad& f : faces)
    for (const glm::vec3& p : f) centre += p / 20.0f;
  for (const Quad& f : faces) {
    glm::vec3 faceCentre = 0.25f * (f[0] + f[1] + f[2] + f[3]);
    addMillimetreQuad(s, f, faceCentre - centre, material, instance);
  }
}

}  // namespace

glm::vec3 cornellLightCentre() { return 0.25f * (kLight[0] + kLight[1] + kLight[2] + kLight[3]) * kMillimetre; }
float cornellLightArea() { return (343.0f - 213.0f) * (332.0f - 227.0f) * kMillimetre * kMillimetre; }
glm::vec3 cornellLightRadiance() { return kLightRadiance; }

Scene makeCornellBox(const CornellOptions& options) {
  Scene s;
  s.name = "cornell";
  s.source = "builtin:cornell";
  s.defaultWidth = 512;
  s.defaultHeight = 512;
  s.exposure = 1.0f;

  enum : uint32_t { kWhite, kRed, kGreen, kLightMaterial };
  s.materials.push_back(makeDiffuseMaterial({0.725f, 0.71f, 0.68f}));
  s.materials.push_back(makeDiffuseMaterial({0.63f, 0.065f, 0.05f}));
  s.materials.push_back(makeDiffuseMaterial({0.14f, 0.45f, 0.091f}));
  GiMaterial light = makeDiffuseMaterial(glm::vec3(0.78f));
  light.emissive[0] = kLightRadiance.x;
  light.emissive[1] = kLightRadiance.y;
  light.emissive[2] = kLightRadiance.z;
  s.materials.push_back(light);

  addMillimetreQuad(s, kFloor, {0, 1, 0}, kWhite, addInstance(s, "floor"));
  addMillimetreQuad(s, kCeiling, {0, -1, 0}, kWhite, addInstance(s, "ceiling"));
  addMillimetreQuad(s, kBackWall, {0, 0, -1}, kWhite, addInstance(s, "back_wall"));
  addMillimetreQuad(s, kRedWall, {-1, 0, 0}, kRed, addInstance(s, "red_wall"));
  addMillimetreQuad(s, kGreenWall, {1, 0, 0}, kGreen, addInstance(s, "green_wall"));
  if (options.withAreaLight) addMillimetreQuad(s, kLight, {0, -1, 0}, kLightMaterial, addInstance(s, "light"));
  if (options.withBlocks) {
    addBlock(s, kShortBlock, kWhite, "short_block");
    addBlock(s, kTallBlock, kWhite, "tall_block");
  }

  Camera camera;
  camera.name = "cornell";
  camera.position = glm::vec3(0.278f, 0.273f, -0.800f);
  camera.target = glm::vec3(0.278f, 0.273f, 0.0f);
  camera.up = glm::vec3(0, 1, 0);
  camera.yfov = 2.0f * std::atan(12.5f / 35.0f);
  camera.znear = 0.0f;  // fitted to the box by finishScene
  camera.zfar = 0.0f;
  s.cameras.push_back(camera);

  finishScene(s, "builtin:cornell");

  if (options.spotLight) {
    const CornellSpotLight& spot = *options.spotLight;
    glm::vec3 position = cornellLightCentre() - glm::vec3(0.0f, 0.01f, 0.0f);
    s.lights.push_back(makeSpotLight(position, {0, -1, 0}, spot.intensity, glm::radians(spot.innerConeDeg),
                                     glm::radians(spot.outerConeDeg)));
    s.lightNames.push_back("cornell_spot");
  }
  return s;
}

}  // namespace gi
