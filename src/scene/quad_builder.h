// Building blocks for the scenes made in code (the Cornell box, the thin-wall rooms): diffuse
// materials, named instances and planar quads split into two flat-shaded triangles.
#pragma once
#include <array>
#include <cstdint>
#include <string>

#include <glm/glm.hpp>

#include "scene/scene.h"

namespace gi {

using Quad = std::array<glm::vec3, 4>;  // corners in order around the quad, metres

// Opaque, single-sided, metallic 0, roughness 1, untextured.
GiMaterial makeDiffuseMaterial(const glm::vec3& albedo);

// Appends an instance name and returns its id.
uint32_t addInstance(Scene& s, const std::string& name);

// Adds a quad as two triangles, each with its own vertices and exact face normal, wound
// counter-clockwise as seen from the side `facing` points to.
void addQuad(Scene& s, Quad q, const glm::vec3& facing, uint32_t material, uint32_t instance);

}  // namespace gi
