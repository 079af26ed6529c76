// Rasterises a mesh's atlas into the texel lattice: exact cell coverage per chart, classified by
// the lattice's rule (texgrad/lattice/texel_grid.h).
#pragma once

#include "texgrad/atlas/atlas.h"
#include "texgrad/io/textured_mesh.h"
#include "texgrad/lattice/texel_grid.h"

namespace texgrad {

/// Builds the texel grid of a width x height texture exactly (no jitter): the grid spans every
/// texel a UV triangle can touch, a cell is covered when a UV triangle of positive area overlaps
/// its interior, and classifyLattice turns that coverage into texel classes and unknowns.
TexelGrid buildTexelGrid(const TexturedMesh& mesh, const Atlas& atlas, int width, int height);

}  // namespace texgrad
