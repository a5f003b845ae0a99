// glTF 2.0 -> gi::Scene (see gltf_loader.h for what is read, what is not, and the errors).
#include "scene/gltf_loader.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <tiny_gltf.h>

#include "scene/gltf_accessor.h"
#include "scene/lights.h"
#include "scene/scene_setup.h"
#include "scene/tangents.h"
#include "scene/textures.h"
#include "util/error.h"

namespace gi {
namespace fs = std::filesystem;
namespace {

// Extensions implemented here: a file may require them.
const std::set<std::string> kSupportedExtensions = {"KHR_lights_punctual", "KHR_materials_emissive_strength",
                                                    "KHR_mesh_quantization"};
// Optional extensions ignored on purpose, without a warning (they only refine the look).
const std::set<std::string> kQuietlyIgnoredExtensions = {"KHR_materials_specular"};

constexpr int kDefaultWidth = 640;

// tinygltf hands each image's encoded bytes here instead of decoding them itself (serially), so
// all images can be decoded in parallel later (textures.h). Images that tinygltf could not read
// (missing files) never arrive, which is how they are detected.
struct CapturedImages {
  std::map<int, std::vector<uint8_t>> bytes;
};

bool captureImageBytes(tinygltf::Image* image, const int imageIndex, std::string*, std::string*, int, int,
                       const unsigned char* bytes, int size, void* user) {
  auto* captured = static_cast<CapturedImages*>(user);
  captured->bytes[imageIndex].assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

bool hasBinaryGltfMagic(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  return in.gcount() == 4 && std::memcmp(magic, "glTF", 4) == 0;
}

// tinygltf's messages are newline-separated; gi::Error messages are one line.
std::string oneLine(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\n') {
      if (!out.empty() && out.back() != ' ') out += "; ";
    } else {
      out += c;
    }
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
  return out;
}

std::string quoted(const std::string& name) { return "'" + name + "'"; }

glm::dmat4 localMatrix(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) return glm::make_mat4(node.matrix.data());  // both column-major
  glm::dmat4 m(1.0);
  if (node.translation.size() == 3) m = glm::translate(m, glm::make_vec3(node.translation.data()));
  if (node.rotation.size() == 4) {
    // glTF stores x, y, z, w; glm's constructor takes w first.
    glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
    if (glm::length(q) > 0.0) m *= glm::mat4_cast(glm::normalize(q));
  }
  if (node.scale.size() == 3) m = glm::scale(m, glm::make_vec3(node.scale.data()));
  return m;
}

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// One primitive's triangles in object space, decoded once however many nodes use its mesh.
struct PrimitiveGeometry {
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::vec2> uvs;
  std::vector<glm::vec4> tangents;  // w == 0: none (material has no normal map)
  std::vector<glm::uvec3> triangles;
  uint32_t material = 0;
  bool usable = false;  // false: not triangles, or nothing left after skipping bad triangles
};

class GltfSceneBuilder {
public:
  explicit GltfSceneBuilder(const fs::path& file) : file_(file), fileName_(file.string()) {}

  Scene build() {
    readModel();
    warnAboutIgnoredFeatures();
    convertMaterials();
    addNodes();
    decodeImages();
    scene_.name = file_.stem().string();
    scene_.source = fileName_;
    finishScene(scene_, fileName_);
    if (!loaderWarnings_.empty()) warn(fileName_ + ": tinygltf: " + oneLine(loaderWarnings_));
    return std::move(scene_);
  }

private:
  fs::path file_;
  std::string fileName_;
  tinygltf::Model model_;
  std::string loaderWarnings_;
  CapturedImages images_;
  Scene scene_;

  std::map<std::pair<int, bool>, int> textureOfImage_;  // (image, srgb) -> scene texture
  std::vector<TextureRequest> textureRequests_;
  std::vector<bool> materialHasNormalMap_;
  int defaultMaterial_ = -1;
  std::map<std::pair<int, int>, PrimitiveGeometry> primitives_;  // (mesh, primitive)

  // ---- file -------------------------------------------------------------------------------

