// The `gi` command line. Subcommands: devices, render (more arrive with the techniques).
#include <cstdio>
#include <iostream>

#include <CLI/CLI.hpp>

#include "app/commands.h"
#include "util/error.h"

int main(int argc, char** argv) {
  CLI::App app{"gi: real-time global illumination techniques on any OpenCL device"};
  app.require_subcommand(1);
  gi::app::registerCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "gi: error: %s (see gi --help)\n", e.what());
    return 2;
  } catch (const gi::Error& e) {
    std::fprintf(stderr, "gi: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gi: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
