// Apps tests: SystemSolver's interactive paths (step, refine) on a synthetic multi-chart Poisson
// problem, against CHOLMOD.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "../solver/synthetic_problem.h"
#include "texgrad/apps/system_solver.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/conjugate_gradient.h"

namespace texgrad {
namespace {

double relativeResidual(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b,
                        const Eigen::MatrixXd& x) {
  return (b - a * x).norm() / b.norm();
}

/// A^-1 b by CHOLMOD.
Eigen::MatrixXd directSolution(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b) {
  CholmodSolver direct;
  direct.compute(a);
  return direct.solve(b);
}

SolverSettings floatMultigrid() {
  SolverSettings settings;
  settings.kind = SolverKind::Multigrid;
  settings.singlePrecision = true;
  return settings;
}

TEST(SystemSolver, RefineConvergesToFloatAccuracyAndReportsTheTrueResidual) {
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 2, 3);
  const Eigen::MatrixXd truth = directSolution(a, b);

  SystemSolver solver(p.grid, floatMultigrid());
  solver.initAndUpdate(a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 2);
  double previous = 1.0;
  for (int k = 0; k < 12; ++k) {
    const SolveReport report = solver.refine(b, x);
    ASSERT_EQ(report.iterations, 1);
    ASSERT_EQ(report.residuals.size(), 1u);
    const double reported = report.residuals.back(), actual = relativeResidual(a, b, x);
    EXPECT_NEAR(reported, actual, 1e-3 * actual + 1e-6) << "refine " << k;
    if (k < 4) {
      EXPECT_LT(reported, 0.5 * previous) << "refine " << k;
    }
    previous = reported;
  }
  EXPECT_LT((x - truth).norm() / truth.norm(), 1e-5);
  EXPECT_TRUE(solver.settings().singlePrecision);  // no divergence here: the cycles stay float
}

TEST(SystemSolver, CgStopsAtItsOwnIterationLimitAndItsDocumentedTolerance) {
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 2, 7);
  auto cg = [&](int cycles, int maxIterations, double tolerance) {
    SolverSettings settings;
    settings.kind = SolverKind::MultigridCg;
    settings.cycles = cycles;
    settings.maxIterations = maxIterations;
    settings.tolerance = tolerance;
    SystemSolver solver(p.grid, settings);
    solver.initAndUpdate(a);
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 2);
    return solver.solve(b, x);
  };
  // maxIterations bounds CG; cycles (V-cycles of the multigrid kind) plays no part.
  for (int cycles : {1, 50}) {
    const SolveReport capped = cg(cycles, 3, 1e-30);
    EXPECT_EQ(capped.iterations, 3) << "cycles " << cycles;
    EXPECT_FALSE(capped.converged);
  }
  // Tolerance 0 is the documented default: stop at the first residual <= 1e-8.
  const SolveReport byDefault = cg(1, 200, 0.0);
  ASSERT_TRUE(byDefault.converged);
  ASSERT_GE(byDefault.residuals.size(), 2u);
  EXPECT_LE(byDefault.residuals.back(), SolverSettings::kDefaultCgTolerance);
  EXPECT_GT(byDefault.residuals[byDefault.residuals.size() - 2],
            SolverSettings::kDefaultCgTolerance);
  EXPECT_EQ(cg(1, 200, SolverSettings::kDefaultCgTolerance).iterations, byDefault.iterations);
}

TEST(SystemSolver, FloatSolveIteratesInFloatOnlyWhereItReachesTheTolerance) {
  const test::SyntheticProblem p = test::multiChartProblem(24);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 1, 3);
  const Eigen::MatrixXd exact = directSolution(a, b);
  for (const double tolerance : {1e-4, kFloatIterateTolerance, 1e-6}) {
    SolverSettings settings;
    settings.kind = SolverKind::MultigridCg;
    settings.tolerance = tolerance;
    SystemSolver solver(p.grid, settings);
    solver.initAndUpdate(a);
    EXPECT_EQ(solver.floatIterates(), tolerance >= kFloatIterateTolerance) << tolerance;
    Eigen::MatrixXf x;  // empty: solved from zero
    const SolveReport report = solver.solve(Eigen::MatrixXf(b.cast<float>()), x);
    ASSERT_TRUE(report.converged) << report.toString();
    // b - A x in double, for the float x returned, within 1.5 times the tolerance.
    EXPECT_LT(relativeResidual(a, b, x.cast<double>()), 1.5 * tolerance) << tolerance;
    EXPECT_LT((x.cast<double>() - exact).norm() / exact.norm(), 100 * tolerance) << tolerance;
  }
  // Other kinds solve on double copies: the same iterate as the double solve, rounded.
  SystemSolver multigrid(p.grid, floatMultigrid());
  multigrid.initAndUpdate(a);
  EXPECT_FALSE(multigrid.floatIterates());
  Eigen::MatrixXd xd = Eigen::MatrixXd::Zero(a.rows(), 1);
  multigrid.solve(b, xd);
  Eigen::MatrixXf xf = Eigen::MatrixXf::Zero(a.rows(), 1);
  multigrid.solve(Eigen::MatrixXf(b.cast<float>()), xf);
  EXPECT_LT((xf.cast<double>() - xd).norm() / xd.norm(), 1e-6);
}

