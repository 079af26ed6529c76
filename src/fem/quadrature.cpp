// Symmetric triangle quadrature: tabulated orbits (Dunavant 1985), polished so that every monomial
// x^i y^j, i + j <= degree, is integrated exactly on the reference triangle to rounding.
#include "texgrad/fem/quadrature.h"

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <vector>

#include "texgrad/core/error.h"

namespace texgrad::fem {
namespace {

constexpr int kPolishIterations = 6;
constexpr double kFiniteDifferenceStep = 1e-7;

/// Orbit parameters -> points. Layout of theta: pairs (a, w) for orbits (1-2a, a, a), then triples
/// (c1, c2, w) for six-point orbits (c1, c2, 1-c1-c2).
std::vector<TriangleQuadraturePoint> expand(const Eigen::VectorXd& theta, int threeOrbits,
                                            int sixOrbits) {
  std::vector<TriangleQuadraturePoint> points;
  for (int o = 0; o < threeOrbits; ++o) {
    const double a = theta[2 * o], w = theta[2 * o + 1], c = 1.0 - 2.0 * a;
    points.push_back({c, a, a, w});
    points.push_back({a, c, a, w});
    points.push_back({a, a, c, w});
  }
  for (int o = 0; o < sixOrbits; ++o) {
    const int k = 2 * threeOrbits + 3 * o;
    const double p = theta[k], q = theta[k + 1], r = 1.0 - p - q, w = theta[k + 2];
    for (const auto& b : std::array<std::array<double, 3>, 6>{
             {{p, q, r}, {p, r, q}, {q, p, r}, {q, r, p}, {r, p, q}, {r, q, p}}})
      points.push_back({b[0], b[1], b[2], w});
  }
  return points;
}

double factorial(int n) { return n <= 1 ? 1.0 : n * factorial(n - 1); }

/// Residuals sum(w x^i y^j) - 2 i! j! / (i + j + 2)! over all monomials up to `degree`
/// (the reference triangle has area 1/2, weights are normalised to sum 1).
Eigen::VectorXd residual(const Eigen::VectorXd& theta, int threeOrbits, int sixOrbits, int degree) {
  const auto points = expand(theta, threeOrbits, sixOrbits);
  std::vector<double> r;
  for (int i = 0; i <= degree; ++i)
    for (int j = 0; i + j <= degree; ++j) {
      double sum = 0.0;
      for (const auto& q : points) sum += q.weight * std::pow(q.b1, i) * std::pow(q.b2, j);
      r.push_back(sum - 2.0 * factorial(i) * factorial(j) / factorial(i + j + 2));
    }
  return Eigen::Map<Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()));
}

std::vector<TriangleQuadraturePoint> polished(Eigen::VectorXd theta, int threeOrbits,
                                              int sixOrbits, int degree) {
  for (int it = 0; it < kPolishIterations; ++it) {
    const Eigen::VectorXd r = residual(theta, threeOrbits, sixOrbits, degree);
    Eigen::MatrixXd jac(r.size(), theta.size());
    for (Eigen::Index k = 0; k < theta.size(); ++k) {
      Eigen::VectorXd hi = theta, lo = theta;
      hi[k] += kFiniteDifferenceStep;
      lo[k] -= kFiniteDifferenceStep;
      jac.col(k) = (residual(hi, threeOrbits, sixOrbits, degree) -
                    residual(lo, threeOrbits, sixOrbits, degree)) /
                   (2.0 * kFiniteDifferenceStep);
    }
    theta -= jac.colPivHouseholderQr().solve(r);
  }
  return expand(theta, threeOrbits, sixOrbits);
}

const std::vector<TriangleQuadraturePoint>& degree2() {
  static const std::vector<TriangleQuadraturePoint> rule = [] {
    Eigen::VectorXd theta(2);
    theta << 1.0 / 6.0, 1.0 / 3.0;
    return expand(theta, 1, 0);
  }();
  return rule;
}

const std::vector<TriangleQuadraturePoint>& degree4() {
  static const std::vector<TriangleQuadraturePoint> rule = [] {
    Eigen::VectorXd theta(4);
    theta << 0.445948490915965, 0.223381589678011, 0.091576213509771, 0.109951743655322;
    return polished(theta, 2, 0, 4);
  }();
  return rule;
}

const std::vector<TriangleQuadraturePoint>& degree6() {
  static const std::vector<TriangleQuadraturePoint> rule = [] {
    Eigen::VectorXd theta(7);
    theta << 0.249286745170910, 0.116786275726379, 0.063089014491502, 0.050844906370207,
        0.053145049844817, 0.310352451033784, 0.082851075618374;
    return polished(theta, 2, 1, 6);
  }();
  return rule;
}

}  // namespace

std::span<const TriangleQuadraturePoint> triangleRule(int degree) {
  if (degree >= 1 && degree <= 2) return degree2();
  if (degree >= 3 && degree <= 4) return degree4();
  if (degree >= 5 && degree <= 6) return degree6();
  throw InvalidInputError("triangle quadrature degree " + std::to_string(degree) +
                          " is not available (use 1..6)");
}

std::span<const std::pair<double, double>> segmentRule() {
  static const std::array<std::pair<double, double>, 3> rule = [] {
    const double h = 0.5 * std::sqrt(3.0 / 5.0);
    return std::array<std::pair<double, double>, 3>{
        {{0.5 - h, 5.0 / 18.0}, {0.5, 8.0 / 18.0}, {0.5 + h, 5.0 / 18.0}}};
  }();
  return rule;
}

}  // namespace texgrad::fem
