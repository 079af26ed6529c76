// Moving texture values between images and the unknowns of a texel grid (n x channels blocks).
#pragma once

#include <Eigen/Core>
#include <array>

#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/image.h"

namespace texgrad {

/// Throws InvalidInputError unless `image` has the size the grid was built for.
void requireGridImageSize(const TexelGrid& grid, const Image& image);

/// Image texel (i, j) that unknown u takes its value from: its own, or for an active texel
/// outside the image the nearest image texel (clamp-to-edge: what a renderer shows there).
std::array<int, 2> imageTexelOf(const TexelGrid& grid, int u);

/// Values of `image` at the grid's unknowns (unknownCount x channels). Active texels outside the
/// image take the nearest image texel (clamp-to-edge: what a renderer shows there).
Eigen::MatrixXd gatherTexels(const TexelGrid& grid, const Image& image);

/// Writes unknown values (unknownCount x image.channels) into the in-image texels of `image`;
/// inactive texels are left as they are.
void scatterTexels(const TexelGrid& grid, const Eigen::MatrixXd& values, Image& image);

/// Writes one channel's unknown values (unknownCount) into channel c of the in-image texels of
/// `image`, as scatterTexels writes that column.
void scatterTexelChannel(const TexelGrid& grid, const Eigen::Ref<const Eigen::VectorXd>& values,
                         int c, Image& image);

/// Per-cell values of a scalar map sampled bilinearly at cell centres (indexed by
/// TexelGrid::cellIndex), mapped linearly from [0, 1] onto [low, high]. Channel 0 is used for
/// one-channel maps, the mean of the first three channels otherwise. The map may have any size.
std::vector<double> cellValuesFromMap(const TexelGrid& grid, const Image& map, double low,
                                      double high);

}  // namespace texgrad
