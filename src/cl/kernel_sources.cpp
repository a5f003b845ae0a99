#include "cl/kernel_sources.h"

#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>

#include "util/error.h"
#include "util/file_io.h"

namespace gi::cl {

std::string kernelSourceText(const std::string& path) {
  if (const char* dir = std::getenv("GI_KERNEL_DIR"); dir && *dir) {
    return readTextFile(std::filesystem::path(dir) / path);
  }
  for (const auto& s : embeddedKernelSources())
    if (path == s.path) return s.text;
  throw Error("kernel source '" + path + "' is not embedded in this binary (rebuild after adding it)");
}

namespace {

bool sourceExists(const std::string& path) {
  if (const char* dir = std::getenv("GI_KERNEL_DIR"); dir && *dir)
    return std::filesystem::exists(std::filesystem::path(dir) / path);
  for (const auto& s : embeddedKernelSources())
    if (path == s.path) return true;
  return false;
}

void expand(const std::string& path, std::set<std::string>& seen, std::ostringstream& out) {
  if (!seen.insert(path).second) return;  // every header is included once (implicit #pragma once)
  std::istringstream in(kernelSourceText(path));
  std::string line;
  int lineNo = 0;
  out << "#line 1 \"" << path << "\"\n";
  while (std::getline(in, line)) {
    ++lineNo;
    std::string_view v(line);
    size_t p = v.find_first_not_of(" \t");
    if (p != std::string_view::npos && v.substr(p).starts_with("#include")) {
      size_t q1 = v.find('"'), q2 = v.rfind('"');
      if (q1 != std::string_view::npos && q2 > q1) {
        std::string name(v.substr(q1 + 1, q2 - q1 - 1));
        std::string sibling = std::filesystem::path(path).parent_path().append(name).lexically_normal().string();
        std::string fromRoot = "kernels/" + name;
        std::string resolved = sourceExists(sibling) ? sibling : fromRoot;
        if (!sourceExists(resolved))
          throw Error(path + ":" + std::to_string(lineNo) + ": included file '" + name + "' not found");
        expand(resolved, seen, out);
        out << "#line " << lineNo + 1 << " \"" << path << "\"\n";
        continue;
      }
    }
    if (p != std::string_view::npos && v.substr(p).starts_with("#pragma once")) {
      out << "\n";
      continue;
    }
    out << line << "\n";
  }
}

}  // namespace

std::string expandKernelIncludes(const std::string& path) {
  std::set<std::string> seen;
  std::ostringstream out;
  expand(path, seen, out);
  return out.str();
}

}  // namespace gi::cl
