// PNG encoding in memory for the glTF write-back: OpenImageIO writes through an IOProxy into a
// byte vector, so the texture is never written to a file of its own.
#include "png_encode.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include "image_spec.h"
#include "texgrad/core/error.h"

namespace texgrad::png {
namespace {

/// Largest channel count a PNG holds (grey, grey + alpha, RGB, RGBA).
constexpr int kMaxChannels = 4;

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
  if (!writeScanlines(*output, image, spec.format)) {
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
