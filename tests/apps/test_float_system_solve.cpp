// Apps tests: A handed to the solvers as a FloatSystem (TexelOperators::screenedSystemInFloat,
// roundedSystem) on the jittered cube, whose 0.01-texel slivers give texels a tiny screening and
// blocks that are only just positive definite: every row keeps its sum through the multigrid's
// level-0 operator, the system solves as the double one does, and the solver that cannot take
// it forms it in double.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/procedural.h"
#include "texgrad/operators/texel_operators.h"
#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/multigrid_solver.h"
#include "texgrad/solver/sparse_sum.h"

namespace texgrad {
namespace {

/// Offset of the jittered cube's UVs from the lattice, in texels (slivers 0.01 texels wide).
constexpr double kSliverJitter = 0.01;

/// The jittered cube's domain at the resolution its UVs are aligned to.
const TexelDomain& sliverCube() {
  static const TexelDomain domain(procedural::alignedCube(4, kSliverJitter),
                                  procedural::kAlignedCubeResolution,
                                  procedural::kAlignedCubeResolution);
  return domain;
}

/// Each row's sum of `a` in column order (a is symmetric).
Eigen::VectorXd rowSums(const SparseMatrixd& a) {
  Eigen::VectorXd sums = Eigen::VectorXd::Zero(a.cols());
  for (int u = 0; u < a.outerSize(); ++u)
    for (int e = a.outerIndexPtr()[u]; e < a.outerIndexPtr()[u + 1]; ++e)
      sums(u) += a.valuePtr()[e];
  return sums;
}

TEST(FloatSystemSolve, TheLevelZeroOperatorKeepsEveryRowSumOfANearlySingularSystem) {
  // Screening far below the stiffness: a row's sum is ~1e-8 of its entries' magnitudes, so
  // rounding a row's entries to float without setting its diagonal from the sum would move the
  // sum by about its own size.
  const TexelDomain& domain = sliverCube();
  const TexelOperators& ops = domain.operators();
  constexpr double kAlpha = 1e-3;
  SparseMatrixd a = ops.screenedSystem(kAlpha);
  const Eigen::VectorXd sums = rowSums(a);
  const Eigen::Index n = a.rows();
  Eigen::VectorXd magnitudes(n);  // of each row's entries
  for (Eigen::Index u = 0; u < n; ++u) magnitudes(u) = a.col(u).cwiseAbs().sum();
  const std::vector<uint8_t> exact = ops.exactUnknowns();
  MultigridSolver<float> fromFloat;
  fromFloat.buildHierarchy(domain.grid());
  fromFloat.initAndUpdate(roundedSystem(ops.screenedSystem(kAlpha), exact));
  // Some boundary rows (those near weak rows) are rounded: their diagonals come from the sums.
  const auto exactCount = std::count(exact.begin(), exact.end(), uint8_t{1});
  ASSERT_GT(fromFloat.levelInfo().front().boundary, exactCount);
  const Eigen::MatrixXf ones = Eigen::MatrixXf::Ones(n, 1);
  Eigen::MatrixXf product;
  fromFloat.applyOperator(ones, product);
  // So does the FloatSystem formed in double, as a solver that keeps A takes it.
  const Eigen::VectorXd formedSums = rowSums(formedMatrix(roundedSystem(std::move(a), exact)));
  int wrong = 0, wrongFormed = 0;
  for (Eigen::Index u = 0; u < sums.size(); ++u) {
    const double allowed = 1e-5 * std::abs(sums(u)) + 1e-13 * magnitudes(u);
    wrong += !(std::abs(product(u, 0) - sums(u)) <= allowed);
    wrongFormed += !(std::abs(formedSums(u) - sums(u)) <= allowed);
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(wrongFormed, 0);
}

TEST(FloatSystemSolve, SolvesTheSliverCubeAsTheDoubleSystemDoes) {
  // The filter's system and solver: CG around float V-cycles on the level-0 operator. The
  // slivers' boundary blocks are only just positive definite: rounding their entries breaks that.
  const TexelDomain& domain = sliverCube();
  const TexelOperators& ops = domain.operators();
  constexpr double kAlpha = 1e4;
  const SparseMatrixd a = ops.screenedSystem(kAlpha);
  Eigen::MatrixXd target(a.rows(), 2);
  target.col(0).setOnes();
  target.col(1) = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 1.0);
  const Eigen::MatrixXd b = kAlpha * (ops.mass() * target);
  CholmodSolver direct;
  direct.compute(a);
  const Eigen::MatrixXd truth = direct.solve(b);
  SolverSettings settings;  // float cycles
  settings.kind = SolverKind::MultigridCg;
  settings.tolerance = 1e-4;  // the filter's default
  ASSERT_TRUE(SystemSolver::takesFloatSystem(settings));
  SystemSolver fromFloat(domain.grid(), settings), fromDouble(domain.grid(), settings);
  ASSERT_TRUE(fromFloat.takesFloatSystem());
  fromFloat.initAndUpdate(roundedSystem(ops.screenedSystem(kAlpha), ops.exactUnknowns()));
  fromDouble.initAndUpdate(ops.screenedSystem(kAlpha));
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 2), y = x;
  EXPECT_TRUE(fromFloat.solve(b, x).converged);
  EXPECT_TRUE(fromDouble.solve(b, y).converged);
  EXPECT_LE((b - a * x).norm() / b.norm(), 2 * settings.tolerance);
  EXPECT_LE((x - truth).norm(), 1.5 * (y - truth).norm() + 1e-6 * truth.norm());

  // A solver that keeps A (the direct one) forms the FloatSystem in double: its exact entries,
  // its rounded diagonals from the row sums.
  SolverSettings exactSettings = settings;
  exactSettings.kind = SolverKind::Direct;
  ASSERT_FALSE(SystemSolver::takesFloatSystem(exactSettings));
  SystemSolver keeping(domain.grid(), exactSettings);
  keeping.initAndUpdate(roundedSystem(ops.screenedSystem(kAlpha), ops.exactUnknowns()));
  const Eigen::VectorXd keptSums = rowSums(keeping.matrix());
  const Eigen::VectorXd sums = rowSums(a);
  EXPECT_LE((keptSums - sums).cwiseAbs().maxCoeff(), 1e-6 * sums.cwiseAbs().maxCoeff());
  Eigen::MatrixXd z = Eigen::MatrixXd::Zero(a.rows(), 2);
  keeping.solve(b, z);
  EXPECT_LE((z - truth).norm(), 1e-4 * truth.norm());
}

}  // namespace
}  // namespace texgrad
