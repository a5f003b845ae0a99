// Shared helpers for the test suites: one OpenCL context per test process (PoCL context creation
// costs tens of ms), temporary directories, and running the `gi` binary.
#pragma once
#include <filesystem>
#include <string>

#include "cl/runtime.h"

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

}  // namespace gi::test
