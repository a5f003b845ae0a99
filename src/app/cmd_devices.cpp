// `gi devices`: every OpenCL device, with the index and name `--device` accepts.
#include <cstdio>

#include "app/commands.h"
#include "cl/runtime.h"

namespace gi::app {

void registerDevicesCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("devices", "List OpenCL devices (select one with --device or GI_DEVICE)");
  cmd->callback([] {
    auto devices = cl::listDevices();
    auto chosen = cl::selectDevice("");
    for (auto& d : devices) std::printf("%s%s\n", d.describe().c_str(), d.id == chosen.id ? "  <- default" : "");
  });
}

}  // namespace gi::app
