// The `gi` command as a user meets it: success paths write their files; bad input (missing or
// broken scene files, unsupported required extensions, bad flags, no OpenCL platform) exits
// non-zero with a one-line reason naming the item, and leaves no output file behind.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

#include <nlohmann/json.hpp>

#include "test_support.h"

using namespace gi;
namespace fs = std::filesystem;

namespace {

// Writes a one-quad glTF (two triangles, optionally a NaN vertex and a degenerate triangle)
// with an external .bin; returns the .gltf path.
fs::path writeQuadGltf(const fs::path& dir, const std::string& extraTopLevel = "", bool badGeometry = false) {
  std::vector<float> pos = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1, 0, 0, 0};
  if (badGeometry) pos[12] = std::nanf("");
  std::vector<uint32_t> idx = {0, 2, 1, 0, 3, 2};
  if (badGeometry) idx.insert(idx.end(), {0, 4, 1, 0, 0, 1});  // a NaN vertex and a degenerate triangle
  {
    std::ofstream bin(dir / "quad.bin", std::ios::binary);
    bin.write(reinterpret_cast<const char*>(pos.data()), pos.size() * 4);
    bin.write(reinterpret_cast<const char*>(idx.data()), idx.size() * 4);
  }
  size_t posBytes = pos.size() * 4, idxBytes = idx.size() * 4;
  std::string json = R"({"asset": {"version": "2.0"},)" + extraTopLevel + R"(
    "buffers": [{"uri": "quad.bin", "byteLength": )" + std::to_string(posBytes + idxBytes) + R"(}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": )" + std::to_string(posBytes) + R"(},
                    {"buffer": 0, "byteOffset": )" + std::to_string(posBytes) + R"(, "byteLength": )" +
                     std::to_string(idxBytes) + R"(}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3",
                   "min": [-1, 0, -1], "max": [1, 0, 1]},
                  {"bufferView": 1, "componentType": 5125, "count": )" + std::to_string(idx.size()) + R"(, "type": "SCALAR"}],
    "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0})";
  std::ofstream(dir / "quad.gltf") << json;
  return dir / "quad.gltf";
}

