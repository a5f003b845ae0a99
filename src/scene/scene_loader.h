// The one entry point for getting a scene: `gi::loadScene(spec, mediaDirFlag)`.
//
//   spec "" | "cornell" | "builtin:cornell"  -> the built-in Cornell box (cornell_box.h)
//   "builtin:cornell_empty"                  -> the Cornell box without its two blocks
//   "builtin:thin_wall"                      -> two rooms split by a 2 cm wall (thin_wall.h)
//   *.gltf | *.glb                           -> glTF 2.0 file (gltf_loader.h)
//   *.json                                   -> scene config (scene_config.h)
//
// Relative file names are resolved through the media search path (media_path.h); mediaDirFlag
// is the --media DIR command-line value ("" when not given). Errors are gi::Error. Nothing is
// printed on success.
#pragma once
#include <string>

#include "scene/scene.h"

namespace gi {

Scene loadScene(const std::string& spec, const std::string& mediaDirFlag);

// Built-in scenes by name ("cornell", "cornell_empty", "thin_wall"); throws gi::Error listing the names.
Scene makeBuiltinScene(const std::string& name);

}  // namespace gi
