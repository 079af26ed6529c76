// Immersion metric per face: J = E3 * Ep^{-1} from 3-D and texel-coordinate edge vectors.
#include "texgrad/fem/metric.h"

#include <Eigen/Dense>
#include <cmath>

namespace texgrad::fem {
namespace {

/// A metric with det g < kDegenerateRatio * (tr g / 2)^2 is treated as degenerate (the 3-D
/// triangle is a sliver or collapsed while its UV triangle is not).
constexpr double kDegenerateRatio = 1e-12;
/// Regularisation added to degenerate metrics, relative to tr(g) / 2 (or to the mean metric).
constexpr double kRegularisation = 1e-6;

Eigen::Vector2d gridCorner(const TexturedMesh& mesh, const TexelGrid& grid, int face, int c) {
  return grid.toGrid(mesh.uvs[mesh.uvTriangles[face][c]]);
}

}  // namespace

double gridArea(const TexturedMesh& mesh, const TexelGrid& grid, int face) {
  const Eigen::Vector2d a = gridCorner(mesh, grid, face, 0);
  const Eigen::Vector2d e1 = gridCorner(mesh, grid, face, 1) - a;
  const Eigen::Vector2d e2 = gridCorner(mesh, grid, face, 2) - a;
  return 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
}

std::vector<Eigen::Matrix2d> immersionMetric(const TexturedMesh& mesh, const TexelGrid& grid,
                                             MetricReport* report) {
  MetricReport local;
  const int faces = static_cast<int>(mesh.faceCount());
  std::vector<Eigen::Matrix2d> g(faces, Eigen::Matrix2d::Zero());
  for (int f = 0; f < faces; ++f) {
    if (gridArea(mesh, grid, f) == 0.0) {
      ++local.uvDegenerateFaces;
      continue;
    }
    const auto& tri = mesh.triangles[f];
    Eigen::Matrix<double, 3, 2> e3;
    e3.col(0) = mesh.positions[tri[1]] - mesh.positions[tri[0]];
    e3.col(1) = mesh.positions[tri[2]] - mesh.positions[tri[0]];
    local.surfaceArea += 0.5 * e3.col(0).cross(e3.col(1)).norm();
    Eigen::Matrix2d ep;
    const Eigen::Vector2d p0 = gridCorner(mesh, grid, f, 0);
    ep.col(0) = gridCorner(mesh, grid, f, 1) - p0;
    ep.col(1) = gridCorner(mesh, grid, f, 2) - p0;
    const Eigen::Matrix<double, 3, 2> jac = e3 * ep.inverse();
    g[f] = jac.transpose() * jac;
  }
  const double scale = local.surfaceArea > 0.0 ? 1.0 / local.surfaceArea : 1.0;
  double meanHalfTrace = 0.0;
  int counted = 0;
  for (auto& m : g) {
    m *= scale;
    if (m.trace() > 0.0) {
      meanHalfTrace += 0.5 * m.trace();
      ++counted;
    }
  }
  meanHalfTrace = counted ? meanHalfTrace / counted : 1.0;
  for (int f = 0; f < faces; ++f) {
    Eigen::Matrix2d& m = g[f];
    if (m.isZero(0.0) && gridArea(mesh, grid, f) == 0.0) continue;
    const double halfTrace = 0.5 * m.trace();
    if (m.determinant() < kDegenerateRatio * halfTrace * halfTrace || halfTrace <= 0.0) {
      const double base = halfTrace > 0.0 ? halfTrace : meanHalfTrace;
      m += kRegularisation * base * Eigen::Matrix2d::Identity();
      ++local.regularisedFaces;
    }
  }
  if (report) *report = local;
  return g;
}

}  // namespace texgrad::fem
