// Texture decoding for scenes: encoded PNG/JPG bytes -> RGBA8 level 0 -> full box-filtered mip
// chain (gi::Texture). Colour textures (srgb) are averaged in linear space and re-encoded, so
// mips of a sharp black/white pattern have the right mid-grey brightness; data textures
// (normals, metallic-roughness) are averaged as stored.
//
// Each image is decoded once even when it backs two textures (e.g. used as colour and as data);
// images are decoded on all hardware threads (Sponza: 49 images, 51 M texels).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace gi {

struct EncodedImage {
  std::string name;            // file or image name, for messages and Texture::name
  std::vector<uint8_t> bytes;  // PNG, JPG, BMP, TGA, ... as stored in the file
};

// One texture to build: which image, and whether it holds sRGB-encoded colour.
struct TextureRequest {
  size_t image = 0;  // index into the images given to decodeTextures
  bool srgb = false;
};

// Builds requests[i] into the i-th returned texture. Throws gi::Error naming the image when an
// image cannot be decoded.
std::vector<Texture> decodeTextures(const std::vector<EncodedImage>& images,
                                    const std::vector<TextureRequest>& requests);

// Number of mip levels of a w×h texture down to 1×1: floor(log2(max(w, h))) + 1.
int mipLevelCount(int width, int height);

// A texture from RGBA8 level-0 texels (width·height·4 bytes at level0), with its full mip chain.
Texture makeTexture(std::string name, int width, int height, const uint8_t* level0, bool srgb);

}  // namespace gi
