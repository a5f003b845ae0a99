// Whole-file helpers. Outputs are written to a temporary file beside the target and renamed,
// so a failure never leaves a partial output file behind.
#pragma once
#include <filesystem>
#include <functional>
#include <string>

namespace gi {

std::string readTextFile(const std::filesystem::path& path);  // throws gi::Error naming the path

// Calls write(tmpPath) and renames tmpPath to path on success; removes tmpPath on any failure.
void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path& tmpPath)>& write);

}  // namespace gi
