// Per-face Riemannian metrics in texel coordinates: the immersion metric of the (unit-area) surface
// and its regularisation; operators/ integrates against them (paper Sec. 5.2).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad::fem {

/// What immersionMetric saw while building the metric.
struct MetricReport {
  double surfaceArea = 0.0;   ///< 3-D area of the faces with positive UV area, before scaling
  int uvDegenerateFaces = 0;  ///< faces with zero UV area (excluded from M, metric left zero)
  int regularisedFaces = 0;   ///< faces whose 3-D triangle is (nearly) degenerate
};

/// Per face f: the SPD 2x2 immersion metric g = J^T J, J = d(3-D position)/d(texel coordinates)
/// (3x2), with positions scaled by 1/sqrt(area) so the surface (faces with positive UV area) has
/// unit area (paper Sec. 7). Units: squared unit-area-surface length per squared texel.
/// Faces with zero UV area get a zero matrix; near-degenerate 3-D faces get g + eps tr(g) I.
std::vector<Eigen::Matrix2d> immersionMetric(const TexturedMesh& mesh, const TexelGrid& grid,
                                             MetricReport* report = nullptr);

/// Signed area of face f's UV triangle in grid (texel) units; positive for counter-clockwise.
double gridArea(const TexturedMesh& mesh, const TexelGrid& grid, int face);

}  // namespace texgrad::fem
