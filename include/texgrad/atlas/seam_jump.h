// Seam diagnostics: how far apart a texture's two sides of every seam are, as a renderer shows it.
#pragma once

#include <vector>

#include "texgrad/atlas/atlas.h"
#include "texgrad/io/image.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Options for measureSeamJump.
struct SeamJumpOptions {
  /// Samples per texel of seam length (measured on the side with more texels); at least 2 per edge.
  double samplesPerTexel = 4.0;
  /// Checks the options; throws InvalidInputError naming the bad field.
  void validate() const;
};

/// Seam jump of a texture: RMS over points sampled along every seam pair of the difference between
/// bilinear lookups on the two sides, weighted by 3-D length (so it is a surface measure).
struct SeamJump {
  double rms = 0.0;                  ///< over all channels, in texture units (1 = full range)
  std::vector<double> rmsPerChannel; ///< per channel
  double maxAbs = 0.0;               ///< largest single-sample difference over all channels
  int64_t samples = 0;               ///< number of sample pairs
  double seamLength3d = 0.0;         ///< total 3-D length of the seams measured
};

/// Measures the seam jump of `texture` over the seams of `atlas` (zero if there are none).
SeamJump measureSeamJump(const TexturedMesh& mesh, const Atlas& atlas, const Image& texture,
                         const SeamJumpOptions& options = {});

}  // namespace texgrad
