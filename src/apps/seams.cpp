// Seam smoothing: a Dirichlet problem on the free texels (harmonic interpolation in the
// seam-continuous space, paper §4), solved with CHOLMOD on the free block.
#include "texgrad/apps/seams.h"

#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/cholmod_solver.h"

namespace texgrad {
namespace {

std::vector<int32_t> freeIndexOfUnknowns(const TexelGrid& grid, const Image& mask,
                                         int64_t& count) {
  std::vector<int32_t> freeIndex(static_cast<size_t>(grid.unknownCount()), -1);
  Eigen::VectorXd maskValues;
  if (!mask.empty()) {
    if (mask.width != grid.imageWidth || mask.height != grid.imageHeight)
      throw InvalidInputError("the seam mask is " + std::to_string(mask.width) + "x" +
                              std::to_string(mask.height) + " but the texture is " +
                              std::to_string(grid.imageWidth) + "x" +
                              std::to_string(grid.imageHeight));
    maskValues = gatherTexels(grid, mask).col(0);
  }
  count = 0;
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const bool isFree = mask.empty()
                            ? grid.texelClass[grid.texelOfUnknown[u]] == TexelClass::Boundary
                            : maskValues[u] > 0.5;
    if (isFree) freeIndex[u] = static_cast<int32_t>(count++);
  }
  return freeIndex;
}

}  // namespace

SeamsResult smoothSeams(const TexelDomain& domain, const Image& texture, const Image& mask) {
  const TexelGrid& grid = domain.grid();
  const TexelOperators& ops = domain.operators();
  SeamsResult result;
  const std::vector<int32_t> freeIndex = freeIndexOfUnknowns(grid, mask, result.freeTexels);
  result.image = texture;
  if (result.freeTexels == 0) return result;
  const Eigen::MatrixXd x = gatherTexels(grid, texture);
  const auto nf = static_cast<Eigen::Index>(result.freeTexels);
  // S_FF (+ a tiny mass term so islands of free texels with no fixed neighbour stay solvable),
  // and the right-hand side -S_FK x_K.
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nf, x.cols());
  const SparseMatrixd& m = ops.mass();
  const SparseViewd s = ops.stiffness();
  const double tiny = 1e-9 * meanDiagonal(s) / meanDiagonal(m);
  // S is a view on M's pattern: entry e is the same (row, column) in both.
  const int* outer = m.outerIndexPtr();
  const int* inner = m.innerIndexPtr();
  for (int k = 0; k < m.outerSize(); ++k) {
    const int32_t fk = freeIndex[k];
    if (fk < 0) continue;
    for (int e = outer[k]; e < outer[k + 1]; ++e) {
      const int row = inner[e];
      const int32_t fr = freeIndex[row];
      if (fr >= 0)
        entries.emplace_back(fr, fk, s.valuePtr()[e] + tiny * m.valuePtr()[e]);
      else
        rhs.row(fk) -= s.valuePtr()[e] * x.row(row);
    }
  }
  Eigen::SparseMatrix<double> sff(nf, nf);
  sff.setFromTriplets(entries.begin(), entries.end());
  const Eigen::MatrixXd xf = solveDirect(sff, rhs);
  Eigen::MatrixXd solved = x;
  for (int u = 0; u < grid.unknownCount(); ++u)
    if (freeIndex[u] >= 0) solved.row(u) = xf.row(freeIndex[u]);
  // Fixed texels are written back with their own (unchanged) float values: bit-identical.
  scatterTexels(grid, solved, result.image);
  return result;
}

}  // namespace texgrad
