// Options shared by the subcommands that render: device selection and the media search path.
#pragma once
#include <string>

#include <CLI/CLI.hpp>

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

}  // namespace gi::app
