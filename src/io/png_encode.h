// PNG encoding in memory for the glTF write-back (private to the io module).
#pragma once

#include <string>
#include <vector>

#include "texgrad/io/image.h"

namespace texgrad::png {

/// Throws InvalidInputError (empty image, wrong buffer size) or UnsupportedError (more than 4
/// channels) prefixed by `where` unless `image` can be stored as a PNG.
void checkImage(const Image& image, const std::string& where);

/// Encodes `image` (texel order, v up) as PNG bytes, top row first: 8-bit for UInt8, 16-bit for
/// the other formats; samples are clamped to [0, 1] (NaN as 0) and rounded. Throws IoError
/// prefixed by `where` if libpng fails.
std::vector<unsigned char> encodePng(const Image& image, PixelFormat format,
                                     const std::string& where);

}  // namespace texgrad::png
