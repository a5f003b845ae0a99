// The built-in Cornell box (see cornell_box.h for the data and its source).
#include "scene/cornell_box.h"

#include <array>
#include <cmath>

#include "scene/lights.h"
#include "scene/scene_setup.h"

namespace gi {
namespace {

using Quad = std::array<glm::vec3, 4>;  // corners in millimetres, as published

constexpr float kMillimetre = 0.001f;
constexpr float kLightY = 548.8f - 0.1f;  // 0.1 mm below the ceiling, so the two never z-fight

// Published data: https://www.graphics.cornell.edu/online/box/data.html
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

GiMaterial diffuseMaterial(const glm::vec3& albedo) {
  GiMaterial m{};
  m.base_color[0] = albedo.x;
  m.base_color[1] = albedo.y;
  m.base_color[2] = albedo.z;
  m.base_color[3] = 1.0f;
  m.metallic = 0.0f;
  m.roughness = 1.0f;
  m.alpha_cutoff = 0.5f;
  m.normal_scale = 1.0f;
  m.alpha_mode = GI_ALPHA_OPAQUE;
  m.base_color_tex = m.metallic_roughness_tex = m.normal_tex = m.emissive_tex = GI_NO_TEXTURE;
  m.double_sided = 0;
  return m;
}

// Adds a quad as two triangles, each with its own vertices and exact face normal, wound
// counter-clockwise as seen from the side `facing` points to.
void addQuad(Scene& s, Quad q, const glm::vec3& facing, uint32_t material, uint32_t instance) {
  glm::vec3 quadNormal = glm::cross(q[2] - q[0], q[3] - q[1]);
  if (glm::dot(quadNormal, facing) < 0.0f) std::swap(q[1], q[3]);
  const glm::vec2 quadUv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const glm::ivec3& corner : {glm::ivec3(0, 1, 2), glm::ivec3(0, 2, 3)}) {
    glm::vec3 p[3], n;
    for (int k = 0; k < 3; ++k) p[k] = q[corner[k]] * kMillimetre;
    n = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
    uint32_t first = static_cast<uint32_t>(s.positions.size());
    for (int k = 0; k < 3; ++k) {
      s.positions.push_back(p[k]);
      s.normals.push_back(n);
      s.uvs.push_back(quadUv[corner[k]]);
      s.tangents.push_back(glm::vec4(0.0f));
    }
    s.triangles.push_back(glm::uvec3(first, first + 1, first + 2));
    s.triangleMaterial.push_back(material);
    s.triangleInstance.push_back(instance);
  }
}

uint32_t addInstance(Scene& s, const std::string& name) {
  s.instanceNames.push_back(name);
  return static_cast<uint32_t>(s.instanceNames.size() - 1);
}

void addBlock(Scene& s, const std::array<Quad, 5>& faces, uint32_t material, const std::string& name) {
  uint32_t instance = addInstance(s, name);
  glm::vec3 centre(0.0f);
  for (const Quad& f : faces)
    for (const glm::vec3& p : f) centre += p / 20.0f;
  for (const Quad& f : faces) {
    glm::vec3 faceCentre = 0.25f * (f[0] + f[1] + f[2] + f[3]);
    addQuad(s, f, faceCentre - centre, material, instance);
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
  s.materials.push_back(diffuseMaterial({0.725f, 0.71f, 0.68f}));
  s.materials.push_back(diffuseMaterial({0.63f, 0.065f, 0.05f}));
  s.materials.push_back(diffuseMaterial({0.14f, 0.45f, 0.091f}));
  GiMaterial light = diffuseMaterial(glm::vec3(0.78f));
  light.emissive[0] = kLightRadiance.x;
  light.emissive[1] = kLightRadiance.y;
  light.emissive[2] = kLightRadiance.z;
  s.materials.push_back(light);

  addQuad(s, kFloor, {0, 1, 0}, kWhite, addInstance(s, "floor"));
  addQuad(s, kCeiling, {0, -1, 0}, kWhite, addInstance(s, "ceiling"));
  addQuad(s, kBackWall, {0, 0, -1}, kWhite, addInstance(s, "back_wall"));
  addQuad(s, kRedWall, {-1, 0, 0}, kRed, addInstance(s, "red_wall"));
  addQuad(s, kGreenWall, {1, 0, 0}, kGreen, addInstance(s, "green_wall"));
  if (options.withAreaLight) addQuad(s, kLight, {0, -1, 0}, kLightMaterial, addInstance(s, "light"));
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
