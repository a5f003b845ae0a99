#include "app/commands.h"

namespace gi::app {

void registerCommands(CLI::App& app) {
  registerDevicesCommand(app);
  registerRenderCommand(app);
  registerCompareCommand(app);
  registerReferenceCommand(app);
  registerBenchCommand(app);
  registerSweepCommand(app);
}

}  // namespace gi::app
