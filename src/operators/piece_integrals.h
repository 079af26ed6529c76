// Metric-independent integrals of one piece T ∩ cell: polygon moments for exactly bilinear pieces,
// quadratic-element integrals for seam pieces (private to operators/).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <array>
#include <span>

#include "texgrad/atlas/cell_clipping.h"
#include "texgrad/fem/texel_basis.h"

namespace texgrad::detail {

/// m[3a + b] = int (x - ox)^a (y - oy)^b over the polygon, in cell-local coordinates (cell
/// corner at 0). The origin (ox, oy) is a point of the piece, so that bilinear products of tiny
/// pieces far from a texel do not cancel catastrophically (their integrals stay >= 0).
struct Moments {
  std::array<double, 9> m{};
  double ox = 0.0, oy = 0.0;
};

/// Local matrices on k texels (k x k, column-major): mass int phi_s phi_t and the three stiffness
/// parts int dx phi_s dx phi_t, int (dx phi_s dy phi_t + dy phi_s dx phi_t), int dy phi_s dy phi_t.
struct LocalIntegrals {
  Eigen::MatrixXd mass, kxx, kxy, kyy;
};

/// Fixed 4 x 4 version for bilinear pieces (texel order (a,b), (a+1,b), (a,b+1), (a+1,b+1)).
struct BilinearIntegrals {
  Eigen::Matrix4d mass, kxx, kxy, kyy;
};

/// Exact moments of a polygon (degree-4 quadrature on a fan from its first vertex).
Moments polygonMoments(std::span<const PieceVertex> polygon, int cellX, int cellY);
/// Moments of the whole unit cell.
const Moments& unitCellMoments();
/// Bilinear-basis integrals over a piece with the given moments (exact).
BilinearIntegrals bilinearIntegrals(const Moments& m);
/// Integrals of the quadratic elements of a seam piece (degree 4 for mass, 2 for stiffness).
void quadraticIntegrals(const fem::PieceBasis& basis, LocalIntegrals& out);

/// Values and gradients of the local texel functions at points of a piece, for quadrature.
struct PieceSampler {
  /// Calls visit(point, weight * area, values, gradients) at each quadrature point of every
  /// element; values has one entry per local texel, gradients is k x 2.
  template <typename Visit>
  static void plain(std::span<const PieceVertex> polygon, int cellX, int cellY, int degree,
                    Visit&& visit);
  template <typename Visit>
  static void quadratic(const fem::PieceBasis& basis, int degree, Visit&& visit);
};

}  // namespace texgrad::detail

#include "piece_sampler.inl"
