// The OpenImageIO description of an image to encode and its scanlines, shared by the image file
// writer and the PNG encoder of the glTF write-back.
#pragma once

#include <OpenImageIO/imageio.h>

#include <string>

#include "texgrad/io/image.h"

namespace texgrad {

/// A spec for `image` stored as `type`: channel names for 1-4 channels (Y, YA, RGB, RGBA), the
/// alpha channel, and colour marked unpremultiplied (OIIO would divide it by alpha otherwise).
OIIO::ImageSpec outputSpec(const Image& image, OIIO::TypeDesc type);

/// Writes `image` to `output`, opened with outputSpec(image, type), as `type` (UINT8, UINT16 or
/// FLOAT): texel rows in file order (top row first), clamped to [0, 1] and rounded to the nearest
/// level for an integer type (NaN becomes 0), a strip of rows at a time, so that no copy of the
/// whole image is made. False on an OpenImageIO error (output.geterror() tells it).
bool writeScanlines(OIIO::ImageOutput& output, const Image& image, OIIO::TypeDesc type);

/// An OpenImageIO error message on one line ("unknown OpenImageIO error" if empty).
std::string oneLine(std::string message);

}  // namespace texgrad
