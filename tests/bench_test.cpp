// `gi bench` through the real binary on the built-in Cornell box at 32x32: the statistics are
// consistent (min <= median <= max; with one timed frame a pass is the sum of its kernels), the
// JSON carries device, driver, revision and every parameter, the quality against a reference equals
// what `gi compare` measures on the written frame, and bad input writes nothing.
#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "test_support.h"

using namespace gi;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {
const std::string kSmall = " --width 32 --height 32 --set shadow.resolution=256 --set rsm.resolution=64";
}

TEST(Bench, WritesConsistentStatisticsAndQuality) {
  auto dir = test::tempDir("bench");
  const std::string env = "GI_DEVICE=cpu";
  test::CommandResult r = test::runGi("reference --width 32 --height 32 --spp 8 --max-bounces 4 --no-cache --out " +
                                          (dir / "ref.exr").string(),
                                      env);
  ASSERT_EQ(r.exitCode, 0) << r.output;

  r = test::runGi("bench --technique vpl --set vpl.count=16" + kSmall + " --frames 3 --warmup 1 --json " +
                      (dir / "b.json").string() + " --image " + (dir / "frame.exr").string() + " --reference " +
                      (dir / "ref.exr").string() + " --heatmap " + (dir / "flip.png").string(),
                  env);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("pass vpl"), std::string::npos) << r.output;
  json j = json::parse(std::ifstream(dir / "b.json"));
  EXPECT_EQ(j["frames"], 3);
  EXPECT_EQ(j["warmup"], 1);
  EXPECT_EQ(j["width"], 32);
  EXPECT_EQ(j["technique"], "vpl");
  EXPECT_EQ(j["params"]["vpl.count"], "16");
  EXPECT_EQ(j["params"]["igi.n"], "4");  // every parameter, defaults included
  EXPECT_FALSE(j["git_revision"].get<std::string>().empty());
  EXPECT_FALSE(j["device"]["name"].get<std::string>().empty());
  EXPECT_FALSE(j["device"]["driver"].get<std::string>().empty());
  EXPECT_GT(j["device_bytes"].get<double>(), 0.0);
  bool sawVplShade = false;
  for (const char* list : {"kernels", "passes"})
    for (auto& k : j[list]) {
      EXPECT_LE(k["min_ms"].get<double>(), k["median_ms"].get<double>()) << k;
      EXPECT_LE(k["median_ms"].get<double>(), k["max_ms"].get<double>()) << k;
      sawVplShade |= k["name"] == "vpl: shade";
    }
  EXPECT_TRUE(sawVplShade) << j["kernels"];
  EXPECT_GT(j["frame_wall_ms"]["median_ms"].get<double>(), 0.0);

  // Quality: the same numbers `gi compare` gives for the written frame.
  r = test::runGi("compare --reference " + (dir / "ref.exr").string() + " --test " + (dir / "frame.exr").string() +
                  " --json " + (dir / "c.json").string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  json c = json::parse(std::ifstream(dir / "c.json"));
  for (const char* m : {"ssim", "grade", "flip", "relmse"})
    EXPECT_NEAR(j["quality"][m].get<double>(), c["metrics"][m].get<double>(), 1e-9) << m;
  EXPECT_TRUE(fs::exists(dir / "flip.png"));

  // One timed frame: each pass is exactly the sum of its kernels.
  r = test::runGi("bench --technique vpl --set vpl.count=16" + kSmall + " --frames 1 --warmup 1 --json " +
                      (dir / "one.json").string(),
                  env);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  json one = json::parse(std::ifstream(dir / "one.json"));
  double total = 0;
  for (auto& p : one["passes"]) {
    double sum = 0;
    std::string prefix = p["name"].get<std::string>();
    for (auto& k : one["kernels"])
      if (k["name"].get<std::string>().substr(0, k["name"].get<std::string>().find(':')) == prefix)
        sum += k["median_ms"].get<double>();
    EXPECT_NEAR(p["median_ms"].get<double>(), sum, 1e-9) << prefix;
    total += sum;
  }
  EXPECT_NEAR(one["device_total_ms"]["median_ms"].get<double>(), total, 1e-9);
  fs::remove_all(dir);
}

// Technique statistics: second-order reports its re-shaded share. Without multi-resolution every
// surface pixel is shaded at full resolution (exactly 1); with it, a strict part of them.
TEST(Bench, WritesTechniqueStatistics) {
  auto dir = test::tempDir("bench_statistics");
  const std::string env = "GI_DEVICE=cpu";
  auto bench = [&](const std::string& sets, const std::string& name) {
    test::CommandResult r = test::runGi("bench --technique second-order --set second-order.count=32" + sets + kSmall +
                                            " --frames 1 --warmup 1 --json " + (dir / name).string(),
                                        env);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("second-order.reshaded_fraction"), std::string::npos) << r.output;
    return json::parse(std::ifstream(dir / name));
  };
  json full = bench(" --set second-order.multires=false --set second-order.negative=8", "full.json");
  EXPECT_EQ(full["statistics"]["second-order.reshaded_fraction"].get<double>(), 1.0) << full["statistics"];
  EXPECT_GT(full["statistics"]["second-order.negative_lights"].get<double>(), 0.0);
  EXPECT_LE(full["statistics"]["second-order.negative_lights"].get<double>(), 8.0);
  json multires = bench(" --set second-order.negative=0", "multires.json");
  const double share = multires["statistics"]["second-order.reshaded_fraction"].get<double>();
  EXPECT_GT(share, 0.0);  // the Cornell box's edges and corners differ from their half-res parents
  EXPECT_LT(share, 1.0);
  EXPECT_EQ(multires["statistics"]["second-order.negative_lights"].get<double>(), 0.0);
  EXPECT_NEAR(multires["statistics"]["second-order.reshaded_pixels"].get<double>(),
              share * full["statistics"]["second-order.reshaded_pixels"].get<double>(), 1e-6);
  fs::remove_all(dir);
}

TEST(Bench, BadInputWritesNothing) {
  auto dir = test::tempDir("bench_bad");
  auto json = dir / "b.json";
  for (const std::string& args : {std::string("--set vpl.count=-3 --technique vpl"), std::string("--technique nope"),
                                  std::string("--frames 0"), std::string("--heatmap x.png"),
                                  std::string("--image x.bmp")}) {
    test::CommandResult r = test::runGi("bench --width 16 --height 16 " + args + " --json " + json.string(), "GI_DEVICE=cpu");
    EXPECT_NE(r.exitCode, 0) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(json)) << args;
  }
  fs::remove_all(dir);
}
