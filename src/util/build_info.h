// Facts about the build that results must carry (`gi bench`, `gi sweep`).
#pragma once

namespace gi {

// `git describe --always --dirty --abbrev=12` of the source tree when CMake last configured it
// ("unknown" outside a git checkout). CMake re-configures whenever a commit or checkout moves HEAD,
// but a later edit that is not committed does not add "-dirty" until the next configure.
extern const char* const kGitRevision;

}  // namespace gi
