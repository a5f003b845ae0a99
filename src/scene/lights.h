// Punctual lights in the GiLight layout (units: ALGORITHMS.md §0, KHR_lights_punctual), and the
// spot-light stand-ins that represent emissive triangles in shadow maps and RSMs (§1).
#pragma once
#include <glm/glm.hpp>

#include "scene/scene.h"

namespace gi {

// irradiance: W/m² per channel on a surface facing the light; direction: where the light travels.
GiLight makeDirectionalLight(const glm::vec3& direction, const glm::vec3& irradiance);

// intensity: W/sr per channel; range 0 = infinite.
GiLight makePointLight(const glm::vec3& position, const glm::vec3& intensity, float range = 0.0f);

// KHR_lights_punctual spot: intensity I0 (W/sr) on the axis, smooth falloff between the cone
// half-angles (radians, 0 <= inner < outer <= pi/2).
GiLight makeSpotLight(const glm::vec3& position, const glm::vec3& direction, const glm::vec3& intensity,
                      float innerConeAngle, float outerConeAngle, float range = 0.0f);

// For every instance (Scene::triangleInstance) with emissive triangles, adds one light
// "emitter:<instance name>" with the instance's emitted power Φ = π·L·A:
//   a spot light (GI_SPOT_FALLOFF_COSINE, I(θ) = L·A·cos θ over the hemisphere) at the
//   area-weighted centroid, 1e-3 scene radii in front of it, facing along the area-weighted
//   normal; L is the area-weighted mean radiance (emissive factor × strength × the emissive
//   texture's mean colour, not its variation over the surface).
// An emitter whose normals cancel (|Σ a·n| < 0.1·A, e.g. a closed glowing sphere) has no facing
// direction and gets a point light of the same power instead (I = L·A/4).
// Emitters below 1e-6 of the total emitted power are left out. Needs bounds (computeBounds).
void addEmissiveStandInLights(Scene& scene);

// The light name prefix of emissive stand-ins; scene configs that replace the file's lights keep
// these, because they stand for geometry that stays in the scene.
inline constexpr const char* kEmitterLightPrefix = "emitter:";

}  // namespace gi