TEST(SystemSolver, SettingsRefuseValuesOutsideTheirRanges) {
  auto message = [](const std::function<void(SolverSettings&)>& set) {
    SolverSettings settings;
    set(settings);
    try {
      settings.validate();
    } catch (const InvalidInputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message([](SolverSettings& s) { s.maxIterations = 0; }),
            "solver maxIterations is 0; expected >= 1");
  EXPECT_NE(message([](SolverSettings& s) { s.tolerance = 1.5; }), "");
  EXPECT_NE(message([](SolverSettings& s) { s.tolerance = std::nan(""); }), "");
  EXPECT_EQ(message([](SolverSettings& s) { s.tolerance = 1.0; }), "");
  EXPECT_NE(message([](SolverSettings& s) { s.multigrid.threads = 1025; }), "");
  EXPECT_EQ(message([](SolverSettings& s) { s.multigrid.lineRatio = 0.5; }),
            "multigrid lineRatio is 0.5; expected 0 (off) or a number >= 1");
  EXPECT_THROW(parseSinglePrecision("half"), InvalidInputError);
  EXPECT_TRUE(parseSinglePrecision("float"));
  EXPECT_FALSE(parseSinglePrecision("double"));
}

/// A square stretched about 3000:1 with screening 1e-7: A is so nearly singular that float
/// rounding in the V-cycle's coarse corrections grows the residual by about 1e4 a cycle. With a
/// right-hand side and float settings of 12 cycles.
struct DivergingProblem {
  test::SyntheticProblem p = test::squareProblem(40, 1.0, 1e-7);
  Eigen::SparseMatrix<double> a = p.system(1e-7);
  Eigen::MatrixXd b = test::randomBlock(a.rows(), 1, 5);
  SolverSettings settings = [] {
    SolverSettings s = floatMultigrid();
    s.cycles = 12;
    return s;
  }();
};

TEST(SystemSolver, DivergingFloatCyclesAreUndoneAndDoubleCyclesTakeOver) {
  const DivergingProblem problem;
  const Eigen::SparseMatrix<double>& a = problem.a;
  const Eigen::MatrixXd& b = problem.b;
  const Eigen::MatrixXd truth = directSolution(a, b);
  // The solver reads its grid while constructed only: the double cycles take the float ones'
  // hierarchy, not the grid, which is gone by then.
  SystemSolver solver = [&] {
    const TexelGrid grid = problem.p.grid;
    return SystemSolver(grid, problem.settings);
  }();
  solver.initAndUpdate(a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 1);
  const SolveReport report = solver.solve(b, x);
  std::cout << report.toString();
  EXPECT_FALSE(solver.settings().singlePrecision);
  EXPECT_LE(*std::max_element(report.residuals.begin(), report.residuals.end()),
            report.residuals.front());
  // Double cycles stop near 1e-8 here (double rounding on this A); the float ones had reached
  // 1e6 by now.
  std::cout << "error against CHOLMOD " << (x - truth).norm() / truth.norm() << "\n";
  EXPECT_LT(relativeResidual(a, b, x), 1e-7);
  EXPECT_LT((x - truth).norm() / truth.norm(), 1e-4);
  // Later steps keep cycling in double.
  solver.step(b, x);
  EXPECT_FALSE(solver.settings().singlePrecision);
  EXPECT_LT(relativeResidual(a, b, x), 1e-7);
}

TEST(SystemSolver, RefineWithoutResidualReportsNoneAndResidualIsMeasuredOnDemand) {
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 2, 6);
  SystemSolver solver(p.grid, floatMultigrid());
  solver.initAndUpdate(a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 2);
  EXPECT_NEAR(solver.relativeResidual(b, x), 1.0, 1e-12);
  double previous = 1.0;
  for (int k = 0; k < 4; ++k) {
    const SolveReport report = solver.refine(b, x, false);
    EXPECT_EQ(report.iterations, 1);
    EXPECT_TRUE(report.residuals.empty());
    const double measured = solver.relativeResidual(b, x);
    EXPECT_NEAR(measured, relativeResidual(a, b, x), 1e-12 * measured);
    EXPECT_LT(measured, 0.5 * previous) << "refine " << k;
    previous = measured;
  }
  Eigen::MatrixXd wrong = Eigen::MatrixXd::Zero(a.rows() + 1, 2);
  EXPECT_THROW(solver.relativeResidual(b, wrong), InvalidInputError);
}

