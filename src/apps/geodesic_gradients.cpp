// The heat method's gradient samples and their divergence (paper Sec. 7.3): the samples are
// built from the clipped faces once, and div_h(-du/|du|) streams over them once per update.
#include "apps/geodesic_gradients.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>

#include "texgrad/atlas/cell_clipping.h"

namespace texgrad {
namespace {

/// Faces per parallel task when building gradient samples (fixed: results do not depend on
/// threads).
constexpr int kFacesPerTask = 64;

/// Stiffness given to the twist mode of a cut cell's uncovered part, as a fraction of the twist
/// stiffness of a covered cell: 1 fills the cell. The analytic tests barely move (sphere at 256²:
/// mean error 3.17e-4 -> 3.18e-4), while on Lantern at 256² the lowest texel goes from -4.9
/// times the largest distance to above zero (0.1 still leaves texels at -0.5% of it).
constexpr double kCutCellStiffening = 1.0;
/// Energy of the twist mode (1 - 2 fx)(1 - 2 fy) c over a covered cell is twist^2 s / 12 with
/// twist = 4 c and s = tr(g^-1) sqrt|g| (paper Sec. 5.1 stiffness, bilinear basis).
constexpr double kTwistEnergy = 1.0 / 12.0;

}  // namespace

GeodesicGradients::GeodesicGradients(const TexelDomain& domain, int threads)
    : arena(threads > 0 ? threads : tbb::task_arena::automatic) {
  arena.execute([&] { build(domain); });
}

void GeodesicGradients::build(const TexelDomain& domain) {
  const fem::TexelBasis& basis = domain.operators().basis();
  const TexelGrid& grid = domain.grid();
  const auto& metric = domain.operators().metric();
  const int faces = basis.faceCount();
  const int chunks = (faces + kFacesPerTask - 1) / kFacesPerTask;
  faceMetrics.assign(static_cast<size_t>(faces), FaceMetric{});
  struct Chunk {
    std::vector<CellSample> cells;
    std::vector<int32_t> cellRows;  ///< cell row b of each cell sample (for the colour bands)
    std::vector<SeamSample> seams;
    std::vector<int32_t> texels;
    std::vector<Eigen::Vector2d> gradients;
    std::vector<CellCover> covers;
  };
  std::vector<Chunk> out(static_cast<size_t>(chunks));
  tbb::parallel_for(0, chunks, [&](int c) {
    Chunk& chunk = out[static_cast<size_t>(c)];
    FaceClip clip;
    fem::PieceBasis pb;
    for (int f = c * kFacesPerTask; f < std::min(faces, (c + 1) * kFacesPerTask); ++f) {
      if (!basis.faceValid(f)) continue;
      const Eigen::Matrix2d& g = metric[static_cast<size_t>(f)];
      const double root = std::sqrt(g.determinant());
      const Eigen::Matrix2d h = g.inverse();
      faceMetrics[static_cast<size_t>(f)] = {root, h(0, 0), h(0, 1), h(1, 1)};
      basis.clipFace(f, clip);
      for (const auto& piece : clip.pieces) {
        const auto poly = clip.polygon(piece);
        const double pieceArea = polygonArea(poly);
        if (pieceArea > 0.0)
          chunk.covers.push_back({grid.cellIndex(piece.cellX, piece.cellY),
                                  domain.atlas().chartOfFace[static_cast<size_t>(f)], pieceArea,
                                  pieceArea * (h(0, 0) + h(1, 1)) * root});
        if (basis.isPlain(f, poly)) {
          const Eigen::Vector2d origin(piece.cellX, piece.cellY);
          double area = 0.0;
          Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
          for (size_t i = 0; i < poly.size(); ++i) {
            const Eigen::Vector2d p = poly[i].p - origin,
                                  q = poly[(i + 1) % poly.size()].p - origin;
            const double cross = p.x() * q.y() - p.y() * q.x();
            area += cross;
            centroid += cross * (p + q);
          }
          if (!(area > 0.0)) continue;
          centroid /= 3.0 * area;
          area *= 0.5;
          chunk.cells.push_back({basis.cellTexels(piece.cellX, piece.cellY), piece.cellX,
                                 static_cast<float>(centroid.x()), static_cast<float>(centroid.y()),
                                 static_cast<float>(area), f});
          chunk.cellRows.push_back(piece.cellY);
          continue;
        }
        basis.buildPieceBasis(f, poly, pb);
        for (size_t e = 0; e < pb.elements.size(); ++e) {
          const auto& t = pb.elements[e];
          Eigen::Matrix2d m;
          m.col(0) = t[1] - t[0];
          m.col(1) = t[2] - t[0];
          const double area = 0.5 * m.determinant();
          if (!(area > 0.0)) continue;
          const Eigen::Matrix2d inv = m.inverse();
          const std::array<Eigen::Vector2d, 3> bg{-(inv.row(0) + inv.row(1)).transpose(),
                                                  inv.row(0).transpose(), inv.row(1).transpose()};
          // Quadratic shape gradients at the centroid (b = 1/3): corners (4 b_i - 1) grad b_i,
          // midpoints of (i, j) 4 (b_j grad b_i + b_i grad b_j).
          Eigen::Matrix<double, 6, 2> dshape;
          for (int i = 0; i < 3; ++i) dshape.row(i) = bg[i].transpose() / 3.0;
          dshape.row(3) = (4.0 / 3.0) * (bg[0] + bg[1]).transpose();
          dshape.row(4) = (4.0 / 3.0) * (bg[1] + bg[2]).transpose();
          dshape.row(5) = (4.0 / 3.0) * (bg[2] + bg[0]).transpose();
          const auto coefficients = pb.coefficients.middleRows(static_cast<Eigen::Index>(6 * e), 6);
          const Eigen::MatrixXd grads = coefficients.transpose() * dshape;  // k x 2
          SeamSample s{
              static_cast<int32_t>(chunk.texels.size()), 0, area * root, h(0, 0), h(0, 1), h(1, 1)};
          for (size_t k = 0; k < pb.texels.size(); ++k) {
            if (pb.texels[k] < 0) continue;
            chunk.texels.push_back(pb.texels[k]);
            chunk.gradients.emplace_back(grads.row(static_cast<Eigen::Index>(k)).transpose());
          }
          s.end = static_cast<int32_t>(chunk.texels.size());
          chunk.seams.push_back(s);
        }
      }
    }
  });
  std::vector<CellCover> covers;
  for (Chunk& chunk : out) covers.insert(covers.end(), chunk.covers.begin(), chunk.covers.end());
  collectCutCells(basis, grid, std::move(covers));
  rowBegin.assign(static_cast<size_t>(grid.ny) + 2, 0);
  for (const Chunk& chunk : out)
    for (int32_t row : chunk.cellRows) ++rowBegin[static_cast<size_t>(row) + 2];
  for (size_t r = 1; r < rowBegin.size(); ++r) rowBegin[r] += rowBegin[r - 1];
  std::vector<int64_t> cursor(rowBegin.begin(), rowBegin.end() - 1);
  cells.resize(static_cast<size_t>(rowBegin.back()));
  for (Chunk& chunk : out) {
    for (size_t i = 0; i < chunk.cells.size(); ++i)
      cells[static_cast<size_t>(cursor[static_cast<size_t>(chunk.cellRows[i]) + 1]++)] =
          chunk.cells[i];
    const auto base = static_cast<int32_t>(seamTexels.size());
    for (SeamSample s : chunk.seams) {
      s.begin += base;
      s.end += base;
      seams.push_back(s);
    }
    seamTexels.insert(seamTexels.end(), chunk.texels.begin(), chunk.texels.end());
    seamGradients.insert(seamGradients.end(), chunk.gradients.begin(), chunk.gradients.end());
    chunk = Chunk();
  }
  tbb::parallel_for(size_t(0), rowBegin.size() - 1, [&](size_t row) {
    std::stable_sort(cells.begin() + rowBegin[row], cells.begin() + rowBegin[row + 1],
                     [](const CellSample& a, const CellSample& b) { return a.cellX < b.cellX; });
  });
  seamTargets = seamTexels;
  std::sort(seamTargets.begin(), seamTargets.end());
  seamTargets.erase(std::unique(seamTargets.begin(), seamTargets.end()), seamTargets.end());
  seamTargetOfEntry.resize(seamTexels.size());
  for (size_t k = 0; k < seamTexels.size(); ++k)
    seamTargetOfEntry[k] = static_cast<int32_t>(
        std::lower_bound(seamTargets.begin(), seamTargets.end(), seamTexels[k]) -
        seamTargets.begin());
  seamSums.assign(seamTargets.size(), 0.0);
  seamDirections.resize(seams.size());
}

void GeodesicGradients::collectCutCells(const fem::TexelBasis& basis, const TexelGrid& grid,
                                        std::vector<CellCover> covers) {
  std::sort(covers.begin(), covers.end(), [](const CellCover& a, const CellCover& b) {
    return a.cell != b.cell ? a.cell < b.cell : a.chart < b.chart;
  });
  cutCells.clear();
  for (size_t begin = 0, end = 0; begin < covers.size(); begin = end) {
    double area = 0.0, stiffness = 0.0;
    bool oneChart = true;
    for (end = begin; end < covers.size() && covers[end].cell == covers[begin].cell; ++end) {
      oneChart = oneChart && covers[end].chart == covers[begin].chart;
      area += covers[end].area;
      stiffness += covers[end].stiffness;
    }
    // A cell shared by two charts holds texels of both: a plane through them means nothing.
    if (!oneChart || area >= 1.0) continue;
    const int32_t cell = covers[begin].cell;
    const int a = cell % (grid.nx + 1) - 1, b = cell / (grid.nx + 1) - 1;
    const std::array<int32_t, 4> texels = basis.cellTexels(a, b);
    if (*std::min_element(texels.begin(), texels.end()) < 0) continue;
    // The uncovered part takes the mean tr(g^-1) sqrt|g| of the faces that cover the cell.
    cutCells.push_back(
        {texels, kCutCellStiffening * kTwistEnergy * (1.0 - area) * stiffness / area});
  }
}

void GeodesicGradients::releaseSamples() {
  // Swapping with empty vectors returns the storage (clear() would keep the capacity).
  std::vector<CellSample>().swap(cells);
  std::vector<FaceMetric>().swap(faceMetrics);
  std::vector<int64_t>().swap(rowBegin);
  std::vector<SeamSample>().swap(seams);
  std::vector<int32_t>().swap(seamTexels);
  std::vector<Eigen::Vector2d>().swap(seamGradients);
  std::vector<Eigen::Vector2d>().swap(seamDirections);
  std::vector<int32_t>().swap(seamTargets);
  std::vector<int32_t>().swap(seamTargetOfEntry);
  std::vector<double>().swap(seamSums);
  std::vector<CutCell>().swap(cutCells);
}

Eigen::SparseMatrix<double> GeodesicGradients::stabiliser(Eigen::Index n) const {
  constexpr std::array<double, 4> kTwist{1.0, -1.0, -1.0, 1.0};
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(16 * cutCells.size());
  for (const CutCell& c : cutCells)
    for (size_t i = 0; i < 4; ++i)
      for (size_t j = 0; j < 4; ++j)
        entries.emplace_back(c.texels[i], c.texels[j], c.weight * kTwist[i] * kTwist[j]);
  Eigen::SparseMatrix<double> g(n, n);
  g.setFromTriplets(entries.begin(), entries.end());
  return g;
}

namespace {

/// X = -g^-1 du / |du|_{g^-1} (unit in g) times `weight`: the direction of steepest descent of
/// u; zero where du = 0.
inline Eigen::Vector2d descentDirection(double gx, double gy, double hxx, double hxy, double hyy,
                                        double weight) {
  const double zx = hxx * gx + hxy * gy, zy = hxy * gx + hyy * gy;
  const double norm2 = gx * zx + gy * zy;
  if (!(norm2 > 0.0) || !std::isfinite(norm2)) return Eigen::Vector2d(0.0, 0.0);
  const double s = -weight / std::sqrt(norm2);
  return Eigen::Vector2d(s * zx, s * zy);
}

}  // namespace

void GeodesicGradients::addRowDivergence(const CellSample* first, const CellSample* last,
                                         const FaceMetric* metrics, const double* u, double* div) {
  // The samples of one cell row come by column, so the sums for the two texel columns of the
  // current cell stay in registers and each texel is written once per row: adding every sample
  // straight into div chains each addition behind the previous sample's store to that texel.
  std::array<int32_t, 4> texels{-1, -1, -1, -1};  // of the current cell
  std::array<double, 4> sum{};                    // same order as texels
  int32_t column = std::numeric_limits<int32_t>::min();
  auto flush = [&](int k) {
    if (texels[k] >= 0) div[texels[k]] += sum[k];
  };
  for (const CellSample* s = first; s != last; ++s) {
    if (s->cellX != column) {
      const bool next = s->cellX == column + 1;
      flush(0);
      flush(2);
      if (!next) {
        flush(1);
        flush(3);
      }
      sum = {next ? sum[1] : 0.0, 0.0, next ? sum[3] : 0.0, 0.0};
      texels = s->texels;
      column = s->cellX;
    }
    std::array<double, 4> v{};
    for (int k = 0; k < 4; ++k) v[k] = texels[k] >= 0 ? u[texels[k]] : 0.0;
    const double fx = s->fx, fy = s->fy;
    const double gx = (1 - fy) * (v[1] - v[0]) + fy * (v[3] - v[2]);
    const double gy = (1 - fx) * (v[2] - v[0]) + fx * (v[3] - v[1]);
    const FaceMetric& m = metrics[s->face];
    const Eigen::Vector2d x = descentDirection(gx, gy, m.hxx, m.hxy, m.hyy, s->area * m.root);
    const double xx = x.x(), xy = x.y();
    sum[0] += -(1 - fy) * xx - (1 - fx) * xy;
    sum[1] += (1 - fy) * xx - fx * xy;
    sum[2] += -fy * xx + (1 - fx) * xy;
    sum[3] += fy * xx + fx * xy;
  }
  for (int k = 0; k < 4; ++k) flush(k);
}

void GeodesicGradients::divergence(const double* u, double* div, Eigen::Index n) {
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, kGeodesicUnknownsPerTask),
                      [&](const tbb::blocked_range<Eigen::Index>& range) {
                        std::fill(div + range.begin(), div + range.end(), 0.0);
                      });
    const int rows = static_cast<int>(rowBegin.size()) - 1;  // cell rows -1 .. ny - 1
    // Cell rows b and b + 2 touch disjoint texel rows, so each colour runs its rows in parallel;
    // every texel gets its contributions in the same order for any thread count.
    auto cellPart = [&] {
      for (int colour = 0; colour < 2; ++colour) {
        tbb::parallel_for(0, (rows + 1 - colour) / 2, [&](int half) {
          const size_t slot = static_cast<size_t>(2 * half + colour);
          addRowDivergence(cells.data() + rowBegin[slot], cells.data() + rowBegin[slot + 1],
                           faceMetrics.data(), u, div);
        });
      }
    };
    // Seam samples share texels in no fixed pattern: directions in parallel, then the sums in
    // entry order into a compact array per seam texel, alongside the cell part.
    auto seamPart = [&] {
      tbb::parallel_for(size_t(0), seams.size(), [&](size_t i) {
        const SeamSample& s = seams[i];
        Eigen::Vector2d grad = Eigen::Vector2d::Zero();
        for (int32_t k = s.begin; k < s.end; ++k) grad += u[seamTexels[k]] * seamGradients[k];
        seamDirections[i] = descentDirection(grad.x(), grad.y(), s.hxx, s.hxy, s.hyy, s.weight);
      });
      std::fill(seamSums.begin(), seamSums.end(), 0.0);
      for (size_t i = 0; i < seams.size(); ++i)
        for (int32_t k = seams[i].begin; k < seams[i].end; ++k)
          seamSums[static_cast<size_t>(seamTargetOfEntry[static_cast<size_t>(k)])] +=
              seamGradients[k].dot(seamDirections[i]);
    };
    tbb::parallel_invoke(cellPart, seamPart);
    tbb::parallel_for(size_t(0), seamTargets.size(),
                      [&](size_t j) { div[seamTargets[j]] += seamSums[j]; });
  });
}

}  // namespace texgrad
