// Exact per-piece integrals: bilinear products are separable, x^a y^b with a, b <= 2, so nine
// polygon moments give the whole 4 x 4 mass and stiffness of a plain piece.
#include "piece_integrals.h"

namespace texgrad::detail {
namespace {

constexpr int kMassDegree = 4;       // phi_s phi_t: quadratic x quadratic (paper Sec. 5.2)
constexpr int kStiffnessDegree = 2;  // dphi_s . dphi_t: linear x linear

/// Coefficients (c0, c1) of X_0 = 1 - x and X_1 = x (same for Y).
constexpr std::array<std::array<double, 2>, 2> kHat{{{1.0, -1.0}, {0.0, 1.0}}};
constexpr std::array<double, 2> kHatSlope{-1.0, 1.0};

std::array<double, 3> product(int i, int j) {
  return {kHat[i][0] * kHat[j][0], kHat[i][0] * kHat[j][1] + kHat[i][1] * kHat[j][0],
          kHat[i][1] * kHat[j][1]};
}

}  // namespace

Moments polygonMoments(std::span<const PieceVertex> polygon, int cellX, int cellY) {
  Moments m{};
  PieceSampler::plain(polygon, cellX, cellY, kMassDegree,
                      [&](const Eigen::Vector2d& p, double w, const auto&, const auto&) {
                        const double x = p.x() - cellX, y = p.y() - cellY;
                        const double xs[3] = {1.0, x, x * x}, ys[3] = {1.0, y, y * y};
                        for (int a = 0; a < 3; ++a)
                          for (int b = 0; b < 3; ++b) m[3 * a + b] += w * xs[a] * ys[b];
                      });
  return m;
}

const Moments& unitCellMoments() {
  static const Moments m = [] {
    Moments r{};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) r[3 * a + b] = 1.0 / ((a + 1.0) * (b + 1.0));
    return r;
  }();
  return m;
}

BilinearIntegrals bilinearIntegrals(const Moments& m) {
  BilinearIntegrals r;
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < 4; ++l) {
      const int kx = k & 1, ky = k >> 1, lx = l & 1, ly = l >> 1;
      const auto px = product(kx, lx), py = product(ky, ly);
      double mass = 0.0, xx = 0.0, yy = 0.0, xy = 0.0;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) mass += px[a] * py[b] * m[3 * a + b];
      for (int b = 0; b < 3; ++b) xx += py[b] * m[b];
      for (int a = 0; a < 3; ++a) yy += px[a] * m[3 * a];
      // int dx B_k dy B_l = X_kx' Y_ly' int Y_ky(y) X_lx(x).
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) xy += kHat[lx][a] * kHat[ky][b] * m[3 * a + b];
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