TEST(SystemSolver, StepAfterRefineStartsFromTheTrueResidual) {
  // refine moves x without the refinement residual that step keeps; step must not reuse it.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 1, 4);
  SystemSolver solver(p.grid, floatMultigrid());
  solver.initAndUpdate(a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 1);
  solver.step(b, x);
  solver.refine(b, x);
  const double before = relativeResidual(a, b, x);
  const SolveReport report = solver.step(b, x);
  ASSERT_EQ(report.residuals.size(), 2u);
  EXPECT_NEAR(report.residuals.front(), before, 1e-9 * before);
  EXPECT_NEAR(report.residuals.back(), relativeResidual(a, b, x), 1e-9);
}

TEST(SystemSolver, RefineWithTheDirectSolverIsExact) {
  const test::SyntheticProblem p = test::multiChartProblem(8);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 1, 5);
  SolverSettings settings;
  settings.kind = SolverKind::Direct;
  SystemSolver solver(p.grid, settings);
  solver.initAndUpdate(a);
  Eigen::MatrixXd x;
  solver.refine(b, x);
  EXPECT_LT(relativeResidual(a, b, x), 1e-10);
}

}  // namespace
TEST(SystemSolver, RvalueUpdateTakesTheMatrixOverAndConstUpdateCopiesIt) {
  const test::SyntheticProblem p = test::multiChartProblem(8);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  for (const SolverKind kind : {SolverKind::Multigrid, SolverKind::Direct}) {
    SolverSettings settings = floatMultigrid();
    settings.kind = kind;
    SystemSolver solver(p.grid, settings);
    Eigen::SparseMatrix<double> owned = a;
    const double* storage = owned.valuePtr();
    solver.initAndUpdate(std::move(owned));
    // Taken over, not copied (Eigen 3.4 would copy on a plain assignment from std::move).
    EXPECT_EQ(solver.matrix().valuePtr(), storage);
    EXPECT_EQ(owned.nonZeros(), 0);
    EXPECT_EQ((solver.matrix() - a).norm(), 0.0);

    const Eigen::SparseMatrix<double> shifted = p.system(1e3);
    solver.update(shifted);  // const: copied, the argument is untouched
    EXPECT_NE(solver.matrix().valuePtr(), shifted.valuePtr());
    EXPECT_EQ((solver.matrix() - shifted).norm(), 0.0);
    Eigen::SparseMatrix<double> next = a;
    storage = next.valuePtr();
    solver.update(std::move(next));
    EXPECT_EQ(solver.matrix().valuePtr(), storage);
    EXPECT_EQ(next.nonZeros(), 0);
  }
}

