// Scene config parsing, validation and application (see scene_config.h for the format).
#include "scene/scene_config.h"

#include <algorithm>
#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "scene/gltf_loader.h"
#include "scene/lights.h"
#include "scene/media_path.h"
#include "scene/scene_loader.h"
#include "scene/scene_setup.h"
#include "util/error.h"
#include "util/file_io.h"

namespace gi {
namespace {

using nlohmann::json;

// Reads typed values out of the JSON tree; every failure names the file and the field path.
class FieldReader {
public:
  explicit FieldReader(std::string fileName) : fileName_(std::move(fileName)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw Error(fileName_ + ": " + field + ": " + problem);
  }

  void onlyKeys(const json& object, const std::string& field, const std::set<std::string>& allowed,
                const std::string& context) const {
    if (!object.is_object()) fail(field, "must be an object");
    for (const auto& [key, value] : object.items())
      if (!allowed.count(key)) {
        std::string list;
        for (const std::string& k : allowed) list += (list.empty() ? "" : ", ") + k;
        throw Error(fileName_ + ": unknown key '" + key + "' in " + context + " (allowed: " + list + ")");
      }
  }

  float number(const json& j, const std::string& field) const {
    if (!j.is_number()) fail(field, "must be a number");
    double v = j.get<double>();
    if (!std::isfinite(v)) fail(field, "must be finite");
    return float(v);
  }

  int integer(const json& j, const std::string& field, int lo, int hi) const {
    if (!j.is_number_integer()) fail(field, "must be an integer");
    long long v = j.get<long long>();
    if (v < lo || v > hi) fail(field, "must be in " + std::to_string(lo) + ".." + std::to_string(hi));
    return int(v);
  }

  std::string string(const json& j, const std::string& field) const {
    if (!j.is_string()) fail(field, "must be a string");
    return j.get<std::string>();
  }

  bool boolean(const json& j, const std::string& field) const {
    if (!j.is_boolean()) fail(field, "must be true or false");
    return j.get<bool>();
  }

  glm::vec3 vec3(const json& j, const std::string& field) const {
    if (!j.is_array() || j.size() != 3) fail(field, "must be an array of 3 numbers");
    return {number(j[0], field + "[0]"), number(j[1], field + "[1]"), number(j[2], field + "[2]")};
  }

