// PNG encoding in memory for the glTF write-back: OpenImageIO writes through an IOProxy into a
// byte vector, so the texture is never written to a file of its own.
#include "png_encode.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "image_spec.h"
#include "texgrad/core/error.h"

namespace texgrad::png {
namespace {

/// Largest channel count a PNG holds (grey, grey + alpha, RGB, RGBA).
constexpr int kMaxChannels = 4;

/// Texel-order floats to file-order (top row first) integer samples, clamped and rounded.
template <typename T>
std::vector<T> fileOrderSamples(const Image& image) {
  constexpr float levels = static_cast<float>(std::numeric_limits<T>::max());
  const size_t row = static_cast<size_t>(image.width) * static_cast<size_t>(image.channels);
  std::vector<T> out(image.pixels.size());
  for (size_t j = 0; j < static_cast<size_t>(image.height); ++j) {
    const size_t from = j * row, to = (static_cast<size_t>(image.height) - 1 - j) * row;
    for (size_t k = 0; k < row; ++k) {
      const float v = image.pixels[from + k];
      const float clamped = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f);
      out[to + k] = static_cast<T>(std::lround(clamped * levels));
    }
  }
  return out;
}

std::string oneLine(std::string message) {
  for (char& c : message)
    if (c == '\n' || c == '\r') c = ' ';
  while (!message.empty() && message.back() == ' ') message.pop_back();
  return message.empty() ? std::string("unknown OpenImageIO error") : message;
}

}  // namespace

/// Encodes `image` as PNG bytes in memory: 8-bit for UInt8, 16-bit for the other formats.
std::vector<unsigned char> encodePng(const Image& image, PixelFormat format,
                                     const std::string& where) {
  const bool sixteenBit = format != PixelFormat::UInt8;
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  const std::string proxyName = "texgrad-memory.png";
  auto output = OIIO::ImageOutput::create(proxyName);
  if (!output) throw IoError(where + oneLine(OIIO::geterror()));
  OIIO::ImageSpec spec =
      outputSpec(image, sixteenBit ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8);
  OIIO::Filesystem::IOProxy* proxyPointer = &proxy;
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxyPointer);
  if (!output->set_ioproxy(&proxy) || !output->open(proxyName, spec))
    throw IoError(where + oneLine(output->geterror()));
  const bool ok =
      sixteenBit
          ? output->write_image(OIIO::TypeDesc::UINT16, fileOrderSamples<uint16_t>(image).data())
          : output->write_image(OIIO::TypeDesc::UINT8, fileOrderSamples<uint8_t>(image).data());
  if (!ok) {
    const std::string message = oneLine(output->geterror());
    output->close();
    throw IoError(where + message);
  }
  if (!output->close()) throw IoError(where + oneLine(output->geterror()));
  return bytes;
}

void checkImage(const Image& image, const std::string& where) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0)
    throw InvalidInputError(where + "the image is empty");
  if (image.channels > kMaxChannels)
    throw UnsupportedError(where + std::to_string(image.channels) +
                           " channels; a PNG texture holds 1 to 4");
  if (image.pixels.size() != image.index(0, image.height))
    throw InvalidInputError(where + "pixel buffer size does not match " +
                            std::to_string(image.width) + " x " + std::to_string(image.height) +
                            " x " + std::to_string(image.channels));
}

}  // namespace texgrad::png
