// Rasterises the chart-boundary edges of an atlas onto the texel footprints they cross.
#include "texgrad/atlas/chart_boundary_texels.h"

#include <algorithm>
#include <cmath>

namespace texgrad {
namespace {

/// True if the segment [a, b] meets the open square (c - 1, c + 1)^2 (a texel footprint). The
/// segment is clipped to the closed square (Liang-Barsky); a chord of a convex polygon that is
/// not on its border has its midpoint inside, so the midpoint decides. Exact for segments on
/// lattice lines: a chart edge along a footprint's border does not meet it.
bool meetsOpenFootprint(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                        const Eigen::Vector2d& c) {
  const Eigen::Vector2d d = b - a;
  double t0 = 0.0, t1 = 1.0;
  for (int axis = 0; axis < 2; ++axis) {
    const double lo = c[axis] - 1.0, hi = c[axis] + 1.0;
    if (d[axis] == 0.0) {
      if (a[axis] <= lo || a[axis] >= hi) return false;
      continue;
    }
    double ta = (lo - a[axis]) / d[axis], tb = (hi - a[axis]) / d[axis];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return false;
  const Eigen::Vector2d m = a + 0.5 * (t0 + t1) * d;
  return std::abs(m.x() - c.x()) < 1.0 && std::abs(m.y() - c.y()) < 1.0;
}

/// Marks the texels whose open footprint the grid-space segment [a, b] meets. The segment is cut
/// into pieces at most one texel long so each piece tests only the few texels around it.
void markSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const TexelGrid& grid,
                 std::vector<uint8_t>& marked) {
  const int pieces = std::max(1, static_cast<int>(std::ceil((b - a).norm())));
  for (int k = 0; k < pieces; ++k) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(k) / pieces);
    const Eigen::Vector2d q =
        k + 1 == pieces ? b : a + (b - a) * (static_cast<double>(k + 1) / pieces);
    const Eigen::Vector2d lo = p.cwiseMin(q), hi = p.cwiseMax(q);
    // Texel x can meet the piece only if x - 1 < hi.x and x + 1 > lo.x.
    const int x0 = std::max(0, static_cast<int>(std::floor(lo.x())));
    const int x1 = std::min(grid.nx - 1, static_cast<int>(std::ceil(hi.x())));
    const int y0 = std::max(0, static_cast<int>(std::floor(lo.y())));
    const int y1 = std::min(grid.ny - 1, static_cast<int>(std::ceil(hi.y())));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        if (meetsOpenFootprint(p, q, Eigen::Vector2d(x, y)))
          marked[static_cast<size_t>(grid.texelIndex(x, y))] = 1;
  }
}

}  // namespace

std::vector<uint8_t> chartBoundaryTexels(const TexturedMesh& mesh, const Atlas& atlas,
                                         const TexelGrid& grid) {
  std::vector<uint8_t> marked(static_cast<size_t>(grid.nx) * static_cast<size_t>(grid.ny), 0);
  auto mark = [&](const FaceEdge& e) {
    const Triangle& uv = mesh.uvTriangles[static_cast<size_t>(e.face)];
    const Eigen::Vector2d a =
        grid.toGrid(mesh.uvs[static_cast<size_t>(uv[static_cast<size_t>(e.corner)])]);
    const Eigen::Vector2d b =
        grid.toGrid(mesh.uvs[static_cast<size_t>(uv[static_cast<size_t>((e.corner + 1) % 3)])]);
    markSegment(a, b, grid, marked);
  };
  for (const SeamPair& seam : atlas.seams) {
    mark(seam.a);
    mark(seam.b);
  }
  for (const FaceEdge& e : atlas.openBoundary) mark(e);
  for (const std::vector<FaceEdge>& edges : atlas.nonManifoldEdges)
    for (const FaceEdge& e : edges) mark(e);
  return marked;
}

}  // namespace texgrad
