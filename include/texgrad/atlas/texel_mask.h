// Images of the texel classification (for `texgrad mask` and for inspecting an atlas).
#pragma once

#include <string>

#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/image.h"

namespace texgrad {

/// What a mask image shows.
enum class MaskKind {
  Active,    ///< 1 on active texels, 0 elsewhere
  Boundary,  ///< 1 on boundary texels
  Interior,  ///< 1 on interior texels
  Chart,     ///< RGB: a distinct colour per owning chart, black on inactive texels
  Coverage,  ///< RGB: white = one chart, red = footprint meets several charts, black = inactive
};

/// Parses "active", "boundary", "interior", "chart", "coverage"; throws InvalidInputError.
MaskKind parseMaskKind(const std::string& text);

/// Renders the mask over the image rectangle (texels outside the image are dropped); 8-bit
/// format, 1 channel for Active/Boundary/Interior and 3 for Chart/Coverage.
Image texelMask(const TexelGrid& grid, MaskKind kind);

}  // namespace texgrad