  glm::vec3 direction(const json& j, const std::string& field) const {
    glm::vec3 d = vec3(j, field);
    if (!(glm::length(d) > 1e-12f)) fail(field, "must not be the zero vector");
    return glm::normalize(d);
  }

private:
  std::string fileName_;
};

ConfigLight parseLight(const json& j, size_t index, const FieldReader& r) {
  const std::string at = "lights[" + std::to_string(index) + "]";
  if (!j.is_object()) r.fail(at, "must be an object");
  if (!j.contains("type")) r.fail(at + ".type", "is required (directional, point or spot)");
  const std::string type = r.string(j["type"], at + ".type");
  const std::set<std::string> common = {"type", "name", "color", "intensity"};
  std::set<std::string> allowed = common;
  if (type == "directional") {
    allowed.insert("direction");
  } else if (type == "point") {
    allowed.insert({"position", "range"});
  } else if (type == "spot") {
    allowed.insert({"position", "direction", "range", "inner_cone_deg", "outer_cone_deg"});
  } else {
    r.fail(at + ".type", "'" + type + "' is not directional, point or spot");
  }
  r.onlyKeys(j, at, allowed, at + " (a " + type + " light)");

  auto required = [&](const char* key) -> const json& {
    if (!j.contains(key)) r.fail(at + "." + key, std::string("is required for a ") + type + " light");
    return j[key];
  };
  ConfigLight out;
  out.name = j.contains("name") ? r.string(j["name"], at + ".name") : type + " " + std::to_string(index);
  glm::vec3 colour = j.contains("color") ? r.vec3(j["color"], at + ".color") : glm::vec3(1.0f);
  if (glm::any(glm::lessThan(colour, glm::vec3(0.0f)))) r.fail(at + ".color", "must not be negative");
  float intensity = r.number(required("intensity"), at + ".intensity");
  if (intensity < 0.0f) r.fail(at + ".intensity", "must be >= 0 (W/m² for directional, W/sr otherwise)");
  float range = j.contains("range") ? r.number(j["range"], at + ".range") : 0.0f;
  if (range < 0.0f) r.fail(at + ".range", "must be >= 0 (0 = infinite)");

  if (type == "directional") {
    out.light = makeDirectionalLight(r.direction(required("direction"), at + ".direction"), intensity * colour);
  } else if (type == "point") {
    out.light = makePointLight(r.vec3(required("position"), at + ".position"), intensity * colour, range);
  } else {
    float inner = j.contains("inner_cone_deg") ? r.number(j["inner_cone_deg"], at + ".inner_cone_deg") : 0.0f;
    float outer = j.contains("outer_cone_deg") ? r.number(j["outer_cone_deg"], at + ".outer_cone_deg") : 45.0f;
    if (!(outer > 0.0f && outer <= 90.0f)) r.fail(at + ".outer_cone_deg", "must be in (0, 90] degrees");
    if (!(inner >= 0.0f && inner < outer)) r.fail(at + ".inner_cone_deg", "must be in [0, outer_cone_deg) degrees");
    out.light = makeSpotLight(r.vec3(required("position"), at + ".position"),
                              r.direction(required("direction"), at + ".direction"), intensity * colour,
                              glm::radians(inner), glm::radians(outer), range);
  }
  return out;
}

Camera parseCamera(const json& j, size_t index, const FieldReader& r) {
  const std::string at = "cameras[" + std::to_string(index) + "]";
  r.onlyKeys(j, at, {"name", "position", "target", "up", "yfov_deg", "znear", "zfar"}, at);
  Camera c;
  c.name = j.contains("name") ? r.string(j["name"], at + ".name") : "config camera " + std::to_string(index);
  if (!j.contains("position")) r.fail(at + ".position", "is required");
  if (!j.contains("target")) r.fail(at + ".target", "is required");
  c.position = r.vec3(j["position"], at + ".position");
  c.target = r.vec3(j["target"], at + ".target");
  c.up = j.contains("up") ? r.direction(j["up"], at + ".up") : glm::vec3(0, 1, 0);
  glm::vec3 view = c.target - c.position;
  if (!(glm::length(view) > 1e-9f)) r.fail(at + ".target", "must differ from position");
  if (glm::length(glm::cross(glm::normalize(view), c.up)) < 1e-4f) r.fail(at + ".up", "must not be parallel to the view direction");
  float yfovDeg = j.contains("yfov_deg") ? r.number(j["yfov_deg"], at + ".yfov_deg") : 60.0f;
  if (!(yfovDeg > 0.0f && yfovDeg < 180.0f)) r.fail(at + ".yfov_deg", "must be in (0, 180) degrees");
  c.yfov = glm::radians(yfovDeg);
  c.znear = 0.0f;
  c.zfar = 0.0f;
  if (j.contains("znear")) {
    c.znear = r.number(j["znear"], at + ".znear");
    if (!(c.znear > 0.0f)) r.fail(at + ".znear", "must be > 0");
  }
  if (j.contains("zfar")) {
    c.zfar = r.number(j["zfar"], at + ".zfar");
    if (!(c.zfar > c.znear)) r.fail(at + ".zfar", "must be > znear");
  }
  return c;
}

}  // namespace

SceneConfig parseSceneConfig(const std::string& jsonText, const std::filesystem::path& file) {
  const std::string fileName = file.string();
  json root;
  try {
    root = json::parse(jsonText);
  } catch (const json::parse_error& e) {
    throw Error(fileName + ": invalid JSON: " + e.what());
  }
  FieldReader r(fileName);
  r.onlyKeys(root, "scene config", {"comment", "gltf", "builtin", "lights", "cameras", "default_camera", "exposure",
                                     "width", "height", "replace_file_lights"},
             "the scene config");
  SceneConfig config;
  config.file = file;
  if (root.contains("comment")) r.string(root["comment"], "comment");
  if (root.contains("gltf")) config.gltf = r.string(root["gltf"], "gltf");
  if (root.contains("builtin")) config.builtin = r.string(root["builtin"], "builtin");
  if (config.gltf.empty() == config.builtin.empty())
    throw Error(fileName + ": needs exactly one of \"gltf\" (a file) or \"builtin\" (e.g. \"cornell\")");
  if (root.contains("replace_file_lights"))
    config.replaceFileLights = r.boolean(root["replace_file_lights"], "replace_file_lights");
  if (root.contains("lights")) {
    if (!root["lights"].is_array()) r.fail("lights", "must be an array");
    for (size_t i = 0; i < root["lights"].size(); ++i) config.lights.push_back(parseLight(root["lights"][i], i, r));
  }
  if (root.contains("cameras")) {
    if (!root["cameras"].is_array()) r.fail("cameras", "must be an array");
    for (size_t i = 0; i < root["cameras"].size(); ++i) config.cameras.push_back(parseCamera(root["cameras"][i], i, r));
  }
  if (root.contains("default_camera")) config.defaultCamera = r.string(root["default_camera"], "default_camera");
  if (root.contains("exposure")) {
    config.exposure = r.number(root["exposure"], "exposure");
    if (!(*config.exposure > 0.0f)) r.fail("exposure", "must be > 0");
  }
  if (root.contains("width")) config.width = r.integer(root["width"], "width", 1, 16384);
  if (root.contains("height")) config.height = r.integer(root["height"], "height", 1, 16384);
  return config;
}

SceneConfig readSceneConfig(const std::filesystem::path& file) { return parseSceneConfig(readTextFile(file), file); }

void applySceneConfig(Scene& scene, const SceneConfig& config) {
  if (config.replaceFileLights) {
    // Keep the emissive stand-ins: the emitting geometry is still in the scene.
    std::vector<GiLight> lights;
    std::vector<std::string> names;
    for (size_t l = 0; l < scene.lights.size(); ++l)
      if (scene.lightNames[l].rfind(kEmitterLightPrefix, 0) == 0) {
        lights.push_back(scene.lights[l]);
        names.push_back(scene.lightNames[l]);
      }
    scene.lights = std::move(lights);
    scene.lightNames = std::move(names);
  }
  for (const ConfigLight& l : config.lights) {
    scene.lights.push_back(l.light);
    scene.lightNames.push_back(l.name);
  }

  const int firstConfigCamera = int(scene.cameras.size());
  for (Camera c : config.cameras) {
    fitClipPlanes(c, scene.bounds);
    scene.cameras.push_back(c);
  }
  if (config.defaultCamera) {
    auto it = std::find_if(scene.cameras.begin(), scene.cameras.end(),
                           [&](const Camera& c) { return c.name == *config.defaultCamera; });
    if (it == scene.cameras.end()) {
      std::string names;
      for (const Camera& c : scene.cameras) names += (names.empty() ? "'" : ", '") + c.name + "'";
      throw Error(config.file.string() + ": default_camera: '" + *config.defaultCamera +
                  "' is not a camera of the scene (cameras: " + names + ")");
    }
    scene.defaultCamera = int(it - scene.cameras.begin());
  } else if (!config.cameras.empty()) {
    scene.defaultCamera = firstConfigCamera;
  }

  if (config.exposure) scene.exposure = *config.exposure;
  if (config.width) scene.defaultWidth = *config.width;
  if (config.height) scene.defaultHeight = *config.height;
  scene.name = config.file.stem().string();
  scene.source = config.file.string();
}

Scene loadSceneConfig(const std::filesystem::path& file, const std::string& mediaDirFlag) {
  SceneConfig config = readSceneConfig(file);
  Scene scene;
  if (!config.builtin.empty()) {
    scene = makeBuiltinScene(config.builtin);
  } else {
    std::filesystem::path configDir = std::filesystem::absolute(file).parent_path();
    scene = loadGltfScene(resolveMediaFile(config.gltf, mediaDirFlag, {configDir}));
  }
  applySceneConfig(scene, config);
  return scene;
}

}  // namespace gi
