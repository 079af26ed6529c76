// Memory is tested, not only benchmarked (issue 28, docs/memory.md): the operators' and the
// multigrid solver's storage per active texel on a procedural mesh stays under a bound, so a
// change that makes them hold more fails here. Each bound is the value measured when it was set
// plus 10% headroom; lower one when a change saves memory.
#include <gtest/gtest.h>

#include <Eigen/Core>

#include "texgrad/apps/filter.h"
#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/procedural.h"
#include "texgrad/solver/multigrid_solver.h"
#include "texgrad/solver/sparse_sum.h"

namespace texgrad::test {
namespace {

constexpr int kSize = 256;          ///< texture width and height
constexpr double kAlpha = 1e4;      ///< screening weight of `texgrad filter` (paper default)
constexpr int kChannels = 3;        ///< RGB
constexpr double kHeadroom = 1.10;  ///< 10% above the value measured when the bound was set
/// Bytes per active texel measured on cubeSphere() at 256² (assembled once, piece integrals
/// freed; multigrid in float after one 3-channel cycle).
constexpr double kOperatorsMeasured = 204.3;
constexpr double kMultigridMeasured = 222.1;  // with level 0's row sums (applyOperator)
/// The filter's SystemSolver (CG on the level-0 operator, no copy of A) after one solve.
constexpr double kFilterSolverMeasured = 222.1;
/// The one-shot filter's solver after its last channel's solve (level vectors for one channel).
constexpr double kOneShotSolverMeasured = 180.9;
/// alpha M + S as the one-shot filter forms it for float cycles (screenedSystemInFloat).
/// (18% of its entries are held exact too on this small mesh: its texels without a regular
/// stencil; at spot 4096², 3.6%.)
constexpr double kFloatSystemMeasured = 102.3;

TEST(StorageBound, OperatorsAndMultigridPerActiveTexelStayUnderTheirBounds) {
  const TexelDomain domain(procedural::cubeSphere(), kSize, kSize,
                           OperatorOptions::assembledOnce());
  const TexelOperators& ops = domain.operators();
  const auto n = static_cast<double>(domain.unknowns());
  MultigridSolver<float> solver;
  solver.initAndUpdate(domain.grid(), SparseSum(kAlpha, ops.mass(), 1.0, ops.stiffness()));
  const Eigen::Index rows = domain.unknowns();
  const MultigridSolver<float>::Matrix b = MultigridSolver<float>::Matrix::Ones(rows, kChannels);
  MultigridSolver<float>::Matrix x = MultigridSolver<float>::Matrix::Zero(rows, kChannels);
  solver.cycle(b, x);

  const double operatorsPerTexel = static_cast<double>(ops.storageBytes()) / n;
  const double multigridPerTexel = static_cast<double>(solver.storageBytes()) / n;
  RecordProperty("operators_bytes_per_texel", std::to_string(operatorsPerTexel));
  RecordProperty("multigrid_bytes_per_texel", std::to_string(multigridPerTexel));
  // The reports count what is surely there: M (value and row index) and S's values; the
  // level-0 vectors x, b, r of the cycle in float.
  const double matrixFloor =
      static_cast<double>(ops.mass().nonZeros()) * (2 * sizeof(double) + sizeof(int)) / n;
  const double vectorFloor = 3.0 * kChannels * sizeof(float);
  EXPECT_GE(operatorsPerTexel, matrixFloor);
  EXPECT_GE(multigridPerTexel, vectorFloor);
  EXPECT_LE(operatorsPerTexel, kOperatorsMeasured * kHeadroom);
  EXPECT_LE(multigridPerTexel, kMultigridMeasured * kHeadroom);
}

TEST(StorageBound, TheFiltersSolverKeepsNoCopyOfA) {
  const TexelDomain domain(procedural::cubeSphere(), kSize, kSize,
                           OperatorOptions::assembledOnce());
  const TexelOperators& ops = domain.operators();
  const auto n = static_cast<double>(domain.unknowns());
  const Eigen::SparseMatrix<double> a = kAlpha * ops.mass() + ops.stiffness();
  const SolverSettings settings = FilterOptions{}.solver;
  const Eigen::MatrixXd b = ops.mass() * Eigen::MatrixXd::Ones(a.rows(), kChannels);
  auto solvedOnce = [&](SystemSolver& solver) {
    solver.initAndUpdate(a);
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), kChannels);
    solver.solve(b, x);
    return static_cast<double>(solver.storageBytes());
  };
  SystemSolver solver(domain.grid(), settings);
  SystemSolver keeping(domain.grid(), settings, MatrixCopy::Kept);
  const double bytes = solvedOnce(solver), perTexel = bytes / n;
  RecordProperty("filter_solver_bytes_per_texel", std::to_string(perTexel));
  // Kept, A (values, row indices, column starts) comes on top.
  const double matrixBytes =
      static_cast<double>(a.nonZeros()) * (sizeof(double) + sizeof(int)) + (n + 1) * sizeof(int);
  EXPECT_GE(solvedOnce(keeping) - bytes, matrixBytes);
  EXPECT_LE(perTexel, kFilterSolverMeasured * kHeadroom);
}

