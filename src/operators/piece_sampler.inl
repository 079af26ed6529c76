// Quadrature-point iteration over pieces (included by piece_integrals.h).
#include "texgrad/fem/quadrature.h"

namespace texgrad::detail {

template <typename Visit>
void PieceSampler::plain(std::span<const PieceVertex> polygon, int cellX, int cellY,
                         int degree, Visit&& visit) {
  const auto rule = fem::triangleRule(degree);
  Eigen::Vector4d values;
  Eigen::Matrix<double, 4, 2> gradients;
  const Eigen::Vector2d origin(cellX, cellY);
  const Eigen::Vector2d p0 = polygon[0].p - origin;
  for (size_t i = 1; i + 1 < polygon.size(); ++i) {
    const Eigen::Vector2d p1 = polygon[i].p - origin, p2 = polygon[i + 1].p - origin;
    const double area = 0.5 * ((p1 - p0).x() * (p2 - p0).y() - (p1 - p0).y() * (p2 - p0).x());
    if (!(area > 0.0)) continue;
    for (const auto& q : rule) {
      const Eigen::Vector2d x = q.b0 * p0 + q.b1 * p1 + q.b2 * p2;
      const double fx = x.x(), fy = x.y();
      values << (1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy;
      gradients << -(1 - fy), -(1 - fx), (1 - fy), -fx, -fy, (1 - fx), fy, fx;
      visit(Eigen::Vector2d(x + origin), q.weight * area, values, gradients);
    }
  }
}

template <typename Visit>
void PieceSampler::quadratic(const fem::PieceBasis& basis, int degree, Visit&& visit) {
  const auto rule = fem::triangleRule(degree);
  const auto k = static_cast<Eigen::Index>(basis.texels.size());
  Eigen::VectorXd values(k);
  Eigen::MatrixXd gradients(k, 2);
  Eigen::Matrix<double, 6, 1> shape;
  Eigen::Matrix<double, 6, 2> dshape;
  for (size_t e = 0; e < basis.elements.size(); ++e) {
    const auto& t = basis.elements[e];
    Eigen::Matrix2d m;
    m.col(0) = t[1] - t[0];
    m.col(1) = t[2] - t[0];
    const double area = 0.5 * m.determinant();
    if (!(area > 0.0)) continue;
    const Eigen::Matrix2d inv = m.inverse();
    const std::array<Eigen::Vector2d, 3> g{-(inv.row(0) + inv.row(1)).transpose(),
                                           inv.row(0).transpose(), inv.row(1).transpose()};
    const auto c = basis.coefficients.middleRows(static_cast<Eigen::Index>(6 * e), 6);
    for (const auto& q : rule) {
      const Eigen::Vector3d b(q.b0, q.b1, q.b2);
      const auto s = fem::quadraticShape(b);
      for (int n = 0; n < 6; ++n) shape[n] = s[n];
      for (int i = 0; i < 3; ++i) dshape.row(i) = (4.0 * b[i] - 1.0) * g[i].transpose();
      dshape.row(3) = 4.0 * (b[1] * g[0] + b[0] * g[1]).transpose();
      dshape.row(4) = 4.0 * (b[2] * g[1] + b[1] * g[2]).transpose();
      dshape.row(5) = 4.0 * (b[0] * g[2] + b[2] * g[0]).transpose();
      values = c.transpose() * shape;
      gradients = c.transpose() * dshape;
      visit(Eigen::Vector2d(q.b0 * t[0] + q.b1 * t[1] + q.b2 * t[2]), q.weight * area, values,
            gradients);
    }
  }
}

}  // namespace texgrad::detail
