// The media search path: --media beats GI_MEDIA_DIR beats the defaults, and a file that is
// nowhere gives a message listing every place searched.
#include <cstdlib>
#include <fstream>
#include <optional>

#include <gtest/gtest.h>

#include "scene/media_path.h"
#include "scene/scene_loader.h"
#include "scene_gltf_writer.h"
#include "test_support.h"
#include "util/error.h"

namespace gi {
namespace {

// Sets GI_MEDIA_DIR for one test and restores the previous value.
class ScopedMediaEnv {
public:
  explicit ScopedMediaEnv(const std::optional<std::string>& value) {
    if (const char* old = std::getenv("GI_MEDIA_DIR")) previous_ = old;
    if (value) setenv("GI_MEDIA_DIR", value->c_str(), 1);
    else unsetenv("GI_MEDIA_DIR");
  }
  ~ScopedMediaEnv() {
    if (previous_) setenv("GI_MEDIA_DIR", previous_->c_str(), 1);
    else unsetenv("GI_MEDIA_DIR");
  }

private:
  std::optional<std::string> previous_;
};

// <dir>/<tag>/only_here_<pid>.gltf: a name no default media folder has.
std::string writeMarkedScene(const std::filesystem::path& dir, const std::string& relative) {
  std::filesystem::create_directories((dir / relative).parent_path());
  test::GltfWriter w;
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  w.addNode({{"mesh", w.addMesh("tri", {{"POSITION", pos}})}});
  std::filesystem::path p = dir / relative;
  w.write(p.parent_path(), p.stem().string());
  return relative;
}

TEST(SceneMediaPath, FlagBeatsEnvironmentBeatsDefaults) {
  auto flagDir = test::tempDir("scene_media_flag");
  auto envDir = test::tempDir("scene_media_env");
  const std::string name = "media_test/only_here_" + std::to_string(::getpid()) + ".gltf";
  writeMarkedScene(flagDir, name);
  writeMarkedScene(envDir, name);

  ScopedMediaEnv env(envDir.string());
  EXPECT_EQ(resolveMediaFile(name, flagDir.string()), std::filesystem::weakly_canonical(flagDir / name));
  EXPECT_EQ(resolveMediaFile(name, ""), std::filesystem::weakly_canonical(envDir / name));
  EXPECT_EQ(loadScene(name, flagDir.string()).source, std::filesystem::weakly_canonical(flagDir / name).string());

  std::vector<MediaDir> path = mediaSearchPath(flagDir.string());
  ASSERT_GE(path.size(), 5u);
  EXPECT_EQ(path[0].origin, "--media");
  EXPECT_EQ(path[1].origin, "GI_MEDIA_DIR");
  EXPECT_EQ(findMediaDir(flagDir.string()), std::filesystem::weakly_canonical(flagDir));
}

TEST(SceneMediaPath, DefaultsIncludeSharedScenesBesideSourceTreeAndBinary) {
  ScopedMediaEnv env(std::nullopt);
  std::vector<MediaDir> path = mediaSearchPath("");
  std::vector<std::string> origins;
  for (const MediaDir& d : path) origins.push_back(d.origin);
  std::vector<std::string> expected = {"../shared/scenes from the current directory", "source tree", "binary directory",
                                       "repository scene configs"};
  EXPECT_EQ(origins, expected);
  EXPECT_EQ(path[1].path, std::filesystem::path(GI_SOURCE_DIR) / ".." / "shared" / "scenes");
}

TEST(SceneMediaPath, NotFoundListsEveryPlaceSearched) {
  auto envDir = test::tempDir("scene_media_missing");
  ScopedMediaEnv env(envDir.string());
  try {
    resolveMediaFile("no_such_scene_anywhere.gltf", "/flag/dir");
    FAIL() << "expected gi::Error";
  } catch (const Error& e) {
    std::string m = e.what();
    for (const char* part : {"no_such_scene_anywhere.gltf", "/flag/dir", "--media", envDir.c_str(), "GI_MEDIA_DIR",
                             "current directory", "source tree", "binary directory"})
      EXPECT_NE(m.find(part), std::string::npos) << part << " missing in: " << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << "one line";
  }
}

TEST(SceneMediaPath, AbsolutePathsAndSpecKinds) {
  auto dir = test::tempDir("scene_media_absolute");
  writeMarkedScene(dir, "abs/tri.gltf");
  EXPECT_EQ(loadScene((dir / "abs/tri.gltf").string(), "").triangleCount(), 1u);
  EXPECT_THROW(resolveMediaFile((dir / "abs/none.gltf").string(), ""), Error);
  EXPECT_EQ(loadScene("builtin:cornell", "").source, "builtin:cornell");
  EXPECT_EQ(loadScene("cornell", "").source, "builtin:cornell");
  EXPECT_THROW(loadScene("scene.obj", ""), Error);
  EXPECT_THROW(loadScene("builtin:nothing", ""), Error);
}

}  // namespace
}  // namespace gi
