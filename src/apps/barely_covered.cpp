// The bound on barely covered texels: kernel coverage from the atlas; each such value clamped
// into the range of its determined mass-matrix neighbours and its own input, outwards in passes.
#include "texgrad/apps/barely_covered.h"

#include "texgrad/atlas/texel_kernel_coverage.h"
#include "texgrad/core/error.h"

namespace texgrad {

std::vector<int32_t> barelyCoveredUnknowns(const TexelDomain& domain) {
  return barelyCoveredTexels(domain.mesh(), domain.grid(), kBarelyCoveredKernel);
}

BarelyCoveredNeighbours barelyCoveredNeighbours(const SparseMatrixd& mass,
                                                std::vector<int32_t> barely) {
  BarelyCoveredNeighbours bound;
  bound.start.reserve(barely.size() + 1);
  bound.start.push_back(0);
  // M is symmetric, so column u lists u's neighbours.
  for (int32_t u : barely) {
    if (u < 0 || u >= mass.cols())
      throw InvalidInputError("barelyCoveredNeighbours: unknown " + std::to_string(u) +
                              " is not in the domain");
    for (SparseMatrixd::InnerIterator it(mass, u); it; ++it)
      if (it.row() != u && it.value() > 0.0)
        bound.neighbours.push_back(static_cast<int32_t>(it.row()));
    bound.start.push_back(static_cast<int64_t>(bound.neighbours.size()));
  }
  bound.unknowns = std::move(barely);
  return bound;
}

void boundBarelyCovered(const TexelDomain& domain, std::span<const int32_t> barely,
                        const Eigen::MatrixXd& input, Eigen::MatrixXd& x) {
  if (barely.empty()) return;
  if (x.rows() != domain.unknowns() || input.rows() != x.rows() || input.cols() != x.cols())
    throw InvalidInputError("boundBarelyCovered: value blocks have the wrong shape");
  const BarelyCoveredNeighbours bound = barelyCoveredNeighbours(
      domain.operators().mass(), std::vector<int32_t>(barely.begin(), barely.end()));
  boundBarelyCovered(bound, input(bound.unknowns, Eigen::all), x);
}

void boundBarelyCovered(const BarelyCoveredNeighbours& bound, const Eigen::MatrixXd& input,
                        Eigen::MatrixXd& x) {
  const auto count = static_cast<Eigen::Index>(bound.unknowns.size());
  if (count == 0) return;
  if (input.rows() != count || input.cols() != x.cols() ||
      bound.start.size() != bound.unknowns.size() + 1)
    throw InvalidInputError("boundBarelyCovered: value blocks have the wrong shape");
  // 1 while a row is still to be bounded.
  std::vector<uint8_t> pending(static_cast<size_t>(x.rows()), 0);
  for (int32_t u : bound.unknowns) {
    if (u < 0 || u >= x.rows())
      throw InvalidInputError("boundBarelyCovered: unknown " + std::to_string(u) +
                              " is not a row of the values");
    pending[static_cast<size_t>(u)] = 1;
  }
  for (int32_t v : bound.neighbours)
    if (v < 0 || v >= x.rows())
      throw InvalidInputError("boundBarelyCovered: neighbour " + std::to_string(v) +
                              " is not a row of the values");
  // Positions in bound.unknowns still open.
  std::vector<int32_t> open(bound.unknowns.size());
  for (size_t i = 0; i < open.size(); ++i) open[i] = static_cast<int32_t>(i);
  Eigen::RowVectorXd lo(x.cols()), hi(x.cols());
  while (!open.empty()) {
    std::vector<int32_t> bounded, still;
    for (int32_t i : open) {
      const int32_t u = bound.unknowns[static_cast<size_t>(i)];
      lo = input.row(i);
      hi = lo;
      bool seen = false;
      for (int64_t k = bound.start[static_cast<size_t>(i)];
           k < bound.start[static_cast<size_t>(i) + 1]; ++k) {
        const int32_t v = bound.neighbours[static_cast<size_t>(k)];
        if (pending[static_cast<size_t>(v)]) continue;
        lo = lo.cwiseMin(x.row(v));
        hi = hi.cwiseMax(x.row(v));
        seen = true;
      }
      if (seen) {
        x.row(u) = x.row(u).cwiseMax(lo).cwiseMin(hi);
        bounded.push_back(i);
      } else {
        still.push_back(i);
      }
    }
    // A pass reads only rows bounded before it, so the order of the unknowns does not matter.
    for (int32_t i : bounded)
      pending[static_cast<size_t>(bound.unknowns[static_cast<size_t>(i)])] = 0;
    if (bounded.empty()) {
      for (int32_t i : still) x.row(bound.unknowns[static_cast<size_t>(i)]) = input.row(i);
      return;
    }
    open.swap(still);
  }
}

}  // namespace texgrad
