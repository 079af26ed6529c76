// Apps layer: a per-texel distance field drawn as an RGB picture (viridis ramp, isolines).
#pragma once

#include <Eigen/Core>

#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/image.h"

namespace texgrad {

/// Picture of a distance field for people: W x H RGB (UInt8) image of the grid's texture, with a
/// viridis ramp from 0 (dark blue) to maxDistance (yellow) on active texels and `isolines`
/// dark, anti-aliased contour lines at k maxDistance / (isolines + 1), k = 1..isolines.
/// Inactive texels are black, unreachable (infinite) ones grey; `distances` is per unknown.
Image distanceColourMap(const TexelGrid& grid, const Eigen::VectorXd& distances, double maxDistance,
                        int isolines);

}  // namespace texgrad
