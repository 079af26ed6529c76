// The paper's comparison baseline (Sec. 4.2, Fig. 5): bilinear basis plus the soft seam energy
// E_C weighted by lambda, against the seam-continuous basis that needs no weight.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <cstdio>
#include <numeric>
#include <random>

#include "../fem/fem_fixtures.h"
#include "texgrad/core/error.h"
#include "texgrad/operators/texel_operators.h"

namespace texgrad {
namespace {

constexpr int kResolution = 64;
constexpr double kAlpha = 1e2;  ///< screening weight of the smoothing problem (short time scale)

struct Problem {
  TexturedMesh mesh = test::twoChartSquare(5);
  Atlas atlas = buildAtlas(mesh);
  TexelGrid grid = buildTexelGrid(mesh, atlas, kResolution, kResolution);
};

std::unique_ptr<TexelOperators> operators(const Problem& p, fem::BasisKind kind, double lambda) {
  OperatorOptions options;
  options.basis = kind;
  options.seamContinuityWeight = lambda;
  return std::make_unique<TexelOperators>(p.mesh, p.atlas, p.grid, options);
}

/// Random texel values: a signal with jumps across the seam, to be smoothed.
Eigen::VectorXd noise(int n) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::VectorXd x(n);
  for (auto& v : x) v = unit(rng);
  return x;
}

/// Minimiser of alpha ||f - psi||^2 + ||df||^2 (+ alpha lambda E_C), psi = sum x0_t phi_t.
Eigen::VectorXd smooth(const TexelOperators& ops, const Eigen::VectorXd& x0) {
  Eigen::SimplicialLDLT<SparseMatrixd> solver(ops.screenedSystem(kAlpha));
  EXPECT_EQ(solver.info(), Eigen::Success);
  return solver.solve(kAlpha * (ops.mass() * x0));
}

/// Number of connected components of the graph of a symmetric sparse matrix.
int components(const SparseMatrixd& a) {
  std::vector<int> parent(a.rows());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int c = 0; c < a.outerSize(); ++c)
    for (SparseMatrixd::InnerIterator it(a, c); it; ++it)
      if (it.value() != 0.0) parent[find(static_cast<int>(it.row()))] = find(c);
  int count = 0;
  for (int i = 0; i < a.rows(); ++i) count += find(i) == i;
  return count;
}

TEST(SoftSeams, EnergyIsTheIntegratedSquaredJump) {
  // x^T C x against an independent midpoint rule along the seam, with basis.evaluate on both
  // sides and surface length from the 3-D positions of the unit-area surface.
  const Problem p;
  const auto ops = operators(p, fem::BasisKind::Bilinear, 0.0);
  const fem::TexelBasis& basis = ops->basis();
  ASSERT_GT(basis.seamCount(), 0);
  double area = 0.0;
  for (const auto& t : p.mesh.triangles)
    area += 0.5 * (p.mesh.positions[t[1]] - p.mesh.positions[t[0]])
                      .cross(p.mesh.positions[t[2]] - p.mesh.positions[t[0]])
                      .norm();
  const Eigen::VectorXd x = noise(p.grid.unknownCount());
  constexpr int kSteps = 2000;
  double sampled = 0.0;
  for (int s = 0; s < basis.seamCount(); ++s) {
    const fem::SeamTrace seam = basis.seamTrace(s);
    const auto& tri = p.mesh.triangles[seam.edge[0].face];
    const double length = (p.mesh.positions[tri[(seam.edge[0].corner + 1) % 3]] -
                           p.mesh.positions[tri[seam.edge[0].corner]])
                              .norm() /
                          std::sqrt(area);
    auto at = [&](int side, double u) {
      const auto& c = basis.faceCorners(seam.edge[side].face);
      const int k = seam.edge[side].corner;
      return fem::SurfacePoint{seam.edge[side].face, c[k] + u * (c[(k + 1) % 3] - c[k])};
    };
    for (int i = 0; i < kSteps; ++i) {
      const double u = (i + 0.5) / kSteps;
      const double jump =
          basis.evaluate(at(0, u), x) - basis.evaluate(at(1, seam.sameDirection ? u : 1.0 - u), x);
      sampled += length / kSteps * jump * jump;
    }
  }
  const double energy = x.dot(ops->seamContinuity() * x);
  EXPECT_GT(sampled, 0.0);
  EXPECT_NEAR(energy, sampled, 1e-4 * sampled);
}

TEST(SoftSeams, JumpShrinksAsLambdaGrows) {
  const Problem p;
  const Eigen::VectorXd x0 = noise(p.grid.unknownCount());
  std::vector<double> energies;
  for (double lambda : {0.0, 1e-2, 1.0, 1e2, 1e4, 1e6}) {
    const auto ops = operators(p, fem::BasisKind::Bilinear, lambda);
    const Eigen::VectorXd x = smooth(*ops, x0);
    energies.push_back(x.dot(ops->seamContinuity() * x));
    std::printf("lambda %8.0e: E_C of the smoothed signal %.3e\n", lambda, energies.back());
  }
  // Penalty argument: E_C of the minimiser of F + alpha lambda E_C never grows with lambda.
  for (size_t k = 1; k < energies.size(); ++k)
    EXPECT_LE(energies[k], energies[k - 1] * (1.0 + 1e-9)) << "step " << k;
  EXPECT_LE(energies.back(), 1e-6 * energies.front());
}

