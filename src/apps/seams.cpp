// Seam smoothing: a Dirichlet problem on the free texels (harmonic interpolation in the
// seam-continuous space, paper §4), solved with CHOLMOD on the free block.
#include "texgrad/apps/seams.h"

#include <numeric>

#include "texgrad/apps/barely_covered.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/atlas/chart_boundary_texels.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/cholmod_solver.h"

namespace texgrad {
namespace {

/// Weight of the screening term that keeps S_FF positive definite where free texels are only
/// weakly tied to fixed ones, relative to S's scale (mean diagonal of S over that of M). It pulls
/// towards the input, not towards 0, so it never darkens; at 1e-9 it moves a harmonic solution by
/// about that fraction of the texture range.
constexpr double kScreening = 1e-9;

/// Per unknown: 1 if it is a candidate for re-solving: a boundary texel whose footprint a chart
/// boundary crosses (not one that is boundary only because stacked charts cover it), or one under
/// `mask`.
std::vector<uint8_t> candidateUnknowns(const TexelDomain& domain, const Image& mask) {
  const TexelGrid& grid = domain.grid();
  std::vector<uint8_t> candidate(static_cast<size_t>(grid.unknownCount()), 0);
  if (mask.empty()) {
    const std::vector<uint8_t> onBoundary =
        chartBoundaryTexels(domain.mesh(), domain.atlas(), grid);
    // Both tests: the class sees a cell clipped by less than its coverage tolerance as full,
    // the exact crossing test sees stacked charts as covering nothing twice.
    for (int u = 0; u < grid.unknownCount(); ++u) {
      const auto t = static_cast<size_t>(grid.texelOfUnknown[u]);
      candidate[static_cast<size_t>(u)] =
          grid.texelClass[t] == TexelClass::Boundary && onBoundary[t] != 0;
    }
    return candidate;
  }
  if (mask.width != grid.imageWidth || mask.height != grid.imageHeight)
    throw InvalidInputError("the seam mask is " + std::to_string(mask.width) + "x" +
                            std::to_string(mask.height) + " but the texture is " +
                            std::to_string(grid.imageWidth) + "x" +
                            std::to_string(grid.imageHeight));
  const Eigen::VectorXd maskValues = gatherTexels(grid, mask).col(0);
  for (int u = 0; u < grid.unknownCount(); ++u)
    candidate[static_cast<size_t>(u)] = maskValues[u] > 0.5 ? 1 : 0;
  return candidate;
}

/// Union-find root of `u` (with path halving).
int32_t findRoot(std::vector<int32_t>& parent, int32_t u) {
  while (parent[static_cast<size_t>(u)] != u) {
    parent[static_cast<size_t>(u)] = parent[static_cast<size_t>(parent[static_cast<size_t>(u)])];
    u = parent[static_cast<size_t>(u)];
  }
  return u;
}

/// Drops the candidates whose component (candidates joined by non-zero entries of S) has no
/// non-zero entry of S to a fixed texel: there the Dirichlet energy has no data, every constant
/// minimises it, and the texels keep their input values. Returns how many were dropped.
int64_t dropUnanchored(const SparseViewd& s, std::vector<uint8_t>& candidate) {
  const auto n = static_cast<int32_t>(candidate.size());
  std::vector<int32_t> parent(static_cast<size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<uint8_t> touchesFixed(static_cast<size_t>(n), 0);
  const int* outer = s.outerIndexPtr();
  const int* inner = s.innerIndexPtr();
  for (int32_t k = 0; k < n; ++k) {
    if (!candidate[static_cast<size_t>(k)]) continue;
    for (int e = outer[k]; e < outer[k + 1]; ++e) {
      const int32_t row = inner[e];
      if (row == k || s.valuePtr()[e] == 0.0) continue;
      if (candidate[static_cast<size_t>(row)])
        parent[static_cast<size_t>(findRoot(parent, row))] = findRoot(parent, k);
      else
        touchesFixed[static_cast<size_t>(k)] = 1;
    }
  }
  std::vector<uint8_t> anchored(static_cast<size_t>(n), 0);
  for (int32_t k = 0; k < n; ++k)
    if (candidate[static_cast<size_t>(k)] && touchesFixed[static_cast<size_t>(k)])
      anchored[static_cast<size_t>(findRoot(parent, k))] = 1;
  int64_t dropped = 0;
  for (int32_t k = 0; k < n; ++k)
    if (candidate[static_cast<size_t>(k)] && !anchored[static_cast<size_t>(findRoot(parent, k))]) {
      candidate[static_cast<size_t>(k)] = 0;
      ++dropped;
    }
  return dropped;
}

}  // namespace

SeamsResult smoothSeams(const TexelDomain& domain, Image texture, const Image& mask,
                        const SeamsOptions& options, const ProgressCallback& progress) {
  const TexelGrid& grid = domain.grid();
  const TexelOperators& ops = domain.operators();
  const SparseMatrixd& m = ops.mass();
  const SparseViewd s = ops.stiffness();
  SeamsResult result;
  std::vector<uint8_t> isFree = candidateUnknowns(domain, mask);
  result.unanchoredTexels = dropUnanchored(s, isFree);
  std::vector<int32_t> freeIndex(isFree.size(), -1);
  for (int u = 0; u < grid.unknownCount(); ++u)
    if (isFree[static_cast<size_t>(u)]) {
      freeIndex[static_cast<size_t>(u)] = static_cast<int32_t>(result.resolved.size());
      result.resolved.push_back(u);
    }
  result.freeTexels = static_cast<int64_t>(result.resolved.size());
  if (result.freeTexels == 0) {
    result.image = std::move(texture);
    return result;
  }
  Eigen::MatrixXd x = gatherTexels(grid, texture);
  const auto nf = static_cast<Eigen::Index>(result.freeTexels);
  // Minimise x^T S x + eps (x - x0)^T M (x - x0) over the free texels with the others fixed at
  // x0: (S_FF + eps M_FF) x_F = -S_FK x_K + eps M_FF x0_F.
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nf, x.cols());
  const double eps = kScreening * meanDiagonal(s) / meanDiagonal(m);
  // S is a view on M's pattern: entry e is the same (row, column) in both.
  const int* outer = m.outerIndexPtr();
  const int* inner = m.innerIndexPtr();
  for (int k = 0; k < m.outerSize(); ++k) {
    const int32_t fk = freeIndex[static_cast<size_t>(k)];
    if (fk < 0) continue;
    for (int e = outer[k]; e < outer[k + 1]; ++e) {
      const int row = inner[e];
      const int32_t fr = freeIndex[static_cast<size_t>(row)];
      if (fr >= 0) {
        entries.emplace_back(fr, fk, s.valuePtr()[e] + eps * m.valuePtr()[e]);
        rhs.row(fk) += eps * m.valuePtr()[e] * x.row(row);
      } else {
        rhs.row(fk) -= s.valuePtr()[e] * x.row(row);
      }
    }
  }
  Eigen::SparseMatrix<double> sff(nf, nf);
  sff.setFromTriplets(entries.begin(), entries.end());
  reportProgress(progress, Progress{"solve", 0.0, 0, 1});
  const Eigen::MatrixXd xf = solveDirect(sff, rhs);
  reportProgress(progress, Progress{"solve", 1.0, 1, 1});
  // The solution goes into x in place (no second n x k copy); the bound reads the input values
  // of the barely covered texels among the free ones, kept before.
  BarelyCoveredNeighbours bound;
  Eigen::MatrixXd barelyInput;
  if (!options.rawSolution) {
    std::vector<int32_t> barely = barelyCoveredUnknowns(domain);
    std::erase_if(barely, [&](int32_t u) { return !isFree[static_cast<size_t>(u)]; });
    bound = barelyCoveredNeighbours(m, std::move(barely));
    barelyInput = x(bound.unknowns, Eigen::all);
  }
  for (Eigen::Index f = 0; f < nf; ++f) x.row(result.resolved[static_cast<size_t>(f)]) = xf.row(f);
  boundBarelyCovered(bound, barelyInput, x);
  // Fixed texels are written back with their own (unchanged) float values: bit-identical. The
  // input's storage becomes the result's (no second image when the caller moves it in).
  scatterTexels(grid, x, texture);
  result.image = std::move(texture);
  return result;
}

}  // namespace texgrad
