// Seam smoothing (`texgrad seams`): re-solve the texels along chart boundaries (or under a mask)
// for the smoothest values given all other texels, which removes visible seams.
#pragma once

#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/image.h"

namespace texgrad {

/// Result of smoothSeams.
struct SeamsResult {
  Image image;                ///< texture with the free texels replaced
  int64_t freeTexels = 0;     ///< texels that were re-solved
};

/// Replaces the boundary texels (or, if `mask` is not empty, the active texels where its channel
/// 0 > 0.5) by the values minimising the Dirichlet energy x^T S x with every other texel fixed:
/// S_FF x_F = -S_FK x_K, solved directly. All other texels are returned bit for bit.
SeamsResult smoothSeams(const TexelDomain& domain, const Image& texture, const Image& mask = {});

}  // namespace texgrad
