// The bound on barely covered texels: kernel coverage from the atlas; each such value clamped
// into the range of its determined mass-matrix neighbours and its own input, outwards in passes.
#include "texgrad/apps/barely_covered.h"

#include "texgrad/atlas/texel_kernel_coverage.h"
#include "texgrad/core/error.h"

namespace texgrad {

std::vector<int32_t> barelyCoveredUnknowns(const TexelDomain& domain) {
  return barelyCoveredTexels(domain.mesh(), domain.grid(), kBarelyCoveredKernel);
}

void boundBarelyCovered(const TexelDomain& domain, std::span<const int32_t> barely,
                        const Eigen::MatrixXd& input, Eigen::MatrixXd& x) {
  if (barely.empty()) return;
  const SparseMatrixd& m = domain.operators().mass();
  if (x.rows() != m.rows() || input.rows() != x.rows() || input.cols() != x.cols())
    throw InvalidInputError("boundBarelyCovered: value blocks have the wrong shape");
  // 1 while a row is still to be bounded; M is symmetric, so column u lists u's neighbours.
  std::vector<uint8_t> pending(static_cast<size_t>(x.rows()), 0);
  std::vector<int32_t> open(barely.begin(), barely.end());
  for (int32_t u : open) pending[static_cast<size_t>(u)] = 1;
  Eigen::RowVectorXd lo(x.cols()), hi(x.cols());
  while (!open.empty()) {
    std::vector<int32_t> bounded, still;
    for (int32_t u : open) {
      lo = input.row(u);
      hi = lo;
      bool seen = false;
      for (SparseMatrixd::InnerIterator it(m, u); it; ++it) {
        if (it.row() == u || it.value() <= 0.0 || pending[static_cast<size_t>(it.row())]) continue;
        lo = lo.cwiseMin(x.row(it.row()));
        hi = hi.cwiseMax(x.row(it.row()));
        seen = true;
      }
      if (seen) {
        x.row(u) = x.row(u).cwiseMax(lo).cwiseMin(hi);
        bounded.push_back(u);
      } else {
        still.push_back(u);
      }
    }
    // A pass reads only rows bounded before it, so the order of `barely` does not matter.
    for (int32_t u : bounded) pending[static_cast<size_t>(u)] = 0;
    if (bounded.empty()) {
      for (int32_t u : still) x.row(u) = input.row(u);
      return;
    }
    open.swap(still);
  }
}

}  // namespace texgrad