TEST(SystemSolver, RefinementOnTheLevelZeroOperatorKeepsNothingAndConvergesToItsSolution) {
  // Reaction-diffusion's shape: mass-dominated A = alpha M + S, a few cycles per solve.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 2, 7);
  const Eigen::MatrixXd truth = directSolution(a, b);

  SolverSettings settings = floatMultigrid();
  settings.cycles = 16;
  SystemSolver lean(p.grid, settings, MatrixCopy::NotForRefinement);
  SystemSolver keeping(p.grid, settings);  // WhenNeeded: keeps A for the refinement residuals
  lean.initAndUpdate(a);
  keeping.initAndUpdate(a);
  EXPECT_THROW(lean.matrix(), Error);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 2), y = x;
  const SolveReport report = lean.solve(b, x);
  keeping.solve(b, y);
  for (int k = 1; k <= 4; ++k)
    EXPECT_LT(report.residuals[k], 0.5 * report.residuals[k - 1]) << "cycle " << k;
  // The residual it tracks (updated by products rounded to float) falls on; the true one and
  // the error end near the float rounding of the level-0 operator and of its products.
  EXPECT_LT(report.residuals.back(), 1e-9) << report.toString();
  EXPECT_LT(relativeResidual(a, b, x), 1e-6);
  EXPECT_LT((x - truth).norm() / truth.norm(), 1e-6);
  EXPECT_LT((y - truth).norm() / truth.norm(), 1e-9);
  // Nothing of the first solve is carried into the next: the same solve gives the same x.
  Eigen::MatrixXd again = Eigen::MatrixXd::Zero(a.rows(), 2);
  lean.solve(b, again);
  EXPECT_EQ(again, x);
  // Neither A (12 bytes per entry) nor the refinement vectors (4 n x 2 doubles) are held.
  const int64_t withheld = a.nonZeros() * 12 + 4 * a.rows() * 2 * 8;
  EXPECT_LE(lean.storageBytes(), keeping.storageBytes() - withheld);
  std::cout << "level-0 residual " << report.residuals.back() << ", true "
            << relativeResidual(a, b, x) << ", error " << (x - truth).norm() / truth.norm()
            << " (kept A: " << (y - truth).norm() / truth.norm() << "); storage "
            << lean.storageBytes() << " against " << keeping.storageBytes() << " bytes\n";
  EXPECT_TRUE(lean.settings().singlePrecision);

  // A tolerance below what those residuals reach: the refinement keeps A, as WhenNeeded does.
  settings.tolerance = 1e-9;
  SystemSolver strict(p.grid, settings, MatrixCopy::NotForRefinement);
  strict.initAndUpdate(a);
  EXPECT_EQ((strict.matrix() - a).norm(), 0.0);
}

TEST(SystemSolver, AViewOfMAndSIsSolvedAsTheFormedSystemWithoutFormingItWhereNoCopyIsKept) {
  const test::SyntheticProblem p = test::multiChartProblem(10);
  const Eigen::MatrixXd b = test::randomBlock(p.mass.rows(), 2, 5);
  // A correction on the diagonal of every 5th unknown, read through the view's third operand.
  Eigen::SparseMatrix<double> shift(p.mass.rows(), p.mass.cols());
  for (Eigen::Index u = 0; u < shift.rows(); u += 5) shift.insert(u, u) = 40.0;
  Eigen::SparseMatrix<double> shifted = p.system(1e3);
  for (Eigen::Index u = 0; u < shift.rows(); u += 5) shifted.coeffRef(u, u) += 40.0;
  for (const MatrixCopy copy : {MatrixCopy::NotForRefinement, MatrixCopy::Kept}) {
    for (const SolverKind kind :
         {SolverKind::Multigrid, SolverKind::MultigridCg, SolverKind::Direct}) {
      SolverSettings settings = floatMultigrid();
      settings.kind = kind;
      if (kind == SolverKind::MultigridCg) settings.tolerance = 1e-6;  // CG on level 0's operator
      SystemSolver fromView(p.grid, settings, copy), fromMatrix(p.grid, settings, copy);
      fromView.initAndUpdate(SparseSum(1e2, p.mass, 1.0, p.stiffness));
      fromMatrix.initAndUpdate(p.system(1e2));
      Eigen::MatrixXd x = Eigen::MatrixXd::Zero(b.rows(), 2), y = x;
      fromView.solve(b, x);
      fromMatrix.solve(b, y);
      EXPECT_EQ(x, y) << "first set-up";
      // A numeric update from a view with a third operand, as from the formed matrix.
      fromView.update(SparseSum(1e3, p.mass, 1.0, p.stiffness, shift));
      fromMatrix.update(shifted);
      fromView.solve(b, x);
      fromMatrix.solve(b, y);
      EXPECT_EQ(x, y) << "after an update";
      // Only a multigrid that keeps no copy does not form A (and holds what the solver given the
      // formed matrix holds); the others form it from the view and keep it.
      if (copy == MatrixCopy::NotForRefinement && kind != SolverKind::Direct) {
        EXPECT_THROW(fromView.matrix(), Error);
        EXPECT_EQ(fromView.storageBytes(), fromMatrix.storageBytes());
      } else {
        EXPECT_EQ((fromView.matrix() - shifted).norm(), 0.0);
      }
    }
  }
}

