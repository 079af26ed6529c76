// Viewer module: locating cell centres on the surface and painting the per-cell beta factor.
#include "texgrad/viewer/beta_brush.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace texgrad::viewer {
namespace {

/// Twice the signed area of a UV triangle below which it is skipped (no cell lies inside it).
constexpr double kDegenerateUvArea = 1e-14;

/// Barycentric coordinates of p in triangle (a, b, c); `area2` = twice its signed area.
Eigen::Vector3d barycentric(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                            const Eigen::Vector2d& b, const Eigen::Vector2d& c, double area2) {
  const auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return u.x() * v.y() - u.y() * v.x();
  };
  const double l0 = cross(b - p, c - p) / area2;
  const double l1 = cross(c - p, a - p) / area2;
  return {l0, l1, 1.0 - l0 - l1};
}

}  // namespace

BetaBrush::BetaBrush(const TexturedMesh& mesh, const TexelGrid& grid)
    : factors_(grid.cellCoverage.size(), 1.0) {
  Eigen::AlignedBox3d box;
  for (const auto& p : mesh.positions) box.extend(p);
  if (!box.isEmpty()) diagonal_ = std::max(box.diagonal().norm(), 1e-12);

  // Best face per cell: the one whose (clamped) barycentrics need the least clamping.
  const size_t cellCount = grid.cellCoverage.size();
  std::vector<float> misfit(cellCount, std::numeric_limits<float>::infinity());
  std::vector<Eigen::Vector3f> position(cellCount, Eigen::Vector3f::Zero());
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    std::array<Eigen::Vector2d, 3> g;
    for (int k = 0; k < 3; ++k) g[k] = grid.toGrid(mesh.uvs[mesh.uvTriangles[f][k]]);
    const double area2 =
        (g[1] - g[0]).x() * (g[2] - g[0]).y() - (g[1] - g[0]).y() * (g[2] - g[0]).x();
    if (std::abs(area2) < kDegenerateUvArea) continue;
    // Cell (a, b) has its centre at (a + 0.5, b + 0.5); look one cell beyond the triangle's box.
    const double minX = std::min({g[0].x(), g[1].x(), g[2].x()});
    const double maxX = std::max({g[0].x(), g[1].x(), g[2].x()});
    const double minY = std::min({g[0].y(), g[1].y(), g[2].y()});
    const double maxY = std::max({g[0].y(), g[1].y(), g[2].y()});
    const int a0 = std::max(-1, static_cast<int>(std::floor(minX - 1.0)));
    const int a1 = std::min(grid.nx - 1, static_cast<int>(std::ceil(maxX)));
    const int b0 = std::max(-1, static_cast<int>(std::floor(minY - 1.0)));
    const int b1 = std::min(grid.ny - 1, static_cast<int>(std::ceil(maxY)));
    const auto& tri = mesh.triangles[f];
    for (int b = b0; b <= b1; ++b)
      for (int a = a0; a <= a1; ++a) {
        const int cell = grid.cellIndex(a, b);
        if (grid.cellCoverage[cell] == CellCoverage::Empty) continue;
        Eigen::Vector3d l = barycentric({a + 0.5, b + 0.5}, g[0], g[1], g[2], area2);
        const double outside = -std::min({l.x(), l.y(), l.z(), 0.0});
        if (outside > 1.0 || static_cast<float>(outside) >= misfit[cell]) continue;
        l = l.cwiseMax(0.0);
        l /= l.sum();
        misfit[cell] = static_cast<float>(outside);
        position[cell] = (l.x() * mesh.positions[tri[0]] + l.y() * mesh.positions[tri[1]] +
                          l.z() * mesh.positions[tri[2]])
                             .cast<float>();
      }
  }
  for (size_t c = 0; c < cellCount; ++c)
    if (std::isfinite(misfit[c])) {
      cells_.push_back(static_cast<int32_t>(c));
      centres_.push_back(position[c]);
    }
}

int BetaBrush::paint(const Eigen::Vector3d& centre, double radius, double strength, double target) {
  const Eigen::Vector3f p = centre.cast<float>();
  const float r2 = static_cast<float>(radius * radius);
  int touched = 0;
  for (size_t i = 0; i < cells_.size(); ++i) {
    const float d2 = (centres_[i] - p).squaredNorm();
    if (d2 >= r2) continue;
    const double falloff = 1.0 - std::sqrt(static_cast<double>(d2)) / radius;
    double& factor = factors_[cells_[i]];
    factor += strength * falloff * falloff * (target - factor);
    ++touched;
  }
  if (touched > 0) untouched_ = false;
  return touched;
}

void BetaBrush::clear() {
  std::fill(factors_.begin(), factors_.end(), 1.0);
  untouched_ = true;
}

}  // namespace texgrad::viewer
