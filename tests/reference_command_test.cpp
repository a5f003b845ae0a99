// `gi reference`: writes the EXR pair, reuses its cache, rejects bad flags without writing.
#include <gtest/gtest.h>

#include "image/image.h"
#include "test_support.h"

using namespace gi;

TEST(ReferenceCommand, WritesImageAndVarianceThenReusesTheCache) {
  auto dir = test::tempDir("reference_cmd");
  std::string env = "GI_CACHE_DIR=" + (dir / "cache").string();
  std::string args = "reference --width 16 --height 12 --spp 4 --max-bounces 3 --out " + (dir / "a.exr").string() +
                     " --variance " + (dir / "a_var.exr").string();
  auto r = test::runGi(args, env);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  Image a = readImage(dir / "a.exr"), v = readImage(dir / "a_var.exr");
  EXPECT_EQ(a.width, 16);
  EXPECT_EQ(a.height, 12);
  EXPECT_EQ(v.width, 16);
  double sum = 0;
  for (float f : a.pixels) sum += f;
  EXPECT_GT(sum, 0.0);

  std::string args2 = "reference --width 16 --height 12 --spp 4 --max-bounces 3 --out " + (dir / "b.exr").string();
  auto r2 = test::runGi(args2, env);
  ASSERT_EQ(r2.exitCode, 0) << r2.output;
  EXPECT_NE(r2.output.find("cached"), std::string::npos) << r2.output;
  Image b = readImage(dir / "b.exr");
  EXPECT_EQ(a.pixels, b.pixels);

  // Same render without the cache: same bits (determinism across processes).
  auto r3 = test::runGi(args2 + " --no-cache", env);
  ASSERT_EQ(r3.exitCode, 0) << r3.output;
  EXPECT_EQ(r3.output.find("cached"), std::string::npos);
  EXPECT_EQ(readImage(dir / "b.exr").pixels, a.pixels);
}

TEST(ReferenceCommand, BadFlagsFailWithoutOutput) {
  auto dir = test::tempDir("reference_bad");
  std::string out = (dir / "x.exr").string();
  for (std::string bad : std::vector<std::string>{"--spp 0", "--mode sideways", "--max-bounces -1", "--width 0", "--camera nosuchcamera",
                          "--out-of-range", "--spp 2 --out " + (dir / "x.png").string()}) {
    auto r = test::runGi("reference " + bad + (bad.find("--out ") == std::string::npos ? " --out " + out : ""),
                         "GI_CACHE_DIR=off");
    EXPECT_NE(r.exitCode, 0) << bad;
    EXPECT_NE(r.output.find("error"), std::string::npos) << bad << ": " << r.output;
    EXPECT_FALSE(std::filesystem::exists(out)) << bad;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.png")) << bad;
  }
}
