// `gi reference`: writes the EXR pair, reuses its cache, rejects bad flags without writing.
#include <filesystem>

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

// A reference rendered in two runs through a checkpoint (3 spp kept, then resumed to 7) has the
// same bits as one uninterrupted 7-spp run; a checkpoint of another reference or a damaged one
// is refused by name, and a finished run deletes its checkpoint.
TEST(ReferenceCommand, ResumesFromACheckpointWithTheSameBits) {
  auto dir = test::tempDir("reference_checkpoint");
  const std::string common = "reference --no-cache --width 16 --height 12 --max-bounces 3";
  const std::string ck = (dir / "r.checkpoint").string();
  auto whole = test::runGi(common + " --spp 7 --out " + (dir / "whole.exr").string());
  ASSERT_EQ(whole.exitCode, 0) << whole.output;
  auto first = test::runGi(common + " --spp 3 --keep-checkpoint --checkpoint " + ck + " --out " + (dir / "part.exr").string());
  ASSERT_EQ(first.exitCode, 0) << first.output;
  ASSERT_TRUE(std::filesystem::exists(ck));
  auto second = test::runGi(common + " --spp 7 --checkpoint " + ck + " --out " + (dir / "resumed.exr").string());
  ASSERT_EQ(second.exitCode, 0) << second.output;
  EXPECT_NE(second.output.find("resuming from"), std::string::npos) << second.output;
  EXPECT_FALSE(std::filesystem::exists(ck)) << "a finished run deletes its checkpoint";
  EXPECT_EQ(readImage(dir / "resumed.exr").pixels, readImage(dir / "whole.exr").pixels);

  // Another reference's checkpoint (other bounces), more samples than asked, a truncated file.
  first = test::runGi(common + " --spp 3 --keep-checkpoint --checkpoint " + ck + " --out " + (dir / "part.exr").string());
  ASSERT_EQ(first.exitCode, 0) << first.output;
  auto other = test::runGi("reference --no-cache --width 16 --height 12 --max-bounces 2 --spp 7 --checkpoint " + ck +
                           " --out " + (dir / "other.exr").string());
  EXPECT_NE(other.exitCode, 0);
  EXPECT_NE(other.output.find("belongs to another reference"), std::string::npos) << other.output;
  auto fewer = test::runGi(common + " --spp 2 --checkpoint " + ck + " --out " + (dir / "fewer.exr").string());
  EXPECT_NE(fewer.exitCode, 0);
  EXPECT_NE(fewer.output.find("already holds 3 spp"), std::string::npos) << fewer.output;
  std::filesystem::resize_file(ck, std::filesystem::file_size(ck) - 5);
  auto cut = test::runGi(common + " --spp 7 --checkpoint " + ck + " --out " + (dir / "cut.exr").string());
  EXPECT_NE(cut.exitCode, 0);
  EXPECT_NE(cut.output.find("truncated"), std::string::npos) << cut.output;
  for (const char* f : {"other.exr", "fewer.exr", "cut.exr"}) EXPECT_FALSE(std::filesystem::exists(dir / f)) << f;
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
