// glTF accessor reading with sparse substitution and range checks (see gltf_accessor.h).
#include "scene/gltf_accessor.h"

#include <algorithm>
#include <cstring>

#include "util/error.h"

namespace gi::gltf {
namespace {

const char* typeName(int components) {
  switch (components) {
    case 1: return "SCALAR";
    case 2: return "VEC2";
    case 3: return "VEC3";
    case 4: return "VEC4";
    default: return "a matrix type";
  }
}

size_t componentSize(int componentType) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;  // not allowed in glTF 2.0 accessors (e.g. int32, double)
  }
}

template <typename T>
T load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);  // glTF data need not be aligned for T
  return v;
}

// One component as float, normalized integers mapped as glTF 2.0 §3.11 says.
float toFloat(const uint8_t* p, int componentType, bool normalized) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return load<float>(p);
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      float v = load<int8_t>(p);
      return normalized ? std::max(v / 127.0f, -1.0f) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
      float v = load<uint8_t>(p);
      return normalized ? v / 255.0f : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      float v = load<int16_t>(p);
      return normalized ? std::max(v / 32767.0f, -1.0f) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      float v = load<uint16_t>(p);
      return normalized ? v / 65535.0f : v;
    }
    default: {  // UNSIGNED_INT (checked by the caller)
      double v = load<uint32_t>(p);
      return static_cast<float>(normalized ? v / 4294967295.0 : v);
    }
  }
}

uint32_t toIndex(const uint8_t* p, int componentType) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return load<uint8_t>(p);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return load<uint16_t>(p);
    default: return load<uint32_t>(p);  // UNSIGNED_INT (checked by the caller)
  }
}

// Where `count` elements of `elementSize` bytes start in a bufferView, and their stride.
// first == nullptr means "no bufferView": the elements read as zeros.
struct ByteRange {
  const uint8_t* first = nullptr;
  size_t stride = 0;
};

ByteRange locate(const tinygltf::Model& model, int viewIndex, size_t byteOffset, size_t count, size_t elementSize,
                 bool strided, const std::string& what) {
  if (viewIndex < 0) return {};
  if (size_t(viewIndex) >= model.bufferViews.size())
    throw Error(what + ": bufferView " + std::to_string(viewIndex) + " does not exist");
  const tinygltf::BufferView& view = model.bufferViews[viewIndex];
  if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size())
    throw Error(what + ": bufferView " + std::to_string(viewIndex) + " names buffer " + std::to_string(view.buffer) +
                ", which does not exist");
  const tinygltf::Buffer& buffer = model.buffers[view.buffer];
  if (view.byteOffset + view.byteLength > buffer.data.size())
    throw Error(what + ": bufferView " + std::to_string(viewIndex) + " (bytes " + std::to_string(view.byteOffset) +
                ".." + std::to_string(view.byteOffset + view.byteLength) + ") lies outside buffer " +
                std::to_string(view.buffer) + " (" + std::to_string(buffer.data.size()) + " bytes)");
  size_t stride = strided && view.byteStride != 0 ? view.byteStride : elementSize;
  if (stride < elementSize)
    throw Error(what + ": bufferView " + std::to_string(viewIndex) + " byteStride " + std::to_string(stride) +
                " is smaller than one element (" + std::to_string(elementSize) + " bytes)");
  size_t needed = count == 0 ? 0 : byteOffset + stride * (count - 1) + elementSize;
  if (needed > view.byteLength)
    throw Error(what + ": needs " + std::to_string(needed) + " bytes of bufferView " + std::to_string(viewIndex) +
                ", which has " + std::to_string(view.byteLength));
  return {buffer.data.data() + view.byteOffset + byteOffset, stride};
}

const tinygltf::Accessor& checkedAccessor(const tinygltf::Model& model, int index, int components,
                                          const std::string& what) {
  if (index < 0 || size_t(index) >= model.accessors.size())
    throw Error(what + ": accessor " + std::to_string(index) + " does not exist");
  const tinygltf::Accessor& a = model.accessors[index];
  int found = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
  if (found != components)
    throw Error(what + ": accessor " + std::to_string(index) + " is " + typeName(found) + ", expected " +
                typeName(components));
  if (componentSize(a.componentType) == 0)
    throw Error(what + ": accessor " + std::to_string(index) + " has invalid componentType " +
                std::to_string(a.componentType));
  return a;
}

// Reads the dense part, then overwrites the elements the sparse part names.
// convert(pointer to one element) stores that element's `components` values at out.
template <typename T, typename Convert>
std::vector<T> readElements(const tinygltf::Model& model, const tinygltf::Accessor& a, int components,
                            const std::string& what, Convert convert) {
  const size_t elementSize = componentSize(a.componentType) * components;
  ByteRange dense = locate(model, a.bufferView, a.byteOffset, a.count, elementSize, true, what);
  // Without a bufferView nothing bounds `count`; refuse sizes no real scene has before allocating.
  if (a.count > (size_t(1) << 28)) throw Error(what + ": count " + std::to_string(a.count) + " is implausibly large");
  std::vector<T> out(a.count * components, T(0));
  if (dense.first)
    for (size_t e = 0; e < a.count; ++e) convert(dense.first + e * dense.stride, &out[e * components]);

  if (!a.sparse.isSparse) return out;
  const std::string sparseWhat = what + " (sparse)";
  if (a.sparse.count < 0) throw Error(sparseWhat + ": negative count");
  const size_t count = size_t(a.sparse.count);
  const int indexType = a.sparse.indices.componentType;
  if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
      indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
    throw Error(sparseWhat + ": indices componentType " + std::to_string(indexType) + " is not an unsigned integer type");
  if (a.sparse.indices.bufferView < 0 || a.sparse.values.bufferView < 0)
    throw Error(sparseWhat + ": indices and values need a bufferView");
  ByteRange indices = locate(model, a.sparse.indices.bufferView, size_t(a.sparse.indices.byteOffset), count,
                             componentSize(indexType), false, sparseWhat + " indices");
  ByteRange values = locate(model, a.sparse.values.bufferView, size_t(a.sparse.values.byteOffset), count,
                            elementSize, false, sparseWhat + " values");
  for (size_t s = 0; s < count; ++s) {
    uint32_t target = toIndex(indices.first + s * indices.stride, indexType);
    if (target >= a.count)
      throw Error(sparseWhat + ": index " + std::to_string(target) + " is out of range (accessor has " +
                  std::to_string(a.count) + " elements)");
    convert(values.first + s * values.stride, &out[size_t(target) * components]);
  }
  return out;
}

}  // namespace

std::vector<float> readFloats(const tinygltf::Model& model, int index, int components, const std::string& what) {
  const tinygltf::Accessor& a = checkedAccessor(model, index, components, what);
  const int type = a.componentType;
  const size_t size = componentSize(type);
  const bool normalized = a.normalized;
  return readElements<float>(model, a, components, what, [&](const uint8_t* p, float* out) {
    for (int c = 0; c < components; ++c) out[c] = toFloat(p + c * size, type, normalized);
  });
}

std::vector<uint32_t> readIndices(const tinygltf::Model& model, int index, const std::string& what) {
  const tinygltf::Accessor& a = checkedAccessor(model, index, 1, what);
  const int type = a.componentType;
  if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
      type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
    throw Error(what + ": index accessor " + std::to_string(index) + " has componentType " + std::to_string(type) +
                ", expected unsigned byte, short or int");
  return readElements<uint32_t>(model, a, 1, what, [&](const uint8_t* p, uint32_t* out) { *out = toIndex(p, type); });
}

}  // namespace gi::gltf