void expectFailureWithoutOutput(const std::string& args, const fs::path& out, const std::string& mustMention,
                                const std::string& env = "") {
  test::CommandResult r = test::runGi(args, env);
  EXPECT_NE(r.exitCode, 0) << args << "\n" << r.output;
  EXPECT_NE(r.output.find(mustMention), std::string::npos) << "expected '" << mustMention << "' in: " << r.output;
  EXPECT_EQ(r.output.find("Segmentation"), std::string::npos) << r.output;
  EXPECT_LT(r.exitCode, 128) << "crashed: " << r.output;
  EXPECT_FALSE(fs::exists(out)) << out << " was written";
  // Nor a temporary left behind.
  for (auto& e : fs::directory_iterator(out.parent_path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

}  // namespace

TEST(Cli, RendersBuiltinCornellBoxWithTimingsAndJson) {
  auto dir = test::tempDir("cli_ok");
  auto out = dir / "cornell.png", json = dir / "t.json";
  test::CommandResult r =
      test::runGi("render --width 64 --height 48 --timings --out " + out.string() + " --json " + json.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(fs::exists(out));
  EXPECT_NE(r.output.find("gbuffer: tiles"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("direct lighting"), std::string::npos) << r.output;
  auto j = nlohmann::json::parse(std::ifstream(json));
  EXPECT_EQ(j["width"], 64);
  EXPECT_GT(j["passes_ms"]["direct lighting"].get<double>(), 0.0);
  fs::remove_all(dir);
}

TEST(Cli, DevicesListsPocl) {
  test::CommandResult r = test::runGi("devices");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("[0]"), std::string::npos) << r.output;
}

TEST(Cli, WritesAovs) {
  auto dir = test::tempDir("cli_aov");
  test::CommandResult r = test::runGi("render --width 32 --height 32 --out " + (dir / "c.exr").string() + " --aov " +
                                      (dir / "aov").string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  for (const char* f : {"depth", "position", "geometric_normal", "shading_normal", "albedo_metallic",
                        "specular_roughness", "emission", "instance_id", "rsm0_position", "rsm0_normal", "rsm0_flux"})
    EXPECT_TRUE(fs::exists(dir / "aov" / (std::string(f) + ".exr"))) << f;
  fs::remove_all(dir);
}

TEST(Cli, MissingSceneFile) {
  auto dir = test::tempDir("cli_missing");
  expectFailureWithoutOutput("render " + (dir / "nope.gltf").string() + " --out " + (dir / "o.png").string(),
                             dir / "o.png", "nope.gltf");
  fs::remove_all(dir);
}

TEST(Cli, TruncatedGltf) {
  auto dir = test::tempDir("cli_trunc");
  fs::path g = writeQuadGltf(dir);
  std::string text = test::readFile(g);
  std::ofstream(g, std::ios::trunc) << text.substr(0, text.size() / 2);
  expectFailureWithoutOutput("render " + g.string() + " --out " + (dir / "o.png").string(), dir / "o.png", "quad.gltf");
  fs::remove_all(dir);
}

TEST(Cli, MissingBinBuffer) {
  auto dir = test::tempDir("cli_nobin");
  fs::path g = writeQuadGltf(dir);
  fs::remove(dir / "quad.bin");
  expectFailureWithoutOutput("render " + g.string() + " --out " + (dir / "o.png").string(), dir / "o.png", "quad.bin");
  fs::remove_all(dir);
}

TEST(Cli, UnsupportedRequiredExtension) {
  auto dir = test::tempDir("cli_draco");
  fs::path g = writeQuadGltf(dir, R"("extensionsUsed": ["KHR_draco_mesh_compression"],
    "extensionsRequired": ["KHR_draco_mesh_compression"],)");
  expectFailureWithoutOutput("render " + g.string() + " --out " + (dir / "o.png").string(), dir / "o.png",
                             "KHR_draco_mesh_compression");
  fs::remove_all(dir);
}

TEST(Cli, NanVerticesAndDegenerateTrianglesAreSkippedWithAWarning) {
  auto dir = test::tempDir("cli_nan");
  fs::path g = writeQuadGltf(dir, "", true);
  test::CommandResult r = test::runGi("render " + g.string() + " --width 32 --height 32 --out " + (dir / "o.png").string());
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("warning"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir / "o.png"));
  fs::remove_all(dir);
}

TEST(Cli, NonsenseFlags) {
  auto dir = test::tempDir("cli_flags");
  fs::path out = dir / "o.png";
  std::string o = " --out " + out.string();
  expectFailureWithoutOutput("render --width -5" + o, out, "width");
  expectFailureWithoutOutput("render --width 100000" + o, out, "width");
  expectFailureWithoutOutput("render --set nonsense.param=1" + o, out, "nonsense.param");
  expectFailureWithoutOutput("render --set shadow.resolution=abc" + o, out, "shadow.resolution");
  expectFailureWithoutOutput("render --set shadow.resolution=99999999" + o, out, "shadow.resolution");
  expectFailureWithoutOutput("render --camera no-such-camera" + o, out, "no-such-camera");
  expectFailureWithoutOutput("render --technique no-such-technique" + o, out, "no-such-technique");
  expectFailureWithoutOutput("render --device no-such-device" + o, out, "no-such-device");
  expectFailureWithoutOutput("render --out " + (dir / "o.bmp").string(), dir / "o.bmp", ".bmp");
  expectFailureWithoutOutput("render --no-such-flag" + o, out, "no-such-flag");
  fs::remove_all(dir);
}

TEST(Cli, NoOpenClPlatform) {
  auto dir = test::tempDir("cli_noplatform");
  fs::create_directories(dir / "vendors");
  fs::path out = dir / "o.png";
  expectFailureWithoutOutput("render --out " + out.string(), out, "no OpenCL platform",
                             "OCL_ICD_VENDORS=" + (dir / "vendors").string() + " OPENCL_VENDOR_PATH=" + (dir / "vendors").string());
  test::CommandResult r = test::runGi("devices", "OCL_ICD_VENDORS=" + (dir / "vendors").string());
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.output.find("no OpenCL platform"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(Cli, KernelBuildFailureIsReportedWithFileAndLine) {
  auto dir = test::tempDir("cli_badkernel");
  fs::copy(fs::path(GI_SOURCE_DIR) / "kernels", dir / "kernels", fs::copy_options::recursive);
  {
    std::ofstream f(dir / "kernels/render/direct_lighting.cl", std::ios::app);
    f << "\nkernel void broken(global float* x) { x[0] = not_declared; }\n";
  }
  fs::path out = dir / "o.png";
  expectFailureWithoutOutput("render --out " + out.string(), out, "kernels/render/direct_lighting.cl:",
                             "GI_KERNEL_DIR=" + dir.string() + " GI_CACHE_DIR=off");
  fs::remove_all(dir);
}
