// Registration of the `gi` subcommands. Each subcommand's options and action live in its own file
// (cmd_devices.cpp, cmd_render.cpp, ...); registerCommands wires them into the CLI11 app.
#pragma once
#include <CLI/CLI.hpp>

namespace gi::app {

void registerCommands(CLI::App& app);

void registerDevicesCommand(CLI::App& app);
void registerRenderCommand(CLI::App& app);
void registerCompareCommand(CLI::App& app);
void registerReferenceCommand(CLI::App& app);
void registerBenchCommand(CLI::App& app);
void registerSweepCommand(CLI::App& app);

}  // namespace gi::app
