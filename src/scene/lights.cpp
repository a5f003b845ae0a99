// Light constructors and emissive stand-in lights (see lights.h).
#include "scene/lights.h"

#include <algorithm>
#include <cmath>

#include "image/image.h"

namespace gi {
namespace {

GiLight blankLight(int type) {
  GiLight l{};
  l.type = type;
  l.shadow_map = -1;  // assigned by the renderer
  l.falloff = GI_SPOT_FALLOFF_GLTF;
  l.cos_inner = 1.0f;
  l.cos_outer = 1.0f;
  return l;
}

void store(float out[3], const glm::vec3& v) {
  out[0] = v.x;
  out[1] = v.y;
  out[2] = v.z;
}

// Mean colour of a texture in linear RGB: its 1×1 mip level, which the box-filtered chain
// built in linear space makes the average of the image.
glm::vec3 meanColour(const Texture& t) {
  if (t.rgba8.size() < 4) return glm::vec3(1.0f);
  const uint8_t* texel = t.rgba8.data() + t.rgba8.size() - 4;
  glm::vec3 c(texel[0] / 255.0f, texel[1] / 255.0f, texel[2] / 255.0f);
  return t.srgb ? glm::vec3(srgbDecode(c.x), srgbDecode(c.y), srgbDecode(c.z)) : c;
}

struct EmitterSum {
  double area = 0;
  glm::dvec3 weightedCentroid{0.0}, weightedNormal{0.0}, weightedRadiance{0.0};
};

}  // namespace

GiLight makeDirectionalLight(const glm::vec3& direction, const glm::vec3& irradiance) {
  GiLight l = blankLight(GI_LIGHT_DIRECTIONAL);
  store(l.direction, glm::normalize(direction));
  store(l.intensity, irradiance);
  return l;
}

GiLight makePointLight(const glm::vec3& position, const glm::vec3& intensity, float range) {
  GiLight l = blankLight(GI_LIGHT_POINT);
  store(l.position, position);
  store(l.intensity, intensity);
  l.range = range;
  return l;
}

GiLight makeSpotLight(const glm::vec3& position, const glm::vec3& direction, const glm::vec3& intensity,
                      float innerConeAngle, float outerConeAngle, float range) {
  GiLight l = blankLight(GI_LIGHT_SPOT);
  store(l.position, position);
  store(l.direction, glm::normalize(direction));
  store(l.intensity, intensity);
  l.cos_inner = std::cos(innerConeAngle);
  l.cos_outer = std::cos(outerConeAngle);
  l.range = range;
  return l;
}

void addEmissiveStandInLights(Scene& scene) {
  std::vector<glm::vec3> materialRadiance(scene.materials.size());
  for (size_t m = 0; m < scene.materials.size(); ++m) {
    const GiMaterial& mat = scene.materials[m];
    glm::vec3 L(mat.emissive[0], mat.emissive[1], mat.emissive[2]);
    if (mat.emissive_tex >= 0 && size_t(mat.emissive_tex) < scene.textures.size())
      L *= meanColour(scene.textures[mat.emissive_tex]);
    materialRadiance[m] = L;
  }

  std::vector<EmitterSum> sums;
  for (size_t t = 0; t < scene.triangles.size(); ++t) {
    glm::vec3 L = materialRadiance[scene.triangleMaterial[t]];
    if (!(std::max({L.x, L.y, L.z}) > 0.0f)) continue;
    const glm::uvec3& tri = scene.triangles[t];
    glm::dvec3 p0 = scene.positions[tri[0]], p1 = scene.positions[tri[1]], p2 = scene.positions[tri[2]];
    glm::dvec3 areaVector = 0.5 * glm::cross(p1 - p0, p2 - p0);  // counter-clockwise side = front
    double area = glm::length(areaVector);
    if (!(area > 0.0)) continue;
    uint32_t instance = scene.triangleInstance[t];
    if (instance >= sums.size()) sums.resize(instance + 1);
    EmitterSum& s = sums[instance];
    s.area += area;
    s.weightedCentroid += area * (p0 + p1 + p2) / 3.0;
    s.weightedNormal += areaVector;
    s.weightedRadiance += area * glm::dvec3(L);
  }

  double totalPower = 0;
  for (const EmitterSum& s : sums) totalPower += s.weightedRadiance.x + s.weightedRadiance.y + s.weightedRadiance.z;
  if (!(totalPower > 0.0)) return;

  const double offset = 1e-3 * scene.bounds.radius();
  for (size_t instance = 0; instance < sums.size(); ++instance) {
    const EmitterSum& s = sums[instance];
    // weightedRadiance = L·A, the on-axis intensity of a cosine emitter of radiance L and area A.
    double power = s.weightedRadiance.x + s.weightedRadiance.y + s.weightedRadiance.z;
    if (!(power > 1e-6 * totalPower)) continue;
    glm::vec3 centroid(s.weightedCentroid / s.area);
    glm::vec3 intensityOnAxis(s.weightedRadiance);
    double normalLength = glm::length(s.weightedNormal);
    GiLight light;
    if (normalLength >= 0.1 * s.area) {
      glm::vec3 normal(s.weightedNormal / normalLength);
      light = makeSpotLight(centroid + float(offset) * normal, normal, intensityOnAxis, 0.0f, 0.5f * float(M_PI));
      light.falloff = GI_SPOT_FALLOFF_COSINE;
      light.cos_inner = 0.0f;
      light.cos_outer = 0.0f;
    } else {
      light = makePointLight(centroid, 0.25f * intensityOnAxis);  // π·L·A spread over 4π sr
    }
    std::string name = instance < scene.instanceNames.size() && !scene.instanceNames[instance].empty()
                           ? scene.instanceNames[instance]
                           : "instance" + std::to_string(instance);
    scene.lights.push_back(light);
    scene.lightNames.push_back(kEmitterLightPrefix + name);
  }
}

}  // namespace gi
