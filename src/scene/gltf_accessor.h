// Reading glTF accessors into plain arrays, for every component type the glTF 2.0 spec (and
// KHR_mesh_quantization) allows: float, and signed/unsigned 8/16-bit and unsigned 32-bit integers,
// normalized or not. Sparse accessors are applied here (tinygltf parses but does not apply them);
// an accessor without a bufferView reads as zeros before its sparse values are applied.
// Every byte range is checked against its bufferView and buffer; violations throw gi::Error.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <tiny_gltf.h>

namespace gi::gltf {

// Accessor `index` as count × `components` floats. Normalized integers map to [0, 1] / [-1, 1]
// as the spec says; other integers convert by value. `what` names the item in messages
// (e.g. "Sponza.gltf: mesh 'arch' primitive 0 attribute POSITION").
std::vector<float> readFloats(const tinygltf::Model& model, int index, int components, const std::string& what);

// An index accessor (SCALAR of unsigned byte/short/int) as 32-bit indices.
std::vector<uint32_t> readIndices(const tinygltf::Model& model, int index, const std::string& what);

}  // namespace gi::gltf
