#include "app/commands.h"
#include "util/error.h"
namespace gi::app {
void registerRenderCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("render", "Render a scene (work in progress)");
  cmd->callback([] { throw Error("render: not built yet"); });
}
}  // namespace gi::app