TEST(SystemSolver, DivergingFloatCyclesWithoutACopyOfAThrowAndUndoTheCycle) {
  // No A to change over with.
  const DivergingProblem problem;
  const Eigen::SparseMatrix<double>& a = problem.a;
  const Eigen::MatrixXd& b = problem.b;
  SystemSolver solver(problem.p.grid, problem.settings, MatrixCopy::NotForRefinement);
  solver.initAndUpdate(a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 1);
  try {
    solver.solve(b, x);
    ADD_FAILURE() << "float cycles on this system diverge";
  } catch (const FloatCyclesDiverged& e) {
    EXPECT_NE(std::string(e.what()).find("--precision double"), std::string::npos) << e.what();
  }
  // The first cycle diverges already (see the test above): undone, x is the initial guess.
  EXPECT_TRUE(x.allFinite());
  EXPECT_LE(relativeResidual(a, b, x), 1.0 + 1e-12) << "the diverging cycle is undone";
}

TEST(SystemSolver, DivergingFloatCyclesWithoutACopyOfAChangeToDoubleCyclesOnTheSystemFormedAgain) {
  // As above, but the caller says how to form A again: the solver changes to double cycles on
  // it, as a solver with a copy does, and converges to CHOLMOD's solution.
  const DivergingProblem problem;
  const Eigen::SparseMatrix<double>& a = problem.a;
  const Eigen::MatrixXd& b = problem.b;
  SystemSolver solver(problem.p.grid, problem.settings, MatrixCopy::NotForRefinement);
  int formed = 0;
  solver.formAgainWith([&] {
    ++formed;
    return a;
  });
  solver.initAndUpdate(Eigen::SparseMatrix<double>(a));
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 1);
  const SolveReport report = solver.solve(b, x);
  EXPECT_EQ(formed, 1);
  EXPECT_FALSE(solver.settings().singlePrecision);
  EXPECT_LT(relativeResidual(a, b, x), 1e-7);
  const Eigen::MatrixXd truth = directSolution(a, b);
  EXPECT_LT((x - truth).norm() / truth.norm(), 1e-4);
  EXPECT_LE(*std::max_element(report.residuals.begin(), report.residuals.end()),
            report.residuals.front());
  EXPECT_EQ((solver.matrix() - a).norm(), 0.0) << "double cycles keep the A they run on";
}

TEST(SystemSolver, CgOnTheLevelZeroOperatorKeepsNoCopyOfAAndMatchesCgOnA) {
  // The filter's shape: screening alpha M much smaller than S per row, a smooth target.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::SparseMatrix<double> a = p.system(1.0);
  const Eigen::Index n = a.rows();
  Eigen::MatrixXd target(n, 2);
  target.col(0).setOnes();
  target.col(1) = Eigen::VectorXd::LinSpaced(n, 0.0, 1.0);
  const Eigen::MatrixXd b = p.mass * target;
  const Eigen::MatrixXd truth = directSolution(a, b);

  SolverSettings settings;
  settings.kind = SolverKind::MultigridCg;
  settings.tolerance = 1e-4;  // the filter's default
  ASSERT_TRUE(settings.cgUsesLevelZeroOperator());
  SystemSolver solver(p.grid, settings);
  solver.initAndUpdate(a);
  EXPECT_THROW(solver.matrix(), Error);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(n, 2);
  const SolveReport report = solver.solve(b, x);
  EXPECT_TRUE(report.converged) << report.toString();
  EXPECT_NEAR(solver.relativeResidual(b, x), relativeResidual(a, b, x),
              1e-3 * relativeResidual(a, b, x));
  // CG starts from the residual of its initial guess itself, not of the guess rounded to float
  // (which A amplifies: 1.5e-4 of |b| from the exact solution here, against 5e-8).
  Eigen::MatrixXd exact = truth;
  const SolveReport fromTruth = solver.solve(b, exact);
  EXPECT_LT(fromTruth.residuals.front(), 1e-6);
  EXPECT_EQ(fromTruth.iterations, 0);
  // From a smooth guess it ends within tolerance of the true residual. (The float stencils leave
  // ~2e-5 between CG's residual and the true one on this coarse grid, where the target changes
  // by a few percent per texel.)
  Eigen::MatrixXd warm = 0.9 * target;
  const SolveReport fromGuess = solver.solve(b, warm);
  EXPECT_TRUE(fromGuess.converged) << fromGuess.toString();
  EXPECT_LT(relativeResidual(a, b, warm), 2 * settings.tolerance);

  // The same CG on the double A with the same float V-cycle (what a kept A gives).
  MultigridSolver<float> mg(settings.multigrid);
  mg.initAndUpdate(p.grid, a);
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(n, 2);
  const SolveReport onA = conjugateGradient(a, b, y, multigridPreconditioner(mg), {320, 1e-4});
  EXPECT_EQ(report.iterations, onA.iterations);
  // No worse than there, up to float rounding of the solution.
  EXPECT_LE((x - truth).norm(), 1.01 * (y - truth).norm() + 1e-6 * truth.norm());

  SystemSolver keeping(p.grid, settings, MatrixCopy::Kept);
  keeping.initAndUpdate(a);
  EXPECT_EQ((keeping.matrix() - a).norm(), 0.0);
}

