#include "util/error.h"

#include <atomic>
#include <cstdio>

namespace gi {
namespace {
std::atomic<bool> g_warnings{true};
}
void warn(const std::string& message) {
  if (g_warnings) std::fprintf(stderr, "gi: warning: %s\n", message.c_str());
}
void setWarningsEnabled(bool enabled) { g_warnings = enabled; }
}  // namespace gi
