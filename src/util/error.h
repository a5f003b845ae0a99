// One error type for everything the user can cause (bad files, bad flags, missing devices).
// The `gi` command prints what() on one line and exits non-zero; nothing else catches it.
#pragma once
#include <stdexcept>
#include <string>

namespace gi {

class Error : public std::runtime_error {
public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Warnings go to stderr with a common prefix; tests can silence them.
void warn(const std::string& message);
void setWarningsEnabled(bool enabled);

}  // namespace gi