namespace {

/// The solves of one kind, with their progress reports copied out of the callback.
struct SolveRecord {
  std::vector<std::string> stages;
  std::vector<double> fractions;
  std::vector<int> steps;
};

ProgressCallback recordInto(SolveRecord& record, int cancelAtStep = -1) {
  return [&record, cancelAtStep](const Progress& p) {
    record.stages.emplace_back(p.stage);
    record.fractions.push_back(p.fraction);
    record.steps.push_back(p.step);
    return p.step != cancelAtStep;
  };
}

}  // namespace

TEST(SystemSolver, EveryKindReportsSetupAndSolveAndIsReusableAfterACancel) {
  const test::SyntheticProblem p = test::multiChartProblem(8);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b0 = test::randomBlock(a.rows(), 2, 5);
  const Eigen::MatrixXd b1 = test::randomBlock(a.rows(), 2, 6);
  const Eigen::MatrixXd b2 = test::randomBlock(a.rows(), 2, 7);
  struct Case {
    SolverKind kind;
    bool single;
  };
  for (const Case c : {Case{SolverKind::Multigrid, true}, Case{SolverKind::Multigrid, false},
                       Case{SolverKind::MultigridCg, true}, Case{SolverKind::Direct, false}}) {
    SCOPED_TRACE(toString(c.kind) + (c.single ? " float" : " double"));
    SolverSettings settings = floatMultigrid();
    settings.kind = c.kind;
    settings.singlePrecision = c.single;
    SystemSolver solver(p.grid, settings);
    SolveRecord setup;
    solver.initAndUpdate(a, recordInto(setup));
    ASSERT_FALSE(setup.stages.empty());
    for (const std::string& stage : setup.stages) EXPECT_EQ(stage, "solver setup");
    EXPECT_EQ(setup.fractions.front(), 0.0);
    EXPECT_EQ(setup.fractions.back(), 1.0);

    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 2);
    SolveRecord record;
    const SolveReport report = solver.solve(b0, x, recordInto(record));
    ASSERT_EQ(static_cast<int>(record.stages.size()), report.iterations + 1);
    for (size_t i = 0; i < record.stages.size(); ++i) {
      EXPECT_EQ(record.stages[i], "solve");
      EXPECT_EQ(record.steps[i], static_cast<int>(i));
      if (i > 0) {
        EXPECT_GE(record.fractions[i], record.fractions[i - 1]);
      }
    }
    EXPECT_EQ(record.fractions.back(), 1.0);

    // Cancelled at the first poll, with x the iterate of the last solve and a new b: the next
    // solve, for yet another b from that x, is the one a fresh solver computes (the residual
    // the cancelled solve formed for b1 must not be taken for that of x and b0).
    SolveRecord cancelled;
    Eigen::MatrixXd y = x;
    EXPECT_THROW(solver.solve(b1, y, recordInto(cancelled, 0)), Cancelled);
    EXPECT_EQ(cancelled.stages.size(), 1u);
    EXPECT_EQ(y, x);
    solver.solve(b2, y);
    SystemSolver fresh(p.grid, settings);
    fresh.initAndUpdate(a);
    Eigen::MatrixXd z = x;
    fresh.solve(b2, z);
    EXPECT_LE((y - z).norm(), 1e-12 * z.norm());
  }
}

}  // namespace texgrad
