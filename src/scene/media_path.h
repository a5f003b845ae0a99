// The media search path: where scene files (glTF, scene configs) named by a relative path are
// looked for. Large media (Sponza, Breakfast Room) are not in the repository; this team keeps them
// in ../shared/scenes beside the checkout, and users point elsewhere with --media or GI_MEDIA_DIR.
//
// Order (first match wins; a path the user typed that exists as given is always taken first):
//   1. the extra directories the caller names (e.g. the directory of the scene config that
//      refers to the file), then the current directory,
//   2. --media DIR (the flag),
//   3. $GI_MEDIA_DIR,
//   4. ../shared/scenes relative to the current directory,
//   5. GI_SOURCE_DIR/../shared/scenes (beside the source tree this binary was built from),
//   6. <directory of the running binary>/../../shared/scenes (build/gi -> ../shared/scenes),
//   7. GI_SOURCE_DIR/scenes (the scene configs that ship with the repository).
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace gi {

struct MediaDir {
  std::filesystem::path path;
  std::string origin;  // "--media", "GI_MEDIA_DIR", "source tree", ... for messages
};

// Places 2-7 above, in order, whether or not they exist (messages list every place searched).
std::vector<MediaDir> mediaSearchPath(const std::string& mediaDirFlag);

// The first directory of places 2-6 that exists: where the team's media are, if anywhere.
std::optional<std::filesystem::path> findMediaDir(const std::string& mediaDirFlag);

// Resolves `name` (absolute, or relative to the places above) to an existing regular file.
// Throws gi::Error naming `name` and every place searched when it is not found.
std::filesystem::path resolveMediaFile(const std::string& name, const std::string& mediaDirFlag,
                                       const std::vector<std::filesystem::path>& firstDirs = {});

}  // namespace gi
