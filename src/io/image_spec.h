// The OpenImageIO description of an image to encode, shared by the image file writer and the PNG
// encoder of the glTF write-back.
#pragma once

#include <OpenImageIO/imageio.h>

#include "texgrad/io/image.h"

namespace texgrad {

/// A spec for `image` stored as `type`: channel names for 1-4 channels (Y, YA, RGB, RGBA), the
/// alpha channel, and colour marked unpremultiplied (OIIO would divide it by alpha otherwise).
OIIO::ImageSpec outputSpec(const Image& image, OIIO::TypeDesc type);

}  // namespace texgrad