  void readModel() {
    std::error_code ec;
    if (!fs::is_regular_file(file_, ec)) throw Error(fileName_ + ": glTF file not found");
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&captureImageBytes, &images_);
    std::string err;
    bool ok = hasBinaryGltfMagic(file_) ? loader.LoadBinaryFromFile(&model_, &err, &loaderWarnings_, fileName_)
                                        : loader.LoadASCIIFromFile(&model_, &err, &loaderWarnings_, fileName_);
    // A file that needs an unsupported extension (e.g. Draco) often fails in tinygltf for that
    // very reason; name the extension, which is the actionable cause.
    checkExtensions();
    if (!ok) {
      std::string detail = oneLine(err);
      if (!loaderWarnings_.empty()) detail += (detail.empty() ? "" : "; ") + oneLine(loaderWarnings_);
      throw Error(fileName_ + ": cannot load glTF: " + (detail.empty() ? "unknown tinygltf error" : detail));
    }
  }

  void checkExtensions() const {
    for (const std::string& ext : model_.extensionsRequired)
      if (!kSupportedExtensions.count(ext))
        throw Error(fileName_ + ": requires glTF extension " + quoted(ext) +
                    ", which this loader does not support (supported: KHR_lights_punctual, "
                    "KHR_materials_emissive_strength, KHR_mesh_quantization)");
  }

  void warnAboutIgnoredFeatures() const {
    std::string ignored;
    for (const std::string& ext : model_.extensionsUsed)
      if (!kSupportedExtensions.count(ext) && !kQuietlyIgnoredExtensions.count(ext))
        ignored += (ignored.empty() ? "" : ", ") + ext;
    if (!ignored.empty()) warn(fileName_ + ": ignoring optional glTF extension(s) " + ignored);
    if (!model_.skins.empty()) warn(fileName_ + ": skins are ignored (skinned meshes are drawn unskinned, placed by their nodes)");
  }

  // ---- materials and textures -------------------------------------------------------------

  std::string imageLabel(int image) const {
    const tinygltf::Image& img = model_.images[image];
    if (!img.uri.empty() && img.uri.rfind("data:", 0) != 0) return img.uri;
    if (!img.name.empty()) return img.name;
    return "image " + std::to_string(image);
  }

  int textureSlot(int textureIndex, int texCoord, bool srgb, const std::string& what) {
    if (textureIndex < 0) return GI_NO_TEXTURE;
    if (size_t(textureIndex) >= model_.textures.size())
      throw Error(what + ": texture " + std::to_string(textureIndex) + " does not exist");
    if (texCoord != 0) warn(what + ": uses TEXCOORD_" + std::to_string(texCoord) + "; only TEXCOORD_0 is loaded");
    const tinygltf::Texture& tex = model_.textures[textureIndex];
    int image = tex.source;
    if (image < 0)
      throw Error(what + ": texture " + std::to_string(textureIndex) +
                  " has no PNG/JPG image source (only an extension's, which is not supported)");
    if (size_t(image) >= model_.images.size())
      throw Error(what + ": texture " + std::to_string(textureIndex) + " names image " + std::to_string(image) +
                  ", which does not exist");
    if (!images_.bytes.count(image)) {
      std::string detail = oneLine(loaderWarnings_);
      throw Error(what + ": texture image " + quoted(imageLabel(image)) + " could not be loaded" +
                  (detail.empty() ? "" : " (tinygltf: " + detail + ")"));
    }
    auto [it, added] = textureOfImage_.try_emplace({image, srgb}, int(textureRequests_.size()));
    if (added) textureRequests_.push_back({size_t(image), srgb});
    return it->second;
  }

