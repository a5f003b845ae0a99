// The flattened, device-ready scene: every glTF node instance baked into world-space triangles,
// materials and lights in the layouts of kernels/common/shared_types.h, one texture atlas.
//
// Producers: scene/gltf_loader (glTF 2.0 files), scene/cornell_box (built in), scene/scene_config
// (JSON configs that add lights, cameras, exposure). Consumer on the device: scene/device_scene.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "kernels/common/shared_types.h"

namespace gi {

struct Bounds {
  glm::vec3 lo{1e30f}, hi{-1e30f};
  void extend(const glm::vec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
  bool valid() const { return lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z; }
  glm::vec3 center() const { return (lo + hi) * 0.5f; }
  glm::vec3 extent() const { return hi - lo; }
  float radius() const { return 0.5f * glm::length(hi - lo); }
};

struct Camera {
  std::string name;
  glm::vec3 position{0, 0, 1};
  glm::vec3 target{0, 0, 0};
  glm::vec3 up{0, 1, 0};
  float yfov = 0.8f;  // vertical field of view, radians
  float znear = 0.01f;
  float zfar = 1000.0f;  // 0 would mean infinite; always set by the loader from the bounds if missing
};

// A texture decoded to RGBA8 with its full mip chain (level 0 first, then each half-size level).
struct Texture {
  std::string name;  // file or image name, for messages
  int width = 0, height = 0, levels = 0;
  bool srgb = false;  // colour data stored sRGB-encoded (decoded on the device when sampled)
  std::vector<uint8_t> rgba8;  // all levels, consecutive
};

struct Scene {
  std::string name;     // for messages and cache keys
  std::string source;   // file it came from, or "builtin:cornell"

  // Per vertex, world space (instances flattened).
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;   // unit; generated flat normals where the file had none
  std::vector<glm::vec4> tangents;  // xyz unit, w = handedness; zero where no normal map needs them
  std::vector<glm::vec2> uvs;       // TEXCOORD_0, (0,0) where missing

  // Per triangle.
  std::vector<glm::uvec3> triangles;        // vertex indices
  std::vector<uint32_t> triangleMaterial;   // index into materials
  std::vector<uint32_t> triangleInstance;   // which node instance (mesh primitive) it came from
  std::vector<std::string> instanceNames;   // per instance id: node/mesh name, for messages and light names

  std::vector<GiMaterial> materials;
  std::vector<Texture> textures;
  std::vector<GiLight> lights;       // punctual lights (file, config, emissive stand-ins)
  std::vector<std::string> lightNames;
  std::vector<Camera> cameras;
  int defaultCamera = 0;

  float exposure = 1.0f;  // display transform multiplier (scene config)
  int defaultWidth = 640, defaultHeight = 360;

  Bounds bounds;  // of all triangles

  size_t triangleCount() const { return triangles.size(); }
  void computeBounds();
};

}  // namespace gi
