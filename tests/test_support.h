// Shared helpers for the test suites: one OpenCL context per test process (PoCL context creation
// costs tens of ms), temporary directories, and running the `gi` binary.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "render/renderer.h"

namespace gi::test {

cl::Context& context();  // the CPU (PoCL) device unless GI_DEVICE says otherwise

std::filesystem::path tempDir(const std::string& name);  // fresh, empty
std::string readFile(const std::filesystem::path& path);

struct CommandResult {
  int exitCode = 0;
  std::string output;  // stdout + stderr
};
// Runs the built `gi` binary with the given arguments (shell-quoted by the caller) and env prefix.
CommandResult runGi(const std::string& args, const std::string& envPrefix = "");

// Settings for technique tests on tiny images: small RSMs and shadow maps (64² RSM, 256² shadow
// maps, 128² cube faces) keep a frame at a few milliseconds on PoCL; `sets` come first.
RenderSettings smallRenderSettings(const std::string& technique, int width, int height, std::vector<std::string> sets);

}  // namespace gi::test
