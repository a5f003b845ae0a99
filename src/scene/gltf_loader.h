// glTF 2.0 (.gltf with external or data-URI buffers, and .glb) -> gi::Scene, via tinygltf.
//
// What is read:
// - The default scene's node tree (scene 0 when none is marked; all root nodes when the file has
//   no scenes). TRS or matrix transforms; every (node, primitive) becomes one instance with its
//   triangles baked into world space (normals by the inverse transpose, tangents by the matrix;
//   winding and tangent handedness flipped where the transform mirrors).
// - Primitives: triangles, triangle strips and fans (converted to lists); points and lines are
//   skipped with a warning. POSITION, NORMAL, TEXCOORD_0, TANGENT in any component type the spec
//   or KHR_mesh_quantization allows, sparse accessors applied (gltf_accessor.h).
//   Missing NORMAL: flat normals (vertices un-welded, as the spec asks). Missing TANGENT on a
//   primitive whose material has a normal map: generated (tangents.h).
//   Triangles with a NaN/Inf vertex or zero area (repeated index, or exactly collinear corners)
//   are skipped, with one warning per primitive giving the count. Indices out of range: error.
// - Materials: metallic-roughness factors and textures, normal texture + scale, emissive factor
//   × KHR_materials_emissive_strength and emissive texture, alpha mode/cutoff, double-sided.
//   No material: the spec's default (white, metallic 1, roughness 1). Occlusion textures,
//   samplers (wrap modes) and texCoord sets other than 0 are not supported (set 0 is used).
//   KHR_materials_specular is ignored silently (optional, only shifts specular colour).
// - Textures: decoded once per image, RGBA8 + mip chain (textures.h); base colour and emissive
//   are sRGB, normal and metallic-roughness linear; an image used both ways gets two entries.
// - KHR_lights_punctual: directional (irradiance W/m² = intensity × colour), point and spot
//   (intensity W/sr × colour, cones, range); they shine along the node's -Z axis.
// - Perspective cameras (orthographic ones are skipped with a warning): position, -Z view
//   direction and +Y up from the node's world matrix; yfov, znear, zfar (missing zfar fitted to the
//   bounds). The first camera is the default and its aspectRatio sets the default image height
//   (width 640). No camera: one framing the bounds (scene_setup.h).
// - Emissive triangles get spot-light stand-ins (lights.h).
//
// Errors (gi::Error, naming the file and the item): unreadable/truncated/malformed files,
// missing .bin or texture images, unsupported extensionsRequired (Draco, meshopt, basisu, ...),
// out-of-range indices or accessors, a scene without triangles.
#pragma once
#include <filesystem>

#include "scene/scene.h"

namespace gi {

Scene loadGltfScene(const std::filesystem::path& file);

}  // namespace gi
