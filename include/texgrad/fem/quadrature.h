// Exact integration rules for fem/ and operators/: symmetric triangle rules (degrees 2, 4, 6) and
// Gauss-Legendre on segments, used on the refinement T (+) T-hat (paper Sec. 5.2).
#pragma once

#include <span>
#include <utility>

namespace texgrad::fem {

/// One point of a triangle rule: barycentric coordinates (b0, b1, b2) and a weight.
struct TriangleQuadraturePoint {
  double b0, b1, b2;
  double weight;  ///< weights of a rule sum to 1: integral = area * sum(weight * f(point))
};

/// Fully symmetric rule exact for polynomials of total degree <= `degree` (1..6): 3 points up to
/// degree 2, 6 points for degree 3..4, 12 points for degree 5..6 (Dunavant 1985 orbits, polished to
/// machine precision by Gauss-Newton on the monomial moment equations at first use).
/// Throws InvalidInputError for a degree outside 1..6.
std::span<const TriangleQuadraturePoint> triangleRule(int degree);

/// Three-point Gauss-Legendre rule on [0, 1] (parameter, weight), exact up to degree 5.
std::span<const std::pair<double, double>> segmentRule();

}  // namespace texgrad::fem
