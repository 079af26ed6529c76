// How much of a texel's bilinear kernel the charts cover: the texels whose value the surface
// signal barely determines.
#pragma once

#include <cstdint>
#include <vector>

#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Largest `fraction` barelyCoveredTexels accepts: one Full footprint cell already covers a
/// quarter of the kernel, so only texels without one are examined.
inline constexpr double kMaxBarelyCoveredFraction = 0.25;

/// Unknowns (ascending) whose bilinear kernel B_t the charts cover by less than `fraction`:
/// the integral of B_t over the UV area of the charts inside its footprint, in texel units
/// (1 for a texel inside one chart), is below `fraction`. Under a metric that is constant over
/// the footprint this is the texel's mass-matrix row sum over that of a fully covered texel.
/// Throws InvalidInputError unless 0 < fraction <= kMaxBarelyCoveredFraction.
std::vector<int32_t> barelyCoveredTexels(const TexturedMesh& mesh, const TexelGrid& grid,
                                         double fraction);

}  // namespace texgrad
