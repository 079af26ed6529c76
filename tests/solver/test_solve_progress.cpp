// Solver tests: progress and cancellation of running solves (V-cycles and conjugate gradients) on
// synthetic Poisson problems, and the ProgressCallback both callable shapes convert to.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "synthetic_problem.h"
#include "texgrad/core/progress.h"
#include "texgrad/solver/conjugate_gradient.h"
#include "texgrad/solver/multigrid_solver.h"

using namespace texgrad;

namespace {

/// One report as a callback saw it (the stage copied: the view dies with the call).
struct Seen {
  std::string stage;
  double fraction;
  int step, steps;
};

/// A callback recording every report; it asks to cancel at the report whose step is `cancelAt`.
ProgressCallback recorder(std::vector<Seen>& seen, int cancelAt = -1) {
  return [&seen, cancelAt](const Progress& p) {
    seen.push_back({std::string(p.stage), p.fraction, p.step, p.steps});
    return p.step != cancelAt;
  };
}

/// Reports of one solve: stage "solve", steps fixed, step and fraction non-decreasing, fraction
/// in [0, 1], the last report at fraction 1 with step = the iterations done.
void expectWellFormed(const std::vector<Seen>& seen, int steps, int iterations) {
  ASSERT_FALSE(seen.empty());
  for (size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i].stage, "solve") << i;
    EXPECT_EQ(seen[i].steps, steps) << i;
    EXPECT_GE(seen[i].fraction, 0.0) << i;
    EXPECT_LE(seen[i].fraction, 1.0) << i;
    if (i == 0) continue;
    EXPECT_GE(seen[i].fraction, seen[i - 1].fraction) << i;
    EXPECT_GE(seen[i].step, seen[i - 1].step) << i;
  }
  EXPECT_EQ(seen.back().fraction, 1.0);
  EXPECT_EQ(seen.back().step, iterations);
  // Polled before every iteration: one report per iteration plus the final one.
  EXPECT_EQ(static_cast<int>(seen.size()), iterations + 1);
}

TEST(SolveProgress, CallbackTakesEitherShapeAndAnEmptyFunctionStaysEmpty) {
  std::string lastStage;
  double lastFraction = -1.0;
  const ProgressCallback plain = [&](std::string_view stage, double fraction) {
    lastStage = stage;
    lastFraction = fraction;
    return fraction < 0.5;
  };
  EXPECT_NO_THROW(reportProgress(plain, Progress{"solve", 0.25, 1, 4}));
  EXPECT_EQ(lastStage, "solve");
  EXPECT_EQ(lastFraction, 0.25);
  EXPECT_THROW(reportProgress(plain, "write", 0.75), Cancelled);
  EXPECT_EQ(lastStage, "write");

  const ProgressCallback empty = std::function<bool(std::string_view, double)>();
  EXPECT_FALSE(empty);
  EXPECT_NO_THROW(reportProgress(empty, "solve", 1.0));
  EXPECT_FALSE(renameStage(empty, "heat solve"));

  std::vector<Seen> seen;
  reportProgress(renameStage(recorder(seen), "heat solve"), Progress{"solve", 0.5, 2, 4});
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].stage, "heat solve");
  EXPECT_EQ(seen[0].step, 2);
  EXPECT_EQ(seen[0].steps, 4);
}

TEST(SolveProgress, FractionFollowsCyclesOrLogResidualAndNeverFalls) {
  SolveReport report;
  report.residuals = {1.0, 1e-2};
  report.iterations = 1;
  // 1 of 10 cycles, but 2 of the 4 decades to a tolerance of 1e-4.
  EXPECT_DOUBLE_EQ(solveFraction(report, 10, 1e-4), 0.5);
  EXPECT_DOUBLE_EQ(solveFraction(report, 10, 0.0), 0.1);
  report.residuals.push_back(1e-1);  // a rising residual keeps the best one's share
  report.iterations = 2;
  EXPECT_DOUBLE_EQ(solveFraction(report, 10, 1e-4), 0.5);
  report.converged = true;
  EXPECT_EQ(solveFraction(report, 10, 1e-4), 1.0);
}

TEST(SolveProgress, MultigridReportsEveryCycleAndCancelLeavesXAndSolverReady) {
  const test::SyntheticProblem p = test::multiChartProblem(8);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 2, 4);
  MultigridSolver<double> mg;
  mg.initAndUpdate(p.grid, a);
  const SolveControl control{8, 0.0};

  std::vector<Seen> seen;
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 2);
  const SolveReport full = mg.solve(b, x, control, recorder(seen));
  expectWellFormed(seen, control.maxCycles, full.iterations);
  EXPECT_EQ(full.iterations, control.maxCycles);

  seen.clear();
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(a.rows(), 2);
  EXPECT_THROW(mg.solve(b, y, control, recorder(seen, 3)), Cancelled);
  EXPECT_EQ(seen.back().step, 3);
  EXPECT_EQ(y, Eigen::MatrixXd::Zero(a.rows(), 2)) << "a cancelled solve leaves x as given";
  const SolveReport again = mg.solve(b, y, control);
  EXPECT_EQ(again.residuals, full.residuals);
  EXPECT_EQ(y, x);
}

TEST(SolveProgress, ConjugateGradientReportsEveryIterationAndCancelsBetweenThem) {
  const test::SyntheticProblem p = test::squareProblem(40, 1.0, 1e-2);
  const Eigen::SparseMatrix<double> a = p.system(1e-2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 3, 6);
  MultigridSolver<float> mg;
  mg.initAndUpdate(p.grid, a);
  const CgOptions options{200, 1e-8};

  std::vector<Seen> seen;
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
  const SolveReport full =
      conjugateGradient(a, b, x, multigridPreconditioner(mg), options, recorder(seen));
  ASSERT_TRUE(full.converged) << full.toString();
  ASSERT_GT(full.iterations, 4);
  expectWellFormed(seen, options.maxIterations, full.iterations);
  // Stopped by the tolerance long before maxIterations, yet the bar moved along the way.
  EXPECT_GT(seen[static_cast<size_t>(full.iterations) - 1].fraction, 0.5);

  seen.clear();
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(a.rows(), 3);
  EXPECT_THROW(conjugateGradient(a, b, y, multigridPreconditioner(mg), options, recorder(seen, 2)),
               Cancelled);
  EXPECT_EQ(seen.back().step, 2);
  // The preconditioner's workspace is intact: the next solve is the uncancelled one.
  Eigen::MatrixXd z = Eigen::MatrixXd::Zero(a.rows(), 3);
  const SolveReport again = conjugateGradient(a, b, z, multigridPreconditioner(mg), options);
  EXPECT_EQ(again.residuals, full.residuals);
}

}  // namespace
