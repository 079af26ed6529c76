// Which texels a chart boundary (seam side, open boundary or non-manifold edge) passes through:
// the texels `texgrad seams` re-solves.
#pragma once

#include <cstdint>
#include <vector>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Per grid texel (y * nx + x): 1 if a chart-boundary edge in UV meets the open footprint
/// (x - 1, x + 1) x (y - 1, y + 1), i.e. the support of its bilinear kernel B_t, else 0.
/// Chart-boundary edges are both sides of every seam, open-boundary and non-manifold edges.
/// A texel every footprint cell of which is covered by whole charts (stacked or mirrored charts
/// laid over one another) is 0 although its class is Boundary.
std::vector<uint8_t> chartBoundaryTexels(const TexturedMesh& mesh, const Atlas& atlas,
                                         const TexelGrid& grid);

}  // namespace texgrad