  void convertMaterials() {
    for (size_t m = 0; m < model_.materials.size(); ++m) {
      const tinygltf::Material& src = model_.materials[m];
      const std::string what = fileName_ + ": material " + quoted(src.name.empty() ? std::to_string(m) : src.name);
      const tinygltf::PbrMetallicRoughness& pbr = src.pbrMetallicRoughness;
      GiMaterial mat = defaultMaterial();
      for (int c = 0; c < 4 && c < int(pbr.baseColorFactor.size()); ++c) mat.base_color[c] = float(pbr.baseColorFactor[c]);
      mat.metallic = float(pbr.metallicFactor);
      mat.roughness = float(pbr.roughnessFactor);

      double strength = 1.0;
      if (auto ext = src.extensions.find("KHR_materials_emissive_strength"); ext != src.extensions.end())
        if (ext->second.Has("emissiveStrength") && ext->second.Get("emissiveStrength").IsNumber())
          strength = ext->second.Get("emissiveStrength").GetNumberAsDouble();
      for (int c = 0; c < 3 && c < int(src.emissiveFactor.size()); ++c) mat.emissive[c] = float(src.emissiveFactor[c] * strength);

      if (src.alphaMode == "MASK") {
        mat.alpha_mode = GI_ALPHA_MASK;
      } else if (src.alphaMode == "BLEND") {
        mat.alpha_mode = GI_ALPHA_BLEND;
      } else if (src.alphaMode != "OPAQUE") {
        throw Error(what + ": alphaMode " + quoted(src.alphaMode) + " is not OPAQUE, MASK or BLEND");
      }
      mat.alpha_cutoff = float(src.alphaCutoff);
      mat.double_sided = src.doubleSided ? 1 : 0;
      mat.normal_scale = float(src.normalTexture.scale);

      mat.base_color_tex = textureSlot(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, true, what);
      mat.metallic_roughness_tex =
          textureSlot(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord, false, what);
      mat.normal_tex = textureSlot(src.normalTexture.index, src.normalTexture.texCoord, false, what);
      mat.emissive_tex = textureSlot(src.emissiveTexture.index, src.emissiveTexture.texCoord, true, what);
      scene_.materials.push_back(mat);
      materialHasNormalMap_.push_back(mat.normal_tex != GI_NO_TEXTURE);
    }
  }

  // glTF's default material (spec §3.9.6): every factor at its default, no textures.
  static GiMaterial defaultMaterial() {
    GiMaterial m{};
    for (float& c : m.base_color) c = 1.0f;
    m.metallic = 1.0f;
    m.roughness = 1.0f;
    m.alpha_cutoff = 0.5f;
    m.normal_scale = 1.0f;
    m.alpha_mode = GI_ALPHA_OPAQUE;
    m.base_color_tex = m.metallic_roughness_tex = m.normal_tex = m.emissive_tex = GI_NO_TEXTURE;
    return m;
  }

  uint32_t materialOf(const tinygltf::Primitive& prim, const std::string& what) {
    if (prim.material >= 0) {
      if (size_t(prim.material) >= model_.materials.size())
        throw Error(what + ": material " + std::to_string(prim.material) + " does not exist");
      return uint32_t(prim.material);
    }
    if (defaultMaterial_ < 0) {
      defaultMaterial_ = int(scene_.materials.size());
      scene_.materials.push_back(defaultMaterial());
      materialHasNormalMap_.push_back(false);
    }
    return uint32_t(defaultMaterial_);
  }

  void decodeImages() {
    std::vector<EncodedImage> encoded(model_.images.size());
    for (const TextureRequest& r : textureRequests_) {
      EncodedImage& e = encoded[r.image];
      if (e.bytes.empty()) {
        e.name = imageLabel(int(r.image));
        e.bytes = std::move(images_.bytes[int(r.image)]);
      }
    }
    try {
      scene_.textures = decodeTextures(encoded, textureRequests_);
    } catch (const Error& e) {
      throw Error(fileName_ + ": " + e.what());
    }
  }

  // ---- nodes ------------------------------------------------------------------------------

  void addNodes() {
    std::vector<int> roots;
    if (!model_.scenes.empty()) {
      int chosen = model_.defaultScene >= 0 ? model_.defaultScene : 0;
      if (size_t(chosen) >= model_.scenes.size())
        throw Error(fileName_ + ": default scene " + std::to_string(chosen) + " does not exist");
      roots = model_.scenes[chosen].nodes;
    } else {
      std::vector<bool> isChild(model_.nodes.size(), false);
      for (const tinygltf::Node& n : model_.nodes)
        for (int c : n.children)
          if (c >= 0 && size_t(c) < isChild.size()) isChild[c] = true;
      for (size_t n = 0; n < model_.nodes.size(); ++n)
        if (!isChild[n]) roots.push_back(int(n));
    }
    std::vector<bool> onPath(model_.nodes.size(), false);
    for (int root : roots) addNode(root, glm::dmat4(1.0), onPath);
  }

