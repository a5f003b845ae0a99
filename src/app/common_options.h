// Options shared by the subcommands that render: device selection and the media search path;
// and, for `gi render` and `gi bench`, the scene and its render settings.
#pragma once
#include <string>

#include <CLI/CLI.hpp>

#include "render/renderer.h"

namespace gi::app {

struct CommonOptions {
  std::string device;  // see cl::selectDevice
  std::string media;   // extra media folder searched first
};

inline void addCommonOptions(CLI::App* cmd, CommonOptions& o) {
  cmd->add_option("--device", o.device,
                  "OpenCL device: index, name substring, cpu or gpu (default: $GI_DEVICE, else first GPU, else CPU)");
  cmd->add_option("--media", o.media,
                  "folder searched first for scene media (then $GI_MEDIA_DIR, then ../shared/scenes)");
}

// The scene positional, --width, --height, --camera, --technique and --set.
inline void addRenderSettingsOptions(CLI::App* cmd, std::string& scene, RenderSettings& s) {
  cmd->add_option("scene", scene,
                  "scene: a .gltf/.glb file, a scene config .json, or nothing for the built-in Cornell box");
  cmd->add_option("--width", s.width, "image width in pixels (default: the scene's)")->check(CLI::Range(1, 16384));
  cmd->add_option("--height", s.height, "image height in pixels (default: the scene's)")->check(CLI::Range(1, 16384));
  cmd->add_option("--camera", s.camera, "camera name or index (default: the scene's default camera)");
  cmd->add_option("--technique", s.technique, "GI technique (direct = direct lighting only) or a chain: source+modifier, e.g. lpv+ssao");
  cmd->add_option("--set", s.sets, "parameter assignment name=value (repeatable; see gi render --list-params)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
}

}  // namespace gi::app