TEST(SoftSeams, WithoutLambdaChartsAreUncoupled) {
  const Problem p;
  ASSERT_EQ(p.atlas.charts.size(), 2u);
  EXPECT_EQ(components(operators(p, fem::BasisKind::Bilinear, 0.0)->screenedSystem(kAlpha)), 2);
  EXPECT_EQ(components(operators(p, fem::BasisKind::Bilinear, 1.0)->screenedSystem(kAlpha)), 1);
  EXPECT_EQ(components(operators(p, fem::BasisKind::SeamContinuous, 0.0)->screenedSystem(kAlpha)),
            1);
}

TEST(SoftSeams, ConsumedOperatorsFormTheSameSystemInTheirOwnStorage) {
  const Problem p;
  for (const auto& [kind, lambda] :
       {std::pair{fem::BasisKind::Bilinear, 1.0}, std::pair{fem::BasisKind::SeamContinuous, 0.0}}) {
    auto ops = operators(p, kind, lambda);
    const SparseMatrixd kept = ops->screenedSystem(kAlpha);
    const double* massValues = ops->mass().valuePtr();
    const SparseMatrixd consumed = TexelOperators::screenedSystem(std::move(ops), kAlpha);
    ASSERT_EQ(consumed.nonZeros(), kept.nonZeros());
    EXPECT_EQ((consumed - kept).norm(), 0.0) << "lambda " << lambda;
    // Without seam screening A is M's own array: no second copy of the pattern was made.
    if (lambda == 0.0) {
      EXPECT_EQ(consumed.valuePtr(), massValues);
    }
  }
  EXPECT_THROW(TexelOperators::screenedSystem(nullptr, kAlpha), InvalidInputError);
}

TEST(SoftSeams, CombinedEntriesSeeTheirRowColumnAndBothOperators) {
  const Problem p;
  auto ops = operators(p, fem::BasisKind::SeamContinuous, 0.0);
  const SparseMatrixd mass = ops->mass();
  const SparseMatrixd stiffness = ops->stiffness();
  const EntryCombination entry = [](Eigen::Index r, Eigen::Index c, double m, double s) {
    return r == c ? m : 2.0 * s + static_cast<double>(r - c);
  };
  const SparseMatrixd kept = ops->combined(entry);
  const double* massValues = ops->mass().valuePtr();
  const SparseMatrixd consumed = TexelOperators::combined(std::move(ops), entry);
  EXPECT_EQ(consumed.valuePtr(), massValues);  // formed in M's own storage
  ASSERT_EQ(consumed.nonZeros(), mass.nonZeros());
  for (int c = 0; c < mass.outerSize(); ++c)
    for (SparseMatrixd::InnerIterator it(mass, c); it; ++it) {
      const double expected =
          it.row() == c ? it.value()
                        : 2.0 * stiffness.coeff(it.row(), c) + static_cast<double>(it.row() - c);
      ASSERT_EQ(kept.coeff(it.row(), c), expected) << it.row() << ", " << c;
      ASSERT_EQ(consumed.coeff(it.row(), c), expected) << it.row() << ", " << c;
    }
}

TEST(SoftSeams, ContinuousBasisNeedsNoLambda) {
  const Problem p;
  const auto ops = operators(p, fem::BasisKind::SeamContinuous, 0.0);
  EXPECT_EQ(ops->seamContinuity().nonZeros(), 0);
  const Eigen::VectorXd x = smooth(*ops, noise(p.grid.unknownCount()));
  std::mt19937_64 rng(3);
  double jump = 0.0;
  for (int k = 0; k < 500; ++k) {
    const auto [a, b] = ops->basis().randomSeamPair(rng);
    jump = std::max(jump, std::abs(ops->basis().evaluate(a, x) - ops->basis().evaluate(b, x)));
  }
  EXPECT_LE(jump, 1e-12 * x.cwiseAbs().maxCoeff());
  OperatorOptions wrong;
  wrong.seamContinuityWeight = 1.0;
  EXPECT_THROW(wrong.validate(), InvalidInputError);
}

// The continuous basis's C is zero: its n + 1 column starts (8 MB at 2048^2, docs/memory.md)
// are formed only when seamContinuity() is asked for, never by building the operators.
TEST(SoftSeams, ContinuousBasisHoldsNoContinuityMatrixUntilAsked) {
  const Problem p;
  const auto ops = operators(p, fem::BasisKind::SeamContinuous, 0.0);
  const int64_t built = ops->storageBytes();
  const SparseMatrixd& c = ops->seamContinuity();
  EXPECT_EQ(c.rows(), p.grid.unknownCount());
  EXPECT_EQ(c.cols(), p.grid.unknownCount());
  EXPECT_EQ(c.nonZeros(), 0);
  EXPECT_GE(ops->storageBytes() - built, int64_t(p.grid.unknownCount()) * int64_t(sizeof(int)));
}

}  // namespace
}  // namespace texgrad
