// barelyCoveredTexels: the kernel integrals of the pieces T ∩ cell of the partially covered cells
// (cell_clipping.h), summed per texel in face order.
#include "texgrad/atlas/texel_kernel_coverage.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <span>
#include <string>

#include "texgrad/atlas/cell_clipping.h"
#include "texgrad/core/error.h"

namespace texgrad {
namespace {

/// Faces per parallel clipping task.
constexpr int32_t kFacesPerTask = 256;
/// The kernel weight a Full cell gives each of its four corner texels.
constexpr double kFullCellShare = 0.25;
static_assert(kFullCellShare >= kMaxBarelyCoveredFraction,
              "a texel with a Full cell is never barely covered");

/// Integrals over one piece of the four corner texels' kernels, corner k = (a + (k & 1),
/// b + (k >> 1)) of cell (a, b).
struct PieceKernels {
  int32_t cellX, cellY;
  std::array<double, 4> integral;
};

/// Integrals of 1, x, y and x y over a convex polygon in cell-local coordinates (fan of
/// triangles; a triangle's quadratic moments are exact with its edge midpoints).
std::array<double, 4> polygonMoments(std::span<const PieceVertex> polygon, int a, int b) {
  std::array<double, 4> m{};
  const Eigen::Vector2d origin(a, b);
  const Eigen::Vector2d p0 = polygon[0].p - origin;
  for (size_t k = 1; k + 1 < polygon.size(); ++k) {
    const Eigen::Vector2d p1 = polygon[k].p - origin, p2 = polygon[k + 1].p - origin;
    const Eigen::Vector2d e1 = p1 - p0, e2 = p2 - p0;
    const double area = 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
    const double sx = p0.x() + p1.x() + p2.x(), sy = p0.y() + p1.y() + p2.y();
    const double sxy = p0.x() * p0.y() + p1.x() * p1.y() + p2.x() * p2.y();
    m[0] += area;
    m[1] += area * sx / 3.0;
    m[2] += area * sy / 3.0;
    m[3] += area * (sxy + sx * sy) / 12.0;
  }
  return m;
}

/// Kernel integrals of the pieces of faces [begin, end) that lie in Partial cells.
void clipFaces(const TexturedMesh& mesh, const TexelGrid& g, int32_t begin, int32_t end,
               std::vector<PieceKernels>& out) {
  FaceClip clip;
  std::array<std::vector<EdgeEvent>, 3> events;
  for (int32_t f = begin; f < end; ++f) {
    std::array<Eigen::Vector2d, 3> c;
    for (int k = 0; k < 3; ++k) c[k] = g.toGrid(mesh.uvs[mesh.uvTriangles[f][k]]);
    const Eigen::Vector2d e1 = c[1] - c[0], e2 = c[2] - c[0];
    if (e1.x() * e2.y() - e1.y() * e2.x() == 0.0) continue;  // UV-degenerate: covers nothing
    std::array<std::span<const EdgeEvent>, 3> spans;
    for (int e = 0; e < 3; ++e) {
      events[e] = latticeCrossings(c[e], c[(e + 1) % 3]);
      spans[e] = events[e];
    }
    clipTriangleToCells(c, spans, clip);
    for (const FacePiece& piece : clip.pieces) {
      const auto cell = static_cast<size_t>(g.cellIndex(piece.cellX, piece.cellY));
      if (g.cellCoverage[cell] != CellCoverage::Partial) continue;
      // Area, x, y, x y moments; pieces are counter-clockwise, so the area is positive.
      const std::array<double, 4> m = polygonMoments(clip.polygon(piece), piece.cellX, piece.cellY);
      // Corner kernels in the cell: (1 - x)(1 - y), x (1 - y), (1 - x) y, x y.
      out.push_back(
          {piece.cellX, piece.cellY, {m[0] - m[1] - m[2] + m[3], m[1] - m[3], m[2] - m[3], m[3]}});
    }
  }
}

/// Unknowns (ascending) none of whose four footprint cells is Full.
std::vector<int32_t> unknownsWithoutFullCells(const TexelGrid& g) {
  std::vector<int32_t> out;
  for (int32_t u = 0; u < g.unknownCount(); ++u) {
    const int32_t t = g.texelOfUnknown[static_cast<size_t>(u)];
    const int x = t % g.nx, y = t / g.nx;
    bool full = false;
    for (int k = 0; k < 4 && !full; ++k)
      full = g.cellCoverage[static_cast<size_t>(g.cellIndex(x - 1 + (k & 1), y - 1 + (k >> 1)))] ==
             CellCoverage::Full;
    if (!full) out.push_back(u);
  }
  return out;
}

}  // namespace

std::vector<int32_t> barelyCoveredTexels(const TexturedMesh& mesh, const TexelGrid& grid,
                                         double fraction) {
  if (!(fraction > 0.0 && fraction <= kMaxBarelyCoveredFraction))
    throw InvalidInputError("the barely-covered fraction must lie in (0, 0.25], got " +
                            std::to_string(fraction));
  const auto faces = static_cast<int32_t>(mesh.faceCount());
  const int32_t tasks = (faces + kFacesPerTask - 1) / kFacesPerTask;
  std::vector<std::vector<PieceKernels>> pieces(static_cast<size_t>(tasks));
  tbb::parallel_for(0, tasks, [&](int32_t t) {
    clipFaces(mesh, grid, t * kFacesPerTask, std::min(faces, (t + 1) * kFacesPerTask),
              pieces[static_cast<size_t>(t)]);
  });
  // A Full cell gives each of its corners a quarter (kFullCellShare >= fraction), so only the
  // texels without one can fall below `fraction`: their sums alone are formed, indexed by the
  // ascending list of them (a few per cent of the unknowns, not a double per unknown).
  const std::vector<int32_t> candidates = unknownsWithoutFullCells(grid);
  std::vector<double> coverage(candidates.size(), 0.0);
  const auto addTo = [&](int x, int y, double value) {
    if (x < 0 || y < 0 || x >= grid.nx || y >= grid.ny) return;
    const int32_t u = grid.unknownOfTexel[static_cast<size_t>(grid.texelIndex(x, y))];
    const auto at = std::lower_bound(candidates.begin(), candidates.end(), u);
    if (u >= 0 && at != candidates.end() && *at == u) coverage[at - candidates.begin()] += value;
  };
  // Sums in face order (independent of the thread count).
  for (const std::vector<PieceKernels>& task : pieces)
    for (const PieceKernels& p : task)
      for (int k = 0; k < 4; ++k) addTo(p.cellX + (k & 1), p.cellY + (k >> 1), p.integral[k]);
  std::vector<int32_t> barely;
  for (size_t i = 0; i < candidates.size(); ++i)
    if (coverage[i] < fraction) barely.push_back(candidates[i]);
  return barely;
}

}  // namespace texgrad
