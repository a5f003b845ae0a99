// Media search path (see media_path.h for the order and why).
#include "scene/media_path.h"

#include <cstdlib>
#include <system_error>

#include "util/error.h"

namespace gi {
namespace fs = std::filesystem;

namespace {

std::optional<fs::path> runningBinaryDir() {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return std::nullopt;
  return exe.parent_path();
}

bool isDirectory(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool isRegularFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

}  // namespace

std::vector<MediaDir> mediaSearchPath(const std::string& mediaDirFlag) {
  std::vector<MediaDir> dirs;
  if (!mediaDirFlag.empty()) dirs.push_back({mediaDirFlag, "--media"});
  if (const char* env = std::getenv("GI_MEDIA_DIR"); env && *env) dirs.push_back({env, "GI_MEDIA_DIR"});
  dirs.push_back({fs::current_path() / ".." / "shared" / "scenes", "../shared/scenes from the current directory"});
  dirs.push_back({fs::path(GI_SOURCE_DIR) / ".." / "shared" / "scenes", "source tree"});
  if (std::optional<fs::path> bin = runningBinaryDir())
    dirs.push_back({*bin / ".." / ".." / "shared" / "scenes", "binary directory"});
  dirs.push_back({fs::path(GI_SOURCE_DIR) / "scenes", "repository scene configs"});
  return dirs;
}

std::optional<fs::path> findMediaDir(const std::string& mediaDirFlag) {
  for (const MediaDir& d : mediaSearchPath(mediaDirFlag))
    if (d.origin != "repository scene configs" && isDirectory(d.path)) return fs::weakly_canonical(d.path);
  return std::nullopt;
}

fs::path resolveMediaFile(const std::string& name, const std::string& mediaDirFlag,
                          const std::vector<fs::path>& firstDirs) {
  if (name.empty()) throw Error("empty scene file name");
  fs::path wanted(name);
  if (wanted.is_absolute()) {
    if (isRegularFile(wanted)) return wanted;
    throw Error("scene file '" + name + "' not found (absolute path, no search)");
  }

  std::vector<MediaDir> places;
  for (const fs::path& d : firstDirs) places.push_back({d, "referring file's directory"});
  places.push_back({fs::current_path(), "current directory"});
  for (MediaDir& d : mediaSearchPath(mediaDirFlag)) places.push_back(std::move(d));

  std::string searched;
  for (const MediaDir& d : places) {
    fs::path candidate = d.path / wanted;
    if (isRegularFile(candidate)) return fs::weakly_canonical(candidate);
    searched += (searched.empty() ? "" : ", ") + candidate.string() + " (" + d.origin + ")";
  }
  throw Error("scene file '" + name + "' not found; searched: " + searched +
              "; point --media or GI_MEDIA_DIR at the folder that holds the scenes");
}

}  // namespace gi
