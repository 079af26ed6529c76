// Surface points of texels; see the header.
#include "texgrad/apps/texel_surface_points.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "closest_point.h"

namespace texgrad {
namespace {

/// UV distance (texels) below which a texel centre counts as inside a triangle: rounding in the
/// barycentric round trip, far below any geometric scale of the lattice.
constexpr double kInsideTexels = 1e-9;

}  // namespace

TexelSurfacePoints texelSurfacePoints(const TexelDomain& domain) {
  const TexelGrid& grid = domain.grid();
  const TexturedMesh& mesh = domain.mesh();
  const fem::TexelBasis& basis = domain.operators().basis();
  const auto n = static_cast<size_t>(grid.unknownCount());
  TexelSurfacePoints points;
  points.face.assign(n, -1);
  points.position = Eigen::MatrixX3d::Zero(static_cast<Eigen::Index>(n), 3);
  points.offset.assign(n, std::numeric_limits<double>::infinity());
  points.jacobian.assign(static_cast<size_t>(basis.faceCount()),
                         Eigen::Matrix<double, 3, 2>::Zero());
  for (int face = 0; face < basis.faceCount(); ++face) {
    if (!basis.faceValid(face)) continue;
    const auto& c = basis.faceCorners(face);
    const Triangle& tri = mesh.triangles[static_cast<size_t>(face)];
    const Eigen::Vector3d& p0 = mesh.positions[static_cast<size_t>(tri[0])];
    const Eigen::Vector3d& p1 = mesh.positions[static_cast<size_t>(tri[1])];
    const Eigen::Vector3d& p2 = mesh.positions[static_cast<size_t>(tri[2])];
    Eigen::Matrix2d e;
    e.col(0) = c[1] - c[0];
    e.col(1) = c[2] - c[0];
    Eigen::Matrix<double, 3, 2> edges;
    edges.col(0) = p1 - p0;
    edges.col(1) = p2 - p0;
    points.jacobian[static_cast<size_t>(face)] = edges * e.inverse();
    // Texels whose footprint [x - 1, x + 1]^2 meets the UV triangle.
    const Eigen::Vector2d lo = c[0].cwiseMin(c[1]).cwiseMin(c[2]);
    const Eigen::Vector2d hi = c[0].cwiseMax(c[1]).cwiseMax(c[2]);
    const int x0 = std::max(0, static_cast<int>(std::floor(lo.x())) - 1);
    const int y0 = std::max(0, static_cast<int>(std::floor(lo.y())) - 1);
    const int x1 = std::min(grid.nx - 1, static_cast<int>(std::ceil(hi.x())) + 1);
    const int y1 = std::min(grid.ny - 1, static_cast<int>(std::ceil(hi.y())) + 1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const int32_t u = grid.unknownOfTexel[static_cast<size_t>(grid.texelIndex(x, y))];
        if (u < 0) continue;
        const auto k = static_cast<size_t>(u);
        if (points.offset[k] == 0.0) continue;  // an earlier face holds the centre
        const Eigen::Vector2d centre(x, y);
        const Eigen::Vector3d b = closestBarycentric(centre, c[0], c[1], c[2]);
        double offset = (b[0] * c[0] + b[1] * c[1] + b[2] * c[2] - centre).norm();
        if (offset <= kInsideTexels) offset = 0.0;
        if (!(offset < points.offset[k])) continue;
        points.offset[k] = offset;
        points.face[k] = face;
        points.position.row(u) = (b[0] * p0 + b[1] * p1 + b[2] * p2).transpose();
      }
  }
  return points;
}

}  // namespace texgrad
