#include "image/image.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imageio.h>

#include "util/error.h"
#include "util/file_io.h"

namespace gi {

float srgbEncode(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}
float srgbDecode(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

Image readImage(const std::filesystem::path& path) {
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) throw Error("cannot read image '" + path.string() + "': " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  Image img(spec.width, spec.height, spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.pixels.data()))
    throw Error("cannot decode image '" + path.string() + "': " + in->geterror());
  in->close();
  return img;
}

void writeImage(const std::filesystem::path& path, const Image& img) {
  if (img.width <= 0 || img.height <= 0 || img.channels <= 0) throw Error("refusing to write empty image " + path.string());
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  bool isFloat = ext == ".exr" || ext == ".hdr";
  if (!isFloat && ext != ".png" && ext != ".jpg" && ext != ".jpeg")
    throw Error("unsupported output format '" + ext + "' for " + path.string() + " (use .png or .exr)");
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    auto out = OIIO::ImageOutput::create(tmp.string());
    if (!out) throw Error("cannot create image writer for " + path.string() + ": " + OIIO::geterror());
    OIIO::ImageSpec spec(img.width, img.height, img.channels, isFloat ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    if (!out->open(tmp.string(), spec)) throw Error("cannot write " + path.string() + ": " + out->geterror());
    bool ok;
    if (isFloat) {
      ok = out->write_image(OIIO::TypeDesc::FLOAT, img.pixels.data());
    } else {
      std::vector<uint8_t> bytes(img.pixels.size());
      for (size_t i = 0; i < bytes.size(); ++i) {
        float v = img.pixels[i];
        bytes[i] = static_cast<uint8_t>(std::lround(std::clamp(std::isfinite(v) ? v : 0.0f, 0.0f, 1.0f) * 255.0f));
      }
      ok = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
    }
    if (!ok || !out->close()) throw Error("cannot write " + path.string() + ": " + out->geterror());
  });
}

Image displayTransform(const Image& linear, float exposure) {
  Image out = linear;
  for (size_t p = 0; p < linear.pixelCount(); ++p)
    for (int c = 0; c < std::min(3, linear.channels); ++c) {
      float& v = out.pixels[p * linear.channels + c];
      v = srgbEncode(std::isfinite(v) ? v * exposure : 0.0f);
    }
  return out;
}

}  // namespace gi
