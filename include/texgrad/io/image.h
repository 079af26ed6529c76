// Float image held in texel order (row 0 = bottom, v upward); image files are flipped on I/O only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace texgrad {

/// Storage type of an image file: decides quantisation on write.
enum class PixelFormat : uint8_t { UInt8, UInt16, Half, Float };

/// A W x H image with 1-4 channels of float values (integer formats normalised to [0, 1]).
///
/// Rows are in *texel order*: row j holds texels whose centres are at v = (j + 0.5) / H, so row 0
/// is the bottom of the picture; readImage/writeImage flip file rows (docs/architecture.md).
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  PixelFormat format = PixelFormat::UInt8;  ///< format it was read in (default for writing)
  std::vector<float> pixels;                ///< size width*height*channels, interleaved

  Image() = default;
  /// Allocates a zero-filled image.
  Image(int w, int h, int c, PixelFormat f = PixelFormat::Float)
      : width(w), height(h), channels(c), format(f),
        pixels(static_cast<size_t>(w) * static_cast<size_t>(h) * static_cast<size_t>(c), 0.0f) {}

  /// Linear index of texel (i, j), channel c.
  size_t index(int i, int j, int c = 0) const {
    return (static_cast<size_t>(j) * static_cast<size_t>(width) + static_cast<size_t>(i)) *
               static_cast<size_t>(channels) +
           static_cast<size_t>(c);
  }
  /// Value of texel (column i, texel row j from the bottom), channel c.
  float& at(int i, int j, int c = 0) { return pixels[index(i, j, c)]; }
  /// Value of texel (column i, texel row j from the bottom), channel c.
  float at(int i, int j, int c = 0) const { return pixels[index(i, j, c)]; }
  /// True if the image holds no texels.
  bool empty() const { return width == 0 || height == 0 || channels == 0; }
};

}  // namespace texgrad
