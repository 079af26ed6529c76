// PNG encoding in memory for the glTF write-back: libpng writes into a byte vector, so the texture
// is never written to a file of its own.
#include "png_encode.h"

#include "image_codecs.h"
#include "texgrad/core/error.h"

namespace texgrad::png {
namespace {

/// Largest channel count a PNG holds (grey, grey + alpha, RGB, RGBA).
constexpr int kMaxChannels = 4;

}  // namespace

std::vector<unsigned char> encodePng(const Image& image, PixelFormat format,
                                     const std::string& where) {
  return codec::encodePng(image, format != PixelFormat::UInt8, where);
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
