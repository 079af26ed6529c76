// Soft seam-continuity energy E_C of the bilinear baseline (paper Sec. 4.2, after Liu et al.
// 2017): E_C(x) = int over seams of (f_side0 - f_side1)^2 dl_h = x^T C x.
#include <algorithm>
#include <cmath>

#include "texel_operators_impl.h"
#include "texgrad/fem/quadrature.h"

namespace texgrad {
namespace {

/// Surface length of face edge e under the face's metric g: sqrt(d^T g d), d in texel units.
double metricLength(const fem::TexelBasis& basis, const std::vector<Eigen::Matrix2d>& metric,
                    const FaceEdge& e) {
  const auto& c = basis.faceCorners(e.face);
  const Eigen::Vector2d d = c[(e.corner + 1) % 3] - c[e.corner];
  return std::sqrt(d.dot(metric[e.face] * d));
}

/// Point at parameter u along face edge e (grid coordinates).
Eigen::Vector2d edgePoint(const fem::TexelBasis& basis, const FaceEdge& e, double u) {
  const auto& c = basis.faceCorners(e.face);
  return c[e.corner] + u * (c[(e.corner + 1) % 3] - c[e.corner]);
}

/// Adds length * int_0^1 j(u) j(u)^T du of one seam to the triplets, j = B(side0) - B(side1):
/// between breaks both sides stay in one cell, so j is quadratic in u and the 3-point
/// Gauss-Legendre rule (exact to degree 5) integrates j j^T exactly.
void addSeam(const fem::TexelBasis& basis, const fem::SeamTrace& seam, double length,
             std::vector<Eigen::Triplet<double>>& out) {
  std::vector<fem::TexelWeight> jump;
  for (size_t k = 0; k + 1 < seam.breaks.size(); ++k) {
    const double u0 = seam.breaks[k], u1 = seam.breaks[k + 1];
    if (!(u1 > u0)) continue;
    for (const auto& [t, w] : fem::segmentRule()) {
      const double u = u0 + t * (u1 - u0);
      jump.clear();
      basis.bilinearWeights(edgePoint(basis, seam.edge[0], u), jump);
      basis.bilinearWeights(edgePoint(basis, seam.edge[1], seam.sameDirection ? u : 1.0 - u), jump,
                            -1.0);
      fem::mergeWeights(jump);
      const double weight = length * w * (u1 - u0);
      for (const auto& a : jump)
        for (const auto& b : jump)
          out.emplace_back(a.unknown, b.unknown, weight * a.weight * b.weight);
    }
  }
}

}  // namespace

void TexelOperators::Impl::buildSeamContinuity() {
  // The seam-continuous basis has no jumps: C = 0 is formed only when asked for
  // (continuityMatrix), as even an empty n x n matrix holds n + 1 column starts.
  if (options.basis != fem::BasisKind::Bilinear) return;
  const int n = basis.grid().unknownCount();
  seamContinuity.resize(n, n);
  seamContinuity.setZero();
  std::vector<Eigen::Triplet<double>> triplets;
  for (int s = 0; s < basis.seamCount(); ++s) {
    const fem::SeamTrace trace = basis.seamTrace(s);
    const double length = 0.5 * (metricLength(basis, metric, trace.edge[0]) +
                                 metricLength(basis, metric, trace.edge[1]));
    addSeam(basis, trace, length, triplets);
  }
  seamContinuity.setFromTriplets(triplets.begin(), triplets.end());
}

const SparseMatrixd& TexelOperators::Impl::continuityMatrix() const {
  if (options.basis == fem::BasisKind::Bilinear) return seamContinuity;
  std::call_once(zeroContinuityFormed, [&] {
    const int n = basis.grid().unknownCount();
    zeroContinuity.resize(n, n);
  });
  return zeroContinuity;
}

}  // namespace texgrad
