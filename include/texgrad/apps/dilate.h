// Gutter padding (`texgrad dilate`): fill texels outside every chart so mip-maps do not bleed.
#pragma once

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/image.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Options for dilateGutters.
struct DilateOptions {
  /// Rings of gutter texels to fill around the charts; ignored when `infinite` is set.
  int radius = 4;
  /// Fill every gutter texel of the image (as long as some texel is active).
  bool infinite = false;
  /// Checks the options; throws InvalidInputError naming the bad field.
  void validate() const;
};

/// Fills gutter (inactive) texels of `texture`. The first ring takes the surface value found across
/// the seam where the nearest chart edge is a seam (the texel centre is carried over to the partner
/// chart and looked up bilinearly there); other texels take the mean of already-filled
/// neighbours, ring by ring. Active texels are returned bit for bit unchanged. `grid` must be built
/// at the texture's resolution.
Image dilateGutters(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& grid,
                    const Image& texture, const DilateOptions& options = {});

}  // namespace texgrad