TEST(StorageBound, TheOneShotFiltersSolverHoldsOneChannel) {
  const TexelDomain domain(procedural::cubeSphere(), kSize, kSize,
                           OperatorOptions::assembledOnce());
  const TexelOperators& ops = domain.operators();
  const auto n = static_cast<double>(domain.unknowns());
  const FilterOptions options;
  Image texture(kSize, kSize, kChannels, PixelFormat::Float);
  for (size_t k = 0; k < texture.pixels.size(); ++k)
    texture.pixels[k] = static_cast<float>(k % 7) / 7.0f;
  const double oneShot =
      static_cast<double>(filterTexture(domain, texture, options).solverStorageBytes);
  SystemSolver allChannels(domain.grid(), options.solver);
  allChannels.initAndUpdate(ops.screenedSystem(options.alpha));
  const Eigen::MatrixXd b = ops.mass() * Eigen::MatrixXd::Ones(domain.unknowns(), kChannels);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(domain.unknowns(), kChannels);
  allChannels.solve(b, x);
  RecordProperty("one_shot_solver_bytes_per_texel", std::to_string(oneShot / n));
  // Level 0's x, b and r (float) for the two channels it does not hold, at least.
  const double twoChannels = 2.0 * 3.0 * sizeof(float) * n;
  EXPECT_LE(oneShot, static_cast<double>(allChannels.storageBytes()) - twoChannels);
  EXPECT_LE(oneShot / n, kOneShotSolverMeasured * kHeadroom);
}

TEST(StorageBound, TheFloatSystemHoldsLessThanTheDoubleMatrix) {
  OperatorOptions deferred = OperatorOptions::assembledOnce();
  deferred.deferAssembly = true;
  TexelDomain domain(procedural::cubeSphere(), kSize, kSize, deferred);
  const auto n = static_cast<double>(domain.unknowns());
  const FloatSystem a =
      TexelOperators::screenedSystemInFloat(domain.releaseOperators(), kAlpha, {});
  const double perTexel = static_cast<double>(a.storageBytes()) / n;
  // In double: 12 bytes per entry (value and row index) and the column starts.
  const double doublePerTexel =
      (static_cast<double>(a.nonZeros()) * (sizeof(double) + sizeof(int)) +
       (n + 1) * sizeof(int)) / n;
  RecordProperty("float_system_bytes_per_texel", std::to_string(perTexel));
  // 8 bytes per rounded entry and 16 per exact one, against 12 each.
  EXPECT_LT(perTexel, doublePerTexel);
  EXPECT_LE(perTexel, kFloatSystemMeasured * kHeadroom);
}

}  // namespace
}  // namespace texgrad::test
