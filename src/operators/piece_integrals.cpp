// Exact per-piece integrals: bilinear products are separable, x^a y^b with a, b <= 2, so nine
// polygon moments give the whole 4 x 4 mass and stiffness of a plain piece.
#include "piece_integrals.h"

namespace texgrad::detail {
namespace {

constexpr int kMassDegree = 4;       // phi_s phi_t: quadratic x quadratic (paper Sec. 5.2)
constexpr int kStiffnessDegree = 2;  // dphi_s . dphi_t: linear x linear

using Hats = std::array<std::array<double, 2>, 2>;
constexpr std::array<double, 2> kHatSlope{-1.0, 1.0};

/// Coefficients (c0, c1) of X_0 = 1 - x and X_1 = x as polynomials in xi = x - origin.
Hats hats(double origin) { return {{{1.0 - origin, -1.0}, {origin, 1.0}}}; }

std::array<double, 3> product(const Hats& hat, int i, int j) {
  return {hat[i][0] * hat[j][0], hat[i][0] * hat[j][1] + hat[i][1] * hat[j][0],
          hat[i][1] * hat[j][1]};
}

}  // namespace

Moments polygonMoments(std::span<const PieceVertex> polygon, int cellX, int cellY) {
  Moments out;
  out.ox = polygon[0].p.x() - cellX;
  out.oy = polygon[0].p.y() - cellY;
  PieceSampler::plain(polygon, cellX, cellY, kMassDegree,
                      [&](const Eigen::Vector2d& p, double w, const auto&, const auto&) {
                        const double x = p.x() - cellX - out.ox, y = p.y() - cellY - out.oy;
                        const double xs[3] = {1.0, x, x * x}, ys[3] = {1.0, y, y * y};
                        for (int a = 0; a < 3; ++a)
                          for (int b = 0; b < 3; ++b) out.m[3 * a + b] += w * xs[a] * ys[b];
                      });
  return out;
}

const Moments& unitCellMoments() {
  static const Moments m = [] {
    Moments r{};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) r.m[3 * a + b] = 1.0 / ((a + 1.0) * (b + 1.0));
    return r;
  }();
  return m;
}

BilinearIntegrals bilinearIntegrals(const Moments& moments) {
  const std::array<double, 9>& m = moments.m;
  const Hats hx = hats(moments.ox), hy = hats(moments.oy);
  BilinearIntegrals r;
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < 4; ++l) {
      const int kx = k & 1, ky = k >> 1, lx = l & 1, ly = l >> 1;
      const auto px = product(hx, kx, lx), py = product(hy, ky, ly);
      double mass = 0.0, xx = 0.0, yy = 0.0, xy = 0.0;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) mass += px[a] * py[b] * m[3 * a + b];
      for (int b = 0; b < 3; ++b) xx += py[b] * m[b];
      for (int a = 0; a < 3; ++a) yy += px[a] * m[3 * a];
      // int dx B_k dy B_l = X_kx' Y_ly' int Y_ky(y) X_lx(x).
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) xy += hx[lx][a] * hy[ky][b] * m[3 * a + b];
      r.mass(k, l) = mass;
      r.kxx(k, l) = kHatSlope[kx] * kHatSlope[lx] * xx;
      r.kyy(k, l) = kHatSlope[ky] * kHatSlope[ly] * yy;
      r.kxy(k, l) = kHatSlope[kx] * kHatSlope[ly] * xy;
    }
  const Eigen::Matrix4d xy = r.kxy;
  r.kxy = xy + xy.transpose();
  return r;
}

void quadraticIntegrals(const fem::PieceBasis& basis, LocalIntegrals& out) {
  const auto k = static_cast<Eigen::Index>(basis.texels.size());
  out.mass.setZero(k, k);
  out.kxx.setZero(k, k);
  out.kxy.setZero(k, k);
  out.kyy.setZero(k, k);
  PieceSampler::quadratic(basis, kMassDegree,
                          [&](const Eigen::Vector2d&, double w, const Eigen::VectorXd& v,
                              const Eigen::MatrixXd&) { out.mass.noalias() += w * v * v.transpose(); });
  PieceSampler::quadratic(basis, kStiffnessDegree,
                          [&](const Eigen::Vector2d&, double w, const Eigen::VectorXd&,
                              const Eigen::MatrixXd& g) {
                            out.kxx.noalias() += w * g.col(0) * g.col(0).transpose();
                            out.kyy.noalias() += w * g.col(1) * g.col(1).transpose();
                            const Eigen::MatrixXd xy = w * g.col(0) * g.col(1).transpose();
                            out.kxy += xy + xy.transpose();
                          });
}

}  // namespace texgrad::detail
