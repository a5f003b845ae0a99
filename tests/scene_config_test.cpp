// Scene configs: parsing, applying lights/cameras/exposure/size, paths relative to the config,
// and an error naming the file and field for each kind of bad input.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "scene/scene_config.h"
#include "scene/scene_loader.h"
#include "scene_gltf_writer.h"
#include "test_support.h"
#include "util/error.h"

namespace gi {
namespace {

std::filesystem::path writeConfig(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  std::filesystem::path file = dir / name;
  std::ofstream(file) << text;
  return file;
}

std::string configError(const std::string& text) {
  try {
    parseSceneConfig(text, "bad.json");
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a gi::Error for " << text;
  return "";
}

void expectMentions(const std::string& message, std::initializer_list<const char*> parts) {
  for (const char* p : parts) EXPECT_NE(message.find(p), std::string::npos) << "'" << p << "' missing in: " << message;
}

TEST(SceneConfig, BuiltinWithLightsCamerasAndDisplaySettings) {
  auto dir = test::tempDir("scene_config_builtin");
  auto file = writeConfig(dir, "box.json", R"({
    "comment": "test config",
    "builtin": "cornell",
    "lights": [
      {"type": "directional", "name": "sun", "direction": [0, -2, 0], "color": [1, 0.5, 0.25], "intensity": 4},
      {"type": "point", "position": [0.3, 0.4, 0.2], "intensity": 2, "range": 3},
      {"type": "spot", "name": "torch", "position": [0.3, 0.5, 0.3], "direction": [0, -1, 0], "intensity": 1,
       "inner_cone_deg": 10, "outer_cone_deg": 20}
    ],
    "cameras": [{"name": "high", "position": [0.278, 0.5, -0.5], "target": [0.278, 0.2, 0.3], "yfov_deg": 50}],
    "default_camera": "high",
    "exposure": 2.5, "width": 320, "height": 200
  })");
  Scene s = loadScene(file.string(), "");
  ASSERT_EQ(s.lights.size(), 4u);  // the Cornell emitter's stand-in + 3
  EXPECT_EQ(s.lightNames[0], "emitter:light");
  EXPECT_EQ(s.lightNames[1], "sun");
  EXPECT_EQ(s.lightNames[2], "point 1");
  EXPECT_EQ(s.lightNames[3], "torch");
  const GiLight& sun = s.lights[1];
  EXPECT_EQ(sun.type, GI_LIGHT_DIRECTIONAL);
  EXPECT_EQ(sun.direction[1], -1.0f);
  EXPECT_EQ(sun.intensity[0], 4.0f);
  EXPECT_EQ(sun.intensity[2], 1.0f);
  EXPECT_EQ(s.lights[2].range, 3.0f);
  EXPECT_NEAR(s.lights[3].cos_outer, std::cos(glm::radians(20.0f)), 1e-6f);
  EXPECT_NEAR(s.lights[3].cos_inner, std::cos(glm::radians(10.0f)), 1e-6f);
  ASSERT_EQ(s.cameras.size(), 2u);
  EXPECT_EQ(s.defaultCamera, 1);
  const Camera& high = s.cameras[1];
  EXPECT_NEAR(high.yfov, glm::radians(50.0f), 1e-6f);
  EXPECT_EQ(high.up, glm::vec3(0, 1, 0));
  EXPECT_GT(high.znear, 0.0f);
  EXPECT_GT(high.zfar, high.znear);
  EXPECT_EQ(s.exposure, 2.5f);
  EXPECT_EQ(s.defaultWidth, 320);
  EXPECT_EQ(s.defaultHeight, 200);
  EXPECT_EQ(s.name, "box");
}

TEST(SceneConfig, GltfPathIsRelativeToTheConfigAndFileLightsCanBeReplaced) {
  auto dir = test::tempDir("scene_config_gltf");
  std::filesystem::create_directories(dir / "models");
  test::GltfWriter w;
  w.doc["extensions"]["KHR_lights_punctual"]["lights"] = {{{"name", "file light"}, {"type", "point"}, {"intensity", 1.0}}};
  w.addNode({{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  int glow = w.addMaterial({{"emissiveFactor", {1.0, 1.0, 1.0}}});
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  w.addNode({{"name", "glow"}, {"mesh", w.addMesh("glow", {{"POSITION", pos}}, -1, glow)}});
  w.write(dir / "models", "lit");

  auto keep = writeConfig(dir, "keep.json", R"({"gltf": "models/lit.gltf"})");
  auto replace = writeConfig(dir, "replace.json", R"({"gltf": "models/lit.gltf", "replace_file_lights": true,
      "lights": [{"type": "point", "name": "mine", "position": [0, 0, 1], "intensity": 3}]})");
  Scene kept = loadScene(keep.string(), "");
  ASSERT_EQ(kept.lightNames.size(), 2u);
  EXPECT_EQ(kept.lightNames[0], "file light");
  EXPECT_EQ(kept.lightNames[1], "emitter:glow");
  Scene replaced = loadScene(replace.string(), "");
  ASSERT_EQ(replaced.lightNames.size(), 2u);
  EXPECT_EQ(replaced.lightNames[0], "emitter:glow");  // the emitting geometry stays, so does its stand-in
  EXPECT_EQ(replaced.lightNames[1], "mine");
}

TEST(SceneConfig, UnknownKeysNameTheKeyAndFile) {
  expectMentions(configError(R"({"builtin": "cornell", "exposre": 1})"), {"bad.json", "'exposre'"});
  expectMentions(configError(R"({"builtin": "cornell", "lights": [{"type": "point", "position": [0,0,0], "intensity": 1, "direction": [0,1,0]}]})"),
                 {"bad.json", "'direction'", "lights[0]"});
  expectMentions(configError(R"({"builtin": "cornell", "cameras": [{"position": [0,0,1], "target": [0,0,0], "fov": 40}]})"),
                 {"bad.json", "'fov'", "cameras[0]"});
}

TEST(SceneConfig, BadValuesNameTheField) {
  expectMentions(configError(R"({"builtin": "cornell", "lights": [{"type": "point", "position": [0,0,0], "intensity": -1}]})"),
                 {"bad.json", "lights[0].intensity"});
  expectMentions(configError(R"({"builtin": "cornell", "lights": [{"type": "directional", "direction": [0,0,0], "intensity": 1}]})"),
                 {"lights[0].direction", "zero"});
  expectMentions(configError(R"({"builtin": "cornell", "lights": [{"type": "laser", "intensity": 1}]})"), {"lights[0].type", "laser"});
  expectMentions(configError(R"({"builtin": "cornell", "lights": [{"type": "spot", "position": [0,0,0], "direction": [0,-1,0], "intensity": 1, "inner_cone_deg": 50, "outer_cone_deg": 40}]})"),
                 {"lights[0].inner_cone_deg"});
  expectMentions(configError(R"({"builtin": "cornell", "lights": [{"type": "point", "position": [0,0], "intensity": 1}]})"),
                 {"lights[0].position"});
  expectMentions(configError(R"({"builtin": "cornell", "lights": [{"type": "point", "position": [0,0,0]}]})"),
                 {"lights[0].intensity", "required"});
  for (const char* fov : {"0", "180", "-5"})
    expectMentions(configError(std::string(R"({"builtin": "cornell", "cameras": [{"position": [0,0,1], "target": [0,0,0], "yfov_deg": )") + fov + "}]}"),
                   {"cameras[0].yfov_deg"});
  expectMentions(configError(R"({"builtin": "cornell", "cameras": [{"position": [0,0,1], "target": [0,0,0], "up": [0,0,1]}]})"),
                 {"cameras[0].up"});
  expectMentions(configError(R"({"builtin": "cornell", "exposure": "bright"})"), {"exposure", "number"});
  expectMentions(configError(R"({"builtin": "cornell", "exposure": 0})"), {"exposure"});
  expectMentions(configError(R"({"builtin": "cornell", "width": 12.5})"), {"width", "integer"});
  expectMentions(configError(R"({"builtin": "cornell", "replace_file_lights": 1})"), {"replace_file_lights"});
  expectMentions(configError(R"({"builtin": "cornell", "gltf": "a.gltf"})"), {"bad.json", "exactly one"});
  expectMentions(configError(R"({"lights": []})"), {"bad.json", "exactly one"});
  expectMentions(configError(R"({"builtin": "cornell", )"), {"bad.json", "invalid JSON"});
  expectMentions(configError(R"([1, 2])"), {"bad.json"});
}

TEST(SceneConfig, LoadErrorsNameTheConfigItem) {
  auto dir = test::tempDir("scene_config_load_errors");
  auto noCamera = writeConfig(dir, "nocam.json", R"({"builtin": "cornell", "default_camera": "balcony"})");
  try {
    loadScene(noCamera.string(), "");
    FAIL();
  } catch (const Error& e) {
    expectMentions(e.what(), {"nocam.json", "default_camera", "'balcony'", "'cornell'"});
  }
  auto noBuiltin = writeConfig(dir, "nobuiltin.json", R"({"builtin": "sponza"})");
  EXPECT_THROW(loadScene(noBuiltin.string(), ""), Error);
  auto missing = writeConfig(dir, "missing.json", R"({"gltf": "nowhere/nothing.gltf"})");
  try {
    loadScene(missing.string(), "");
    FAIL();
  } catch (const Error& e) {
    expectMentions(e.what(), {"nowhere/nothing.gltf", "referring file's directory", "source tree"});
  }
}

}  // namespace
}  // namespace gi
