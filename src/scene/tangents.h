// Per-vertex tangent frames for normal mapping, for meshes whose file has no TANGENT attribute.
//
// Convention (glTF 2.0): tangent.xyz points along +u, the bitangent is cross(normal, tangent.xyz)
// × tangent.w and points along -v (glTF's v axis runs down the image, normal maps' green axis up),
// so an unmirrored mapping has w = +1 and a mirrored one w = -1.
//
// Method: per triangle the UV gradients dP/du and -dP/dv (Lengyel 2001), normalised and added to
// each corner weighted by the corner angle (as MikkTSpace does, so a vertex's result does not
// depend on how the surface around it is triangulated), then Gram-Schmidt against the vertex
// normal. Unlike MikkTSpace, vertices are never split: a vertex shared across a UV mirror seam gets
// the average frame. Vertices with no usable UV gradient get any unit vector orthogonal to the
// normal and w = +1.
#pragma once
#include <vector>

#include <glm/glm.hpp>

namespace gi {

std::vector<glm::vec4> generateTangents(const std::vector<glm::vec3>& positions,
                                        const std::vector<glm::vec3>& normals,
                                        const std::vector<glm::vec2>& uvs,
                                        const std::vector<glm::uvec3>& triangles);

}  // namespace gi
