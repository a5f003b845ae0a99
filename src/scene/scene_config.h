// Scene configs (JSON): a glTF file or built-in scene plus the lights, cameras, exposure and image
// size to render it with. Example (all keys but one of "gltf"/"builtin" optional):
//
//   {
//     "comment": "free text, ignored",
//     "gltf": "sponza/Sponza.gltf",          // config's directory, then the media search path
//     "builtin": "cornell",                  // instead of "gltf": cornell | cornell_empty | thin_wall
//     "replace_file_lights": false,          // true: drop the file's KHR_lights_punctual lights
//                                            // (emissive stand-ins stay: their geometry stays)
//     "lights": [
//       {"type": "directional", "name": "sun", "direction": [0.2, -1, 0.1],
//        "color": [1, 0.95, 0.9], "intensity": 20},                      // W/m² irradiance
//       {"type": "point", "position": [0, 2, 0], "intensity": 5, "range": 0},   // W/sr
//       {"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "intensity": 5,
//        "inner_cone_deg": 20, "outer_cone_deg": 40, "range": 0}
//     ],
//     "cameras": [{"name": "nave", "position": [..], "target": [..], "up": [0, 1, 0],
//                  "yfov_deg": 60, "znear": 0.05, "zfar": 100}],
//     "default_camera": "nave",              // any camera of the file or the config
//     "exposure": 1.0, "width": 1280, "height": 720
//   }
//
// Defaults: color [1,1,1]; name "<type> <i>"; range 0 (infinite); cones 0° / 45° (the glTF
// defaults); camera up +y, yfov 60°, znear/zfar fitted to the scene bounds. Config cameras are
// added after the file's; without default_camera the first config camera (else the file's default)
// is used. Unknown keys, wrong types and invalid values throw gi::Error naming the file and field.
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace gi {

struct ConfigLight {
  std::string name;
  GiLight light;
};

struct SceneConfig {
  std::filesystem::path file;  // for messages and to resolve "gltf" against its directory
  std::string gltf;            // as written; empty when builtin is set
  std::string builtin;
  bool replaceFileLights = false;
  std::vector<ConfigLight> lights;
  std::vector<Camera> cameras;  // znear/zfar 0 where not given
  std::optional<std::string> defaultCamera;
  std::optional<float> exposure;
  std::optional<int> width, height;
};

// Parses and validates; `file` is used for messages and relative paths.
SceneConfig parseSceneConfig(const std::string& jsonText, const std::filesystem::path& file);
SceneConfig readSceneConfig(const std::filesystem::path& file);

// Applies lights, cameras, default camera, exposure and size to a loaded scene.
void applySceneConfig(Scene& scene, const SceneConfig& config);

// Reads the config, loads its glTF (resolved against the config's directory, then the media
// search path with `mediaDirFlag`) or built-in scene, and applies the config.
Scene loadSceneConfig(const std::filesystem::path& file, const std::string& mediaDirFlag);

}  // namespace gi
