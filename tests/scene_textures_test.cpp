// Texture decoding and mip chains: level sizes, sRGB-correct averaging, decode errors.
#include <cmath>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "image/image.h"
#include "scene/textures.h"
#include "test_support.h"
#include "util/error.h"

namespace gi {
namespace {

TEST(SceneTextures, MipLevelCountReachesOneTexel) {
  EXPECT_EQ(mipLevelCount(1, 1), 1);
  EXPECT_EQ(mipLevelCount(4, 2), 3);
  EXPECT_EQ(mipLevelCount(5, 3), 3);
  EXPECT_EQ(mipLevelCount(1024, 1024), 11);
  EXPECT_EQ(mipLevelCount(256, 1024), 11);
}

TEST(SceneTextures, ColourMipsAverageInLinearSpaceDataMipsAsStored) {
  // 2×2: black, white / black, white; alpha 0, 255 / 0, 255.
  std::vector<uint8_t> texels = {0, 0, 0, 0, 255, 255, 255, 255, 0, 0, 0, 0, 255, 255, 255, 255};
  Texture colour = makeTexture("c", 2, 2, texels.data(), true);
  Texture data = makeTexture("d", 2, 2, texels.data(), false);
  ASSERT_EQ(colour.levels, 2);
  ASSERT_EQ(colour.rgba8.size(), (4u + 1u) * 4u);
  const uint8_t* c1 = &colour.rgba8[16];
  const uint8_t* d1 = &data.rgba8[16];
  // Half the light of white is sRGB code 188, not 128.
  uint8_t expected = uint8_t(std::lround(255.0f * srgbEncode(0.5f)));
  EXPECT_EQ(c1[0], expected);
  EXPECT_EQ(c1[2], expected);
  EXPECT_EQ(c1[3], 128);  // alpha is linear coverage
  EXPECT_EQ(d1[0], 128);
  EXPECT_EQ(d1[3], 128);
  EXPECT_TRUE(colour.srgb);
  EXPECT_FALSE(data.srgb);
}

TEST(SceneTextures, NonSquareChainKeepsLevelSizes) {
  std::vector<uint8_t> texels(8 * 2 * 4, 100);
  Texture t = makeTexture("wide", 8, 2, texels.data(), true);
  ASSERT_EQ(t.levels, 4);  // 8×2, 4×1, 2×1, 1×1
  EXPECT_EQ(t.rgba8.size(), size_t(16 + 4 + 2 + 1) * 4);
  for (uint8_t v : t.rgba8) EXPECT_EQ(v, 100);  // a constant image stays constant at every level
}

std::vector<uint8_t> fileBytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

TEST(SceneTextures, OneImageDecodedForTwoColourSpaces) {
  auto dir = test::tempDir("scene_textures_decode");
  Image img(3, 2, 3, 0.0f);
  img.at(1, 0)[0] = 1.0f;  // one red texel
  writeImage(dir / "img.png", img);
  std::vector<EncodedImage> images = {{"unused.png", {}}, {"img.png", fileBytes(dir / "img.png")}};
  std::vector<Texture> textures = decodeTextures(images, {{1, true}, {1, false}});
  ASSERT_EQ(textures.size(), 2u);
  for (const Texture& t : textures) {
    EXPECT_EQ(t.name, "img.png");
    EXPECT_EQ(t.width, 3);
    EXPECT_EQ(t.height, 2);
    EXPECT_EQ(t.levels, 2);
    EXPECT_EQ(t.rgba8[4 + 0], 255);  // texel (1,0) red, opaque (RGB expanded to RGBA)
    EXPECT_EQ(t.rgba8[4 + 1], 0);
    EXPECT_EQ(t.rgba8[4 + 3], 255);
  }
  EXPECT_TRUE(textures[0].srgb);
  EXPECT_FALSE(textures[1].srgb);
}

TEST(SceneTextures, UndecodableImageNamesTheImage) {
  std::vector<EncodedImage> images = {{"broken.png", {0x89, 'P', 'N', 'G', 1, 2, 3}}};
  try {
    decodeTextures(images, {{0, true}});
    FAIL() << "expected gi::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gi
