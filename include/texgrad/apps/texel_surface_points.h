// Where each texel sits on the surface: the 3-D point a texel stands for, for apps that look at
// the surface from outside the atlas (projecting photos onto the texture).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "texgrad/apps/texel_domain.h"

namespace texgrad {

/// One surface point per unknown. A texel whose centre lies in a valid UV triangle takes that
/// point (the first face in index order where UVs stack, as texelCentreFaces); a boundary texel
/// whose centre lies outside M takes the point of M nearest to its centre in texel coordinates,
/// searched over the faces whose UV triangle meets its footprint (so it stays in its own chart's
/// neighbourhood instead of jumping across the atlas).
struct TexelSurfacePoints {
  std::vector<int32_t> face;  ///< per unknown: face holding the point (-1: none found)
  Eigen::MatrixX3d position;  ///< per unknown (rows): 3-D position, model units
  /// Per unknown: UV distance of the point from the texel centre, in texels (0 inside M).
  std::vector<double> offset;
  /// Per face: d(position) / d(texel coordinates), a 3 x 2 matrix (zero for invalid faces).
  std::vector<Eigen::Matrix<double, 3, 2>> jacobian;
};

/// Surface points of every unknown of `domain`.
TexelSurfacePoints texelSurfacePoints(const TexelDomain& domain);

}  // namespace texgrad
