// Writes small glTF 2.0 files for the scene-loader tests: JSON built with nlohmann::json, binary
// data in one buffer, saved as .gltf + .bin, .gltf with a base64 data URI, or .glb.
#pragma once
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace gi::test {

constexpr int kGltfByte = 5120, kGltfUByte = 5121, kGltfShort = 5122, kGltfUShort = 5123, kGltfUInt = 5125,
              kGltfFloat = 5126;

inline std::string base64(const std::vector<uint8_t>& data) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < data.size(); i += 3) {
    uint32_t v = uint32_t(data[i]) << 16;
    if (i + 1 < data.size()) v |= uint32_t(data[i + 1]) << 8;
    if (i + 2 < data.size()) v |= data[i + 2];
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += i + 1 < data.size() ? table[(v >> 6) & 63] : '=';
    out += i + 2 < data.size() ? table[v & 63] : '=';
  }
  return out;
}

class GltfWriter {
public:
  enum class Storage { BinFile, DataUri, Glb };

  nlohmann::json doc;  // edit freely; buffers are filled in by write()

  GltfWriter() {
    doc["asset"] = {{"version", "2.0"}};
    doc["scene"] = 0;
    doc["scenes"] = nlohmann::json::array({nlohmann::json{{"nodes", nlohmann::json::array()}}});
  }

  // Appends bytes (4-byte aligned) as a new bufferView; returns its index.
  int addView(const void* data, size_t bytes, size_t stride = 0) {
    while (bin_.size() % 4) bin_.push_back(0);
    nlohmann::json view = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}};
    if (stride) view["byteStride"] = stride;
    const uint8_t* p = static_cast<const uint8_t*>(data);
    bin_.insert(bin_.end(), p, p + bytes);
    return append("bufferViews", view);
  }

  template <typename T>
  int addAccessor(const std::vector<T>& values, int componentType, const std::string& type, bool normalized = false) {
    int components = type == "SCALAR" ? 1 : type[3] - '0';
    int view = addView(values.data(), values.size() * sizeof(T));
    nlohmann::json a = {{"bufferView", view}, {"componentType", componentType},
                        {"count", values.size() / components}, {"type", type}};
    if (normalized) a["normalized"] = true;
    return append("accessors", a);
  }

  int addPositions(const std::vector<float>& xyz) { return addAccessor(xyz, kGltfFloat, "VEC3"); }
  int addIndices(const std::vector<uint32_t>& idx) { return addAccessor(idx, kGltfUInt, "SCALAR"); }

  // A mesh with one primitive; attributes maps names to accessor indices.
  int addMesh(const std::string& name, const nlohmann::json& attributes, int indices = -1, int material = -1,
              int mode = 4) {
    nlohmann::json prim = {{"attributes", attributes}, {"mode", mode}};
    if (indices >= 0) prim["indices"] = indices;
    if (material >= 0) prim["material"] = material;
    return append("meshes", {{"name", name}, {"primitives", nlohmann::json::array({prim})}});
  }

  // Adds a node; root nodes join scene 0.
  int addNode(const nlohmann::json& node, bool root = true) {
    int index = append("nodes", node);
    if (root) doc["scenes"][0]["nodes"].push_back(index);
    return index;
  }

  int addMaterial(const nlohmann::json& material) { return append("materials", material); }

  // Writes <dir>/<name>.gltf (+ <name>.bin) or <name>.glb; returns the main file.
  std::filesystem::path write(const std::filesystem::path& dir, const std::string& name,
                              Storage storage = Storage::BinFile) const {
    nlohmann::json out = doc;
    std::vector<uint8_t> bin = bin_;
    while (bin.size() % 4) bin.push_back(0);
    if (!bin.empty()) {
      nlohmann::json buffer = {{"byteLength", bin.size()}};
      if (storage == Storage::BinFile) {
        buffer["uri"] = name + ".bin";
        std::ofstream(dir / (name + ".bin"), std::ios::binary).write(reinterpret_cast<const char*>(bin.data()), bin.size());
      } else if (storage == Storage::DataUri) {
        buffer["uri"] = "data:application/octet-stream;base64," + base64(bin);
      }
      out["buffers"] = nlohmann::json::array({buffer});
    }
    if (storage != Storage::Glb) {
      std::filesystem::path file = dir / (name + ".gltf");
      std::ofstream(file) << out.dump(1);
      return file;
    }
    std::string json = out.dump();
    while (json.size() % 4) json += ' ';
    std::filesystem::path file = dir / (name + ".glb");
    std::ofstream f(file, std::ios::binary);
    auto u32 = [&](uint32_t v) { f.write(reinterpret_cast<const char*>(&v), 4); };
    uint32_t total = 12 + 8 + uint32_t(json.size()) + (bin.empty() ? 0 : 8 + uint32_t(bin.size()));
    u32(0x46546C67);  // "glTF"
    u32(2);
    u32(total);
    u32(uint32_t(json.size()));
    u32(0x4E4F534A);  // "JSON"
    f.write(json.data(), json.size());
    if (!bin.empty()) {
      u32(uint32_t(bin.size()));
      u32(0x004E4942);  // "BIN\0"
      f.write(reinterpret_cast<const char*>(bin.data()), bin.size());
    }
    return file;
  }

private:
  std::vector<uint8_t> bin_;

  int append(const char* key, const nlohmann::json& value) {
    if (!doc.contains(key)) doc[key] = nlohmann::json::array();
    doc[key].push_back(value);
    return int(doc[key].size() - 1);
  }
};

}  // namespace gi::test
