// Viewer module: the filter app's painted gradient-scale map (paper §7.1 local filtering): brush
// dabs on the surface change a per-cell factor that scales the filter's global beta.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad::viewer {

/// Per-cell factor map (indexed by TexelGrid::cellIndex, 1 = unpainted) with the 3-D position of
/// every covered cell's centre, so a dab reaches every cell within a 3-D radius, across seams.
class BetaBrush {
 public:
  /// Locates every covered cell centre on the mesh (by the UV triangle containing it, or the
  /// nearest one for partially covered cells whose centre lies outside every triangle).
  BetaBrush(const TexturedMesh& mesh, const TexelGrid& grid);

  /// Moves the factor of cells within `radius` (model units) of `centre` towards `target` by
  /// strength * falloff, falloff = (1 - d / radius)^2. Returns the number of cells touched.
  int paint(const Eigen::Vector3d& centre, double radius, double strength, double target);
  /// Sets every factor back to 1.
  void clear();
  /// True if no cell has been painted since construction or clear().
  bool untouched() const { return untouched_; }
  /// Factor per cell (size = grid.cellCoverage.size()).
  const std::vector<double>& factors() const { return factors_; }
  /// Length of the mesh's bounding-box diagonal (brush radii are fractions of it).
  double diagonal() const { return diagonal_; }
  /// Covered cells that were located on the surface.
  size_t locatedCells() const { return cells_.size(); }

 private:
  std::vector<double> factors_;
  std::vector<int32_t> cells_;            ///< located cell indices
  std::vector<Eigen::Vector3f> centres_;  ///< their 3-D positions
  double diagonal_ = 1.0;
  bool untouched_ = true;
};

}  // namespace texgrad::viewer
