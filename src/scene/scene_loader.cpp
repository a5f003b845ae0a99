// Scene entry point: dispatches a scene spec to the built-in scenes, the glTF loader or the
// scene config reader (see scene_loader.h).
#include "scene/scene_loader.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "scene/cornell_box.h"
#include "scene/gltf_loader.h"
#include "scene/media_path.h"
#include "scene/scene_config.h"
#include "scene/thin_wall.h"
#include "util/error.h"

namespace gi {

Scene makeBuiltinScene(const std::string& name) {
  if (name == "cornell") return makeCornellBox();
  if (name == "cornell_empty") {
    CornellOptions options;
    options.withBlocks = false;
    Scene s = makeCornellBox(options);
    s.name = "cornell_empty";
    s.source = "builtin:cornell_empty";
    return s;
  }
  if (name == "thin_wall") return makeThinWallScene();
  throw Error("unknown built-in scene '" + name + "' (built-in scenes: cornell, cornell_empty, thin_wall)");
}

Scene loadScene(const std::string& spec, const std::string& mediaDirFlag) {
  if (spec.empty() || spec == "cornell") return makeBuiltinScene("cornell");
  const std::string builtinPrefix = "builtin:";
  if (spec.rfind(builtinPrefix, 0) == 0) return makeBuiltinScene(spec.substr(builtinPrefix.size()));

  std::string extension = std::filesystem::path(spec).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (extension == ".gltf" || extension == ".glb") return loadGltfScene(resolveMediaFile(spec, mediaDirFlag));
  if (extension == ".json") return loadSceneConfig(resolveMediaFile(spec, mediaDirFlag), mediaDirFlag);
  throw Error("scene '" + spec +
              "': expected builtin:cornell (or cornell), a .gltf/.glb file or a .json scene config");
}

}  // namespace gi
