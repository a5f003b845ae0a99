// Kernel sources embedded at build time (cmake/EmbedKernels.cmake) and the #include expansion
// that turns one .cl file into one self-contained program text. Expansion inserts #line
// directives, so compiler messages name the original file and line ("kernels/raster/setup.cl:42").
#pragma once
#include <string>
#include <vector>

namespace gi::cl {

struct EmbeddedSource {
  const char* path;  // relative to the repository root, e.g. "kernels/common/types.h"
  std::string text;
};

const std::vector<EmbeddedSource>& embeddedKernelSources();

// Text of one kernel file. When GI_KERNEL_DIR is set (kernel development), the file is read from
// that directory (the repository root) instead of the embedded copy.
std::string kernelSourceText(const std::string& path);

// `path` with every `#include "x"` replaced by x's expanded text (each file once), with #line
// directives. Include names are resolved relative to kernels/ and to the including file.
std::string expandKernelIncludes(const std::string& path);

}  // namespace gi::cl