  void addNode(int index, const glm::dmat4& parent, std::vector<bool>& onPath) {
    if (index < 0 || size_t(index) >= model_.nodes.size())
      throw Error(fileName_ + ": node " + std::to_string(index) + " does not exist");
    if (onPath[index]) throw Error(fileName_ + ": the node hierarchy has a cycle through node " + std::to_string(index));
    const tinygltf::Node& node = model_.nodes[index];
    const glm::dmat4 world = parent * localMatrix(node);
    const std::string nodeName = node.name.empty() ? "node " + std::to_string(index) : node.name;

    if (node.mesh >= 0) addMeshInstance(node.mesh, world, nodeName);
    if (node.camera >= 0) addCamera(node.camera, world, nodeName);
    if (auto ext = node.extensions.find("KHR_lights_punctual"); ext != node.extensions.end())
      if (ext->second.Has("light") && ext->second.Get("light").IsNumber())
        addLight(ext->second.Get("light").GetNumberAsInt(), world, nodeName);

    onPath[index] = true;
    for (int child : node.children) addNode(child, world, onPath);
    onPath[index] = false;
  }

  // ---- meshes -----------------------------------------------------------------------------

  void addMeshInstance(int meshIndex, const glm::dmat4& world, const std::string& nodeName) {
    if (size_t(meshIndex) >= model_.meshes.size())
      throw Error(fileName_ + ": node " + quoted(nodeName) + " names mesh " + std::to_string(meshIndex) +
                  ", which does not exist");
    const tinygltf::Mesh& mesh = model_.meshes[meshIndex];
    float det = glm::determinant(glm::mat3(glm::mat4(world)));
    if (!(std::abs(det) > 0.0f) || !std::isfinite(det)) {
      warn(fileName_ + ": node " + quoted(nodeName) + " has a singular transform; its mesh is skipped");
      return;
    }
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const PrimitiveGeometry& geometry = primitive(meshIndex, int(p));
      if (!geometry.usable) continue;
      std::string instanceName = nodeName;
      if (mesh.primitives.size() > 1) instanceName.append("/").append(std::to_string(p));
      addInstance(geometry, glm::mat4(world), instanceName);
    }
  }

  void addInstance(const PrimitiveGeometry& g, const glm::mat4& world, const std::string& name) {
    const glm::mat3 linear(world);
    const glm::mat3 normalMatrix = glm::inverseTranspose(linear);
    const bool mirrors = glm::determinant(linear) < 0.0f;
    const uint32_t base = uint32_t(scene_.positions.size());
    const uint32_t instance = uint32_t(scene_.instanceNames.size());
    scene_.instanceNames.push_back(name);

    for (size_t v = 0; v < g.positions.size(); ++v) {
      scene_.positions.push_back(glm::vec3(world * glm::vec4(g.positions[v], 1.0f)));
      scene_.normals.push_back(glm::normalize(normalMatrix * g.normals[v]));
      scene_.uvs.push_back(g.uvs[v]);
      const glm::vec4& t = g.tangents[v];
      // A mirroring transform turns a right-handed tangent frame into a left-handed one.
      scene_.tangents.push_back(t.w == 0.0f ? glm::vec4(0.0f)
                                            : glm::vec4(glm::normalize(linear * glm::vec3(t)), mirrors ? -t.w : t.w));
    }
    for (const glm::uvec3& t : g.triangles) {
      // Mirroring also reverses the winding; swap two corners so the front face stays the front.
      scene_.triangles.push_back(mirrors ? glm::uvec3(t.x, t.z, t.y) + base : t + base);
      scene_.triangleMaterial.push_back(g.material);
      scene_.triangleInstance.push_back(instance);
    }
  }

  const PrimitiveGeometry& primitive(int meshIndex, int primIndex) {
    auto key = std::make_pair(meshIndex, primIndex);
    auto it = primitives_.find(key);
    if (it == primitives_.end()) it = primitives_.emplace(key, decodePrimitive(meshIndex, primIndex)).first;
    return it->second;
  }

  std::vector<glm::uvec3> assembleTriangles(const std::vector<uint32_t>& idx, int mode, const std::string& what) {
    std::vector<glm::uvec3> tris;
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      if (idx.size() % 3 != 0)
        throw Error(what + ": " + std::to_string(idx.size()) + " indices, not a multiple of 3 for triangles");
      for (size_t i = 0; i + 2 < idx.size(); i += 3) tris.emplace_back(idx[i], idx[i + 1], idx[i + 2]);
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      // glTF 2.0 §3.7.2.1: triangle i = (v_i, v_{i+1+i%2}, v_{i+2-i%2}), alternating the winding back.
      for (size_t i = 0; i + 2 < idx.size(); ++i)
        tris.emplace_back(idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]);
    } else {  // TRIANGLE_FAN: triangle i = (v_{i+1}, v_{i+2}, v_0)
      for (size_t i = 0; i + 2 < idx.size(); ++i) tris.emplace_back(idx[i + 1], idx[i + 2], idx[0]);
    }
    return tris;
  }

  PrimitiveGeometry decodePrimitive(int meshIndex, int primIndex) {
    const tinygltf::Mesh& mesh = model_.meshes[meshIndex];
    const tinygltf::Primitive& prim = mesh.primitives[primIndex];
    const std::string what = fileName_ + ": mesh " + quoted(mesh.name.empty() ? std::to_string(meshIndex) : mesh.name) +
                             " primitive " + std::to_string(primIndex);
    PrimitiveGeometry g;
    const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
    if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) {
      warn(what + ": mode " + std::to_string(mode) + " (points or lines) is not rendered; skipped");
      return g;
    }
    auto attribute = [&](const char* name) {
      auto it = prim.attributes.find(name);
      return it == prim.attributes.end() ? -1 : it->second;
    };
    if (attribute("POSITION") < 0) {
      warn(what + ": has no POSITION attribute; skipped");
      return g;
    }
    g.material = materialOf(prim, what);

    std::vector<float> raw = gltf::readFloats(model_, attribute("POSITION"), 3, what + " attribute POSITION");
    const size_t vertexCount = raw.size() / 3;
    // Every attribute has one element per vertex (glTF 2.0 §3.7.2.1).
    auto readAttribute = [&](int accessor, const char* name, int components) {
      std::vector<float> values = gltf::readFloats(model_, accessor, components, what + " attribute " + name);
      if (values.size() != vertexCount * components)
        throw Error(what + ": attribute " + name + " has " + std::to_string(values.size() / components) +
                    " elements, POSITION has " + std::to_string(vertexCount));
      return values;
    };
    std::vector<glm::vec3> positions(vertexCount);
    std::memcpy(positions.data(), raw.data(), raw.size() * sizeof(float));

    std::vector<uint32_t> indices;
    if (prim.indices >= 0) {
      indices = gltf::readIndices(model_, prim.indices, what + " indices");
      for (size_t k = 0; k < indices.size(); ++k)
        if (indices[k] >= vertexCount)
          throw Error(what + ": index " + std::to_string(indices[k]) + " (at position " + std::to_string(k) +
                      ") is out of range: the primitive has " + std::to_string(vertexCount) + " vertices");
    } else {
      indices.resize(vertexCount);
      for (size_t v = 0; v < vertexCount; ++v) indices[v] = uint32_t(v);
    }
    std::vector<glm::uvec3> triangles = assembleTriangles(indices, mode, what);
    triangles = withoutBadTriangles(triangles, positions, what);
    if (triangles.empty()) return g;

    std::vector<glm::vec2> uvs(vertexCount, glm::vec2(0.0f));
    if (int a = attribute("TEXCOORD_0"); a >= 0) {
      raw = readAttribute(a, "TEXCOORD_0", 2);
      for (size_t v = 0; v < vertexCount; ++v) {
        glm::vec2 uv(raw[2 * v], raw[2 * v + 1]);
        uvs[v] = std::isfinite(uv.x) && std::isfinite(uv.y) ? uv : glm::vec2(0.0f);
      }
    }
    std::vector<glm::vec4> tangents;
    if (int a = attribute("TANGENT"); a >= 0 && materialHasNormalMap_[g.material]) {
      raw = readAttribute(a, "TANGENT", 4);
      tangents.resize(vertexCount);
      for (size_t v = 0; v < vertexCount && !tangents.empty(); ++v) {
        glm::vec3 t(raw[4 * v], raw[4 * v + 1], raw[4 * v + 2]);
        float len = glm::length(t);
        if (finite(t) && len > 0.0f)
          tangents[v] = glm::vec4(t / len, raw[4 * v + 3] < 0.0f ? -1.0f : 1.0f);
        else
          tangents.clear();  // a broken TANGENT attribute: generate the frames instead
      }
    }

    if (int a = attribute("NORMAL"); a >= 0) {
      raw = readAttribute(a, "NORMAL", 3);
      g.normals.resize(vertexCount);
      std::memcpy(g.normals.data(), raw.data(), raw.size() * sizeof(float));
      repairNormals(g.normals, positions, triangles);
      g.positions = std::move(positions);
      g.uvs = std::move(uvs);
      g.triangles = std::move(triangles);
    } else {
      // glTF 2.0 §3.7.2.1: without normals, flat shading (each triangle gets its own vertices),
      // and any TANGENT attribute is ignored.
      tangents.clear();
      for (const glm::uvec3& t : triangles) {
        glm::vec3 n = glm::normalize(glm::cross(positions[t.y] - positions[t.x], positions[t.z] - positions[t.x]));
        uint32_t first = uint32_t(g.positions.size());
        for (int k = 0; k < 3; ++k) {
          g.positions.push_back(positions[t[k]]);
          g.normals.push_back(n);
          g.uvs.push_back(uvs[t[k]]);
        }
        g.triangles.emplace_back(first, first + 1, first + 2);
      }
    }

    if (!materialHasNormalMap_[g.material])
      g.tangents.assign(g.positions.size(), glm::vec4(0.0f));
    else if (!tangents.empty())
      g.tangents = std::move(tangents);
    else
      g.tangents = generateTangents(g.positions, g.normals, g.uvs, g.triangles);
    g.usable = true;
    return g;
  }

  // Drops triangles with a NaN/Inf corner or zero area (a repeated index, or corners whose edge
  // cross product is exactly zero); slivers of tiny but non-zero area are kept, they render
  // correctly. One warning per primitive with the counts.
  std::vector<glm::uvec3> withoutBadTriangles(const std::vector<glm::uvec3>& triangles,
                                              const std::vector<glm::vec3>& positions, const std::string& what) {
    std::vector<glm::uvec3> kept;
    kept.reserve(triangles.size());
    size_t nonFinite = 0, degenerate = 0;
    for (const glm::uvec3& t : triangles) {
      const glm::vec3 &a = positions[t.x], &b = positions[t.y], &c = positions[t.z];
      if (!finite(a) || !finite(b) || !finite(c)) {
        ++nonFinite;
        continue;
      }
      glm::dvec3 cross = glm::cross(glm::dvec3(b) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a));
      if (t.x == t.y || t.y == t.z || t.x == t.z || cross == glm::dvec3(0.0)) {
        ++degenerate;
        continue;
      }
      kept.push_back(t);
    }
    if (nonFinite + degenerate > 0)
      warn(what + ": skipped " + std::to_string(nonFinite + degenerate) + " of " + std::to_string(triangles.size()) +
           " triangles (" + std::to_string(nonFinite) + " with NaN/Inf vertices, " + std::to_string(degenerate) +
           " degenerate)");
    return kept;
  }

  // File normals that are not finite or have zero length are replaced by the area-weighted
  // normal of the triangles around the vertex (or +z when it is in none).
  static void repairNormals(std::vector<glm::vec3>& normals, const std::vector<glm::vec3>& positions,
                            const std::vector<glm::uvec3>& triangles) {
    std::vector<bool> broken(normals.size(), false);
    bool any = false;
    for (size_t v = 0; v < normals.size(); ++v) {
      float len = glm::length(normals[v]);
      broken[v] = !finite(normals[v]) || !(len > 1e-20f);
      if (broken[v]) {
        normals[v] = glm::vec3(0.0f);
        any = true;
      } else {
        normals[v] /= len;
      }
    }
    if (!any) return;
    for (const glm::uvec3& t : triangles) {
      glm::vec3 areaNormal = glm::cross(positions[t.y] - positions[t.x], positions[t.z] - positions[t.x]);
      for (int k = 0; k < 3; ++k)
        if (broken[t[k]]) normals[t[k]] += areaNormal;
    }
    for (size_t v = 0; v < normals.size(); ++v)
      if (broken[v]) {
        float len = glm::length(normals[v]);
        normals[v] = len > 0.0f ? normals[v] / len : glm::vec3(0, 0, 1);
      }
  }

  // ---- cameras and lights -----------------------------------------------------------------

  void addCamera(int cameraIndex, const glm::dmat4& world, const std::string& nodeName) {
    if (size_t(cameraIndex) >= model_.cameras.size())
      throw Error(fileName_ + ": node " + quoted(nodeName) + " names camera " + std::to_string(cameraIndex) +
                  ", which does not exist");
    const tinygltf::Camera& src = model_.cameras[cameraIndex];
    const std::string name = !src.name.empty() ? src.name : nodeName;
    if (src.type != "perspective") {
      warn(fileName_ + ": camera " + quoted(name) + " is " + src.type + "; only perspective cameras are supported, skipped");
      return;
    }
    const tinygltf::PerspectiveCamera& p = src.perspective;
    if (!(p.yfov > 0.0 && p.yfov < M_PI))
      throw Error(fileName_ + ": camera " + quoted(name) + ": yfov " + std::to_string(p.yfov) +
                  " is not in (0, pi) radians");
    Camera c;
    c.name = name;
    c.position = glm::vec3(world * glm::dvec4(0, 0, 0, 1));
    const glm::dmat3 linear(world);
    c.target = c.position + glm::vec3(glm::normalize(linear * glm::dvec3(0, 0, -1)));
    c.up = glm::vec3(glm::normalize(linear * glm::dvec3(0, 1, 0)));
    c.yfov = float(p.yfov);
    c.znear = p.znear > 0.0 ? float(p.znear) : 0.0f;  // 0: fitted to the bounds
    c.zfar = p.zfar > c.znear ? float(p.zfar) : 0.0f;
    if (scene_.cameras.empty() && p.aspectRatio > 0.0) {
      scene_.defaultWidth = kDefaultWidth;
      scene_.defaultHeight = std::max(1, int(std::lround(kDefaultWidth / p.aspectRatio)));
    }
    scene_.cameras.push_back(c);
  }

  void addLight(int lightIndex, const glm::dmat4& world, const std::string& nodeName) {
    if (lightIndex < 0 || size_t(lightIndex) >= model_.lights.size())
      throw Error(fileName_ + ": node " + quoted(nodeName) + " names KHR_lights_punctual light " +
                  std::to_string(lightIndex) + ", which does not exist");
    const tinygltf::Light& src = model_.lights[lightIndex];
    const std::string name = src.name.empty() ? "light " + std::to_string(lightIndex) : src.name;
    const std::string what = fileName_ + ": light " + quoted(name);
    glm::vec3 colour(1.0f);
    if (src.color.size() == 3) colour = glm::vec3(src.color[0], src.color[1], src.color[2]);
    if (!(src.intensity >= 0.0) || !finite(colour) || glm::any(glm::lessThan(colour, glm::vec3(0.0f))))
      throw Error(what + ": intensity and colour must be finite and >= 0");
    if (!(src.range >= 0.0)) throw Error(what + ": range must be > 0 (or absent)");
    // KHR_lights_punctual units are this engine's units (ALGORITHMS.md §0): directional
    // intensity is irradiance in W/m² ("lux"), point/spot intensity is W/sr ("candela").
    const glm::vec3 intensity = float(src.intensity) * colour;
    const glm::vec3 position(world * glm::dvec4(0, 0, 0, 1));
    const glm::vec3 direction(glm::normalize(glm::dmat3(world) * glm::dvec3(0, 0, -1)));
    GiLight light;
    if (src.type == "directional") {
      light = makeDirectionalLight(direction, intensity);
    } else if (src.type == "point") {
      light = makePointLight(position, intensity, float(src.range));
    } else if (src.type == "spot") {
      double inner = src.spot.innerConeAngle, outer = src.spot.outerConeAngle;
      if (!(inner >= 0.0 && inner < outer && outer <= 0.5 * M_PI + 1e-9))
        throw Error(what + ": spot cone angles must satisfy 0 <= innerConeAngle < outerConeAngle <= pi/2 (found " +
                    std::to_string(inner) + ", " + std::to_string(outer) + ")");
      light = makeSpotLight(position, direction, intensity, float(inner), float(outer), float(src.range));
    } else {
      warn(what + ": unknown light type " + quoted(src.type) + "; skipped");
      return;
    }
    scene_.lights.push_back(light);
    scene_.lightNames.push_back(name);
  }
};

}  // namespace

Scene loadGltfScene(const fs::path& file) { return GltfSceneBuilder(file).build(); }

}  // namespace gi
