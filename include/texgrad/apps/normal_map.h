// Tangent-space normal maps as unit vectors: decode before processing, renormalise and encode after.
#pragma once

#include "texgrad/io/image.h"

namespace texgrad {

/// Decodes an RGB(A) normal map (c in [0, 1] → n = 2c − 1, the OpenGL/glTF tangent-space
/// convention: +x right, +y up, +z out of the surface) into a 3-channel image of unit vectors.
/// Zero-length texels decode to (0, 0, 1). Extra channels (alpha) are dropped.
Image decodeNormalMap(const Image& encoded);

/// Renormalises every texel of a 3-channel vector image to unit length in place (zero → +z).
void renormalize(Image& vectors);

/// Encodes unit vectors back to colours c = (n + 1) / 2, keeping `like`'s channel count and format
/// (alpha, if `like` has one, is copied from `like`).
Image encodeNormalMap(const Image& vectors, const Image& like);

}  // namespace texgrad
