// Seam smoothing (`texgrad seams`): re-solve the texels along chart boundaries (or under a mask)
// for the smoothest values given all other texels, which removes visible seams.
#pragma once

#include <cstdint>
#include <vector>

#include "texgrad/apps/texel_domain.h"
#include "texgrad/core/progress.h"
#include "texgrad/io/image.h"

namespace texgrad {

/// Result of smoothSeams.
struct SeamsResult {
  Image image;                    ///< texture with the free texels replaced
  int64_t freeTexels = 0;         ///< texels that were re-solved
  std::vector<int32_t> resolved;  ///< their unknown indices, ascending
  /// Candidates left as they are because no fixed texel ties their group to the rest (a whole
  /// chart, or charts joined by seams, with no texel off a chart boundary or outside the mask).
  int64_t unanchoredTexels = 0;
};

/// Options of smoothSeams.
struct SeamsOptions {
  /// Keep the solved values at barely covered texels; by default the re-solved ones among them
  /// are clamped into the range the surface shows around them (boundBarelyCovered): the harmonic
  /// values there are barely determined (1.7e4 ranges outside the input's on a cube with
  /// 0.01-texel slivers).
  bool rawSolution = false;
};

/// Replaces the boundary texels whose footprint a chart boundary crosses (chartBoundaryTexels; or,
/// if `mask` is not empty, the active texels where its channel 0 > 0.5) by the values minimising
/// the Dirichlet energy x^T S x with every other texel fixed: S_FF x_F = -S_FK x_K, solved directly
/// (with a screening towards the input of relative weight 1e-9 for conditioning). Texels under
/// stacked or mirrored charts that no chart boundary crosses stay fixed. Candidates joined by S
/// to no fixed texel have no data to agree with and are not re-solved (unanchoredTexels). All
/// texels not re-solved are returned bit for bit. Reports stage "solve" to `progress` before (0)
/// and after (1) the direct solve, which cannot be cancelled while it runs. The result is written
/// in `texture`'s storage: a caller done with the input moves it in (`mask` must be another
/// image).
SeamsResult smoothSeams(const TexelDomain& domain, Image texture, const Image& mask = {},
                        const SeamsOptions& options = {}, const ProgressCallback& progress = {});

}  // namespace texgrad
