// Solver tests: multigrid V-cycle (paper §6.2, Fig. 8) on synthetic Poisson problems, no mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <cstdio>
#include <memory>
#include <sstream>
#include <vector>

#include "synthetic_problem.h"
#include "texgrad/core/error.h"
#include "texgrad/core/float_system.h"
#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/multigrid_solver.h"

using namespace texgrad;

namespace {

template <typename T>
SolveReport runCycles(const test::SyntheticProblem& p, double alpha, int cycles, int k = 3,
                      MultigridOptions options = {}) {
  MultigridSolver<T> mg(options);
  const Eigen::SparseMatrix<double> a = p.system(alpha);
  mg.init(p.grid, a);
  mg.update(a);
  const Eigen::MatrixXd b = a * test::randomBlock(a.rows(), k);
  typename MultigridSolver<T>::Matrix x = MultigridSolver<T>::Matrix::Zero(a.rows(), k);
  return mg.solve(b.cast<T>(), x, {cycles, 0.0});
}

}  // namespace

TEST(Multigrid, ConvergenceFactorIndependentOfGridSize) {
  // Poisson-like (alpha small): the factor per V-cycle stays within 2x over 64^2 .. 512^2.
  // Screened (alpha = 1e4, unit-area mass): alpha h^2 shrinks with n, so the problem tends to the
  // Poisson one from the easy side; its factor is bounded by the Poisson factor at every size.
  std::vector<double> poisson, screened;
  for (int n : {64, 128, 256, 512}) {
    const test::SyntheticProblem p = test::squareProblem(n);
    for (double alpha : {1e-2, 1e4}) {
      const SolveReport r = runCycles<double>(p, alpha, 6);
      (alpha < 1.0 ? poisson : screened).push_back(r.convergenceFactor(4));
      std::printf("alpha %g n %d factor per cycle %.4f\n", alpha, n, r.convergenceFactor(4));
      EXPECT_LT(r.convergenceFactor(4), 0.2) << "n = " << n << ", alpha = " << alpha << "\n"
                                             << r.toString();
    }
    EXPECT_LE(screened.back(), 1.2 * poisson.back()) << "n = " << n;
  }
  const auto [lo, hi] = std::minmax_element(poisson.begin(), poisson.end());
  EXPECT_LE(*hi, 2.0 * *lo);
}

TEST(Multigrid, DoubleConvergesToCholmodSolution) {
  const test::SyntheticProblem p = test::multiChartProblem(24);
  for (double alpha : {1e-1, 1e2, 1e4}) {
    const Eigen::SparseMatrix<double> a = p.system(alpha);
    const Eigen::MatrixXd b = test::randomBlock(a.rows(), 3, 7);
    const Eigen::MatrixXd exact = solveDirect(a, b);
    MultigridSolver<double> mg;
    mg.init(p.grid, a);
    mg.update(a);
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
    const SolveReport r = mg.solve(b, x, {40, 1e-12});
    EXPECT_TRUE(r.converged) << r.toString();
    EXPECT_LT((x - exact).norm() / exact.norm(), 1e-10) << "alpha " << alpha << "\n"
                                                        << r.toString();
    for (size_t i = 2; i < r.residuals.size(); ++i)  // geometric decrease, cycle after cycle
      EXPECT_LT(r.residuals[i], 0.5 * r.residuals[i - 1]) << "cycle " << i << "\n" << r.toString();
  }
}

TEST(Multigrid, FloatReachesSinglePrecisionAccuracy) {
  const test::SyntheticProblem p = test::multiChartProblem(24);
  const Eigen::SparseMatrix<double> a = p.system(1e4);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 3, 3);
  const Eigen::MatrixXd exact = solveDirect(a, b);
  MultigridSolver<float> mg;
  mg.init(p.grid, a);
  mg.update(a);
  Eigen::MatrixXf x = Eigen::MatrixXf::Zero(a.rows(), 3);
  const SolveReport r = mg.solve(b.cast<float>(), x, {12, 0.0});
  EXPECT_LT((x.cast<double>() - exact).norm() / exact.norm(), 1e-5) << r.toString();
}

TEST(Multigrid, InitAndUpdateEqualsInitThenUpdate) {
  // One chain of Galerkin products for both phases gives bit-identical cycles, and an update
  // with a new alpha afterwards still needs no new symbolic analysis. (The values given to init
  // guide the interior/boundary split, so both start from the same matrix.)
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::SparseMatrix<double> a = p.system(1e3);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 2, 5);
  MultigridSolver<double> separate, fused;
  separate.init(p.grid, a);
  separate.update(a);
  fused.initAndUpdate(p.grid, a);
  EXPECT_EQ(fused.stats().inits, 1);
  EXPECT_EQ(fused.stats().updates, 1);
  EXPECT_EQ(fused.stats().symbolicAnalyses, separate.stats().symbolicAnalyses);
  Eigen::MatrixXd x1 = Eigen::MatrixXd::Zero(a.rows(), 2), x2 = x1;
  for (int k = 0; k < 3; ++k) {
    separate.cycle(b, x1);
    fused.cycle(b, x2);
  }
  EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0);
  const int analyses = fused.stats().symbolicAnalyses;
  fused.update(p.system(1e4));
  EXPECT_EQ(fused.stats().symbolicAnalyses, analyses);
}

TEST(Multigrid, SetUpFromMAndSEqualsSetUpFromTheFormedSystem) {
  // alpha M + S read from M and S (SparseSum, never formed) gives bit-identical cycles, on a
  // multi-level hierarchy and on one solved directly, and a new alpha only updates.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::MatrixXd b = test::randomBlock(p.mass.rows(), 2, 7);
  for (int minCoarse : {16, 100000}) {
    MultigridOptions o;
    o.minCoarseUnknowns = minCoarse;
    MultigridSolver<double> formed(o), summed(o);
    formed.initAndUpdate(p.grid, p.system(1e3));
    summed.initAndUpdate(p.grid, SparseSum(1e3, p.mass, 1.0, p.stiffness));
    EXPECT_EQ(summed.hierarchy().levelCount(), formed.hierarchy().levelCount());
    EXPECT_EQ(summed.hierarchy().levelCount() == 1, minCoarse > 16);
    const int analyses = summed.stats().symbolicAnalyses;
    for (double alpha : {1e3, 1e1}) {
      if (alpha != 1e3) {
        formed.update(p.system(alpha));
        summed.update(SparseSum(alpha, p.mass, 1.0, p.stiffness));
      }
      Eigen::MatrixXd x1 = Eigen::MatrixXd::Zero(b.rows(), 2), x2 = x1;
      for (int k = 0; k < 2; ++k) {
        formed.cycle(b, x1);
        summed.cycle(b, x2);
      }
      EXPECT_GT(x1.norm(), 0.0);
      EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0) << "alpha " << alpha;
    }
    EXPECT_EQ(summed.stats().symbolicAnalyses, analyses);
    EXPECT_EQ(summed.stats().updates, 2);
  }
}

namespace {

/// Bytes of a compressed matrix with `rows` columns and `nonZeros` entries (values, row indices
/// and column starts), as the solver counts its set-up matrices.
int64_t sparseBytes(int64_t rows, int64_t nonZeros) {
  return nonZeros * int64_t(sizeof(double) + sizeof(int)) + (rows + 1) * int64_t(sizeof(int));
}

}  // namespace

TEST(Multigrid, HandedOverMatrixReleasedWhileLevelZeroIsFilledGivesTheSameCycles) {
  // Large enough for several bands of level 0's stencils (assignStencils) and whole pages of
  // A^0's arrays: the handed-over A^0's pages are dropped band by band, and a later read of one
  // would see zeros instead of the values the viewed matrix gives.
  const test::SyntheticProblem p = test::multiChartProblem(80);
  const Eigen::MatrixXd b = test::randomBlock(p.mass.rows(), 2, 5);
  MultigridSolver<float> viewed, handed;
  const Eigen::SparseMatrix<double> a = p.system(0.01);
  Eigen::SparseMatrix<double> given = a;
  viewed.initAndUpdate(p.grid, a);
  handed.initAndUpdate(p.grid, std::move(given));
  ASSERT_GE(handed.levelInfo().size(), 2u);
  MultigridSolver<float>::Matrix x1 = MultigridSolver<float>::Matrix::Zero(b.rows(), 2), x2 = x1;
  for (int k = 0; k < 2; ++k) {
    viewed.cycle(b.cast<float>(), x1);
    handed.cycle(b.cast<float>(), x2);
  }
  EXPECT_GT(x1.norm(), 0.0f);
  EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0f);
}

TEST(Multigrid, HandedOverMatrixGivesTheSameCyclesAndIsFreedWithLevelZero) {
  // A handed over (a&&) is taken from the caller and gives bit-identical cycles to a view of
  // the caller's A, for initAndUpdate and update alike. While each level l > 0's data are built
  // the set-up holds exactly A^l and A^{l+1}, no A^{l-1} (each is freed as soon as the next
  // level's operator and its own data exist); with level 0's data it holds A^0 (only when
  // handed over) and then A^1, formed from those data once A^0 is freed: never both.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::MatrixXd b = test::randomBlock(p.mass.rows(), 3, 9);
  MultigridOptions o;
  o.minCoarseUnknowns = 16;
  MultigridSolver<float> viewed(o), handed(o);
  for (double alpha : {1e3, 1e1}) {
    const Eigen::SparseMatrix<double> a = p.system(alpha);
    Eigen::SparseMatrix<double> given = a;
    if (alpha == 1e3) {
      viewed.initAndUpdate(p.grid, a);
      handed.initAndUpdate(p.grid, std::move(given));
    } else {
      viewed.update(a);
      handed.update(std::move(given));
    }
    EXPECT_EQ(given.rows(), 0);
    EXPECT_EQ(given.nonZeros(), 0);
    MultigridSolver<float>::Matrix x1 = MultigridSolver<float>::Matrix::Zero(b.rows(), 3), x2 = x1;
    for (int k = 0; k < 2; ++k) {
      viewed.cycle(b.cast<float>(), x1);
      handed.cycle(b.cast<float>(), x2);
    }
    EXPECT_GT(x1.norm(), 0.0f);
    EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0f) << "alpha " << alpha;

    const std::vector<MultigridLevelInfo> info = handed.levelInfo(), seen = viewed.levelInfo();
    ASSERT_GE(info.size(), 3u);  // A^1 is dropped after a level that also held one
    const int64_t a0 = sparseBytes(a.rows(), a.nonZeros());
    for (size_t l = 0; l < info.size(); ++l) {
      const bool last = l + 1 == info.size();
      const int64_t own = l == 0 ? 0 : sparseBytes(info[l].unknowns, info[l].nonZeros);
      const int64_t next = last ? 0 : sparseBytes(info[l + 1].unknowns, info[l + 1].nonZeros);
      EXPECT_EQ(seen[l].setUpMatrixBytes, own + next) << "level " << l;
      EXPECT_EQ(info[l].setUpMatrixBytes, l == 0 ? std::max(a0, next) : own + next)
          << "level " << l;
    }
  }
}

/// `a` (symmetric, compressed) as a FloatSystem whose entries are all exact (exact = 1) or all
/// rounded, with its row sums.
FloatSystem floatSystemOf(const Eigen::SparseMatrix<double>& a, uint8_t exact) {
  auto pattern = std::make_shared<Eigen::SparseMatrix<double>>(a);
  const auto n = static_cast<int>(a.rows());
  FloatSystem f(n, pattern->outerIndexPtr(), pattern->innerIndexPtr(),
                std::vector<uint8_t>(static_cast<size_t>(n), exact));
  for (int u = 0; u < n; ++u) {
    double sum = 0.0;
    for (int e = a.outerIndexPtr()[u]; e < a.outerIndexPtr()[u + 1]; ++e) {
      f.set(e, a.valuePtr()[e]);
      sum += a.valuePtr()[e];
    }
    f.setRowSum(u, sum);
  }
  f.keepPatternAlive(pattern);
  return f;
}

TEST(Multigrid, AnEmptyFloatSystemIsAnEmptyMatrix) {
  EXPECT_EQ(SparseSum(FloatSystem()).nonZeros(), 0);
  EXPECT_EQ(formedMatrix(FloatSystem()).rows(), 0);
}

TEST(Multigrid, AFloatSystemHandedOverGivesTheCyclesOfItsEntries) {
  // All entries exact: the same cycles and level-0 operator as the double A handed over, bit
  // for bit, with one level or several, for initAndUpdate and update; the system is taken over
  // and every level's unknownOfSlot is freed after the set-up. All rounded: the interior
  // stencils and row sums are the same, so the cycles stay close.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::MatrixXd b = test::randomBlock(p.mass.rows(), 2, 7);
  using Matrix = MultigridSolver<float>::Matrix;
  for (const int minCoarse : {16, static_cast<int>(p.mass.rows()) + 1}) {
    MultigridOptions o;
    o.minCoarseUnknowns = minCoarse;
    MultigridSolver<float> fromDouble(o), fromFloat(o), rounded(o);
    for (double alpha : {1e3, 1e1}) {
      const Eigen::SparseMatrix<double> a = p.system(alpha);
      Eigen::SparseMatrix<double> given = a;
      FloatSystem exact = floatSystemOf(a, 1), inexact = floatSystemOf(a, 0);
      if (alpha == 1e3) {
        fromDouble.initAndUpdate(p.grid, std::move(given));
        fromFloat.buildHierarchy(p.grid);
        fromFloat.initAndUpdate(std::move(exact));
        rounded.buildHierarchy(p.grid);
        rounded.initAndUpdate(std::move(inexact));
      } else {
        fromDouble.update(std::move(given));
        fromFloat.update(std::move(exact));
        rounded.update(std::move(inexact));
      }
      EXPECT_EQ(exact.rows(), 0);
      EXPECT_EQ(exact.nonZeros(), 0);
      Matrix x1 = Matrix::Zero(b.rows(), 2), x2 = x1, x3 = x1;
      for (int k = 0; k < 2; ++k) {
        fromDouble.cycle(b.cast<float>(), x1);
        fromFloat.cycle(b.cast<float>(), x2);
        rounded.cycle(b.cast<float>(), x3);
      }
      EXPECT_GT(x1.norm(), 0.0f);
      EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0f) << "alpha " << alpha;
      EXPECT_LT((x1 - x3).norm(), 1e-5f * x1.norm()) << "alpha " << alpha;
      Matrix y1, y2, y3;
      fromDouble.applyOperator(x1, y1);
      fromFloat.applyOperator(x1, y2);
      rounded.applyOperator(x1, y3);
      EXPECT_EQ((y1 - y2).cwiseAbs().maxCoeff(), 0.0f) << "alpha " << alpha;
      // Rounded, the interior rows (stencils and row sums) give the same products.
      int differing = 0;
      for (Eigen::Index u = 0; u < y1.rows(); ++u) differing += y1.row(u) != y3.row(u);
      EXPECT_LE(differing, rounded.levelInfo().front().boundary) << "alpha " << alpha;
      for (int l = 0; l < fromFloat.hierarchy().levelCount(); ++l)
        EXPECT_TRUE(fromFloat.hierarchy().level(l).unknownOfSlot.empty()) << "level " << l;
    }
  }
}

TEST(Multigrid, HandedOverMatrixOfAOneLevelHierarchyIsFactorisedThenFreed) {
  // With a single level the direct factorisation reads the handed-over A^0 before it is freed:
  // the same cycles (an exact solve) and the same level-0 operator as with a view.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::MatrixXd b = test::randomBlock(p.mass.rows(), 2, 11);
  MultigridOptions o;
  o.minCoarseUnknowns = static_cast<int>(p.mass.rows()) + 1;  // nothing to coarsen
  MultigridSolver<float> viewed(o), handed(o);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  Eigen::SparseMatrix<double> given = a;
  viewed.initAndUpdate(p.grid, a);
  handed.initAndUpdate(p.grid, std::move(given));
  EXPECT_EQ(given.nonZeros(), 0);
  ASSERT_EQ(handed.levelInfo().size(), 1u);
  MultigridSolver<float>::Matrix x1 = MultigridSolver<float>::Matrix::Zero(b.rows(), 2), x2 = x1;
  viewed.cycle(b.cast<float>(), x1);
  handed.cycle(b.cast<float>(), x2);
  EXPECT_GT(x1.norm(), 0.0f);
  EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0f);
  MultigridSolver<float>::Matrix y1, y2;
  viewed.applyOperator(x1, y1);
  handed.applyOperator(x1, y2);
  EXPECT_EQ((y1 - y2).cwiseAbs().maxCoeff(), 0.0f);
}

TEST(Multigrid, ChangingAlphaOnlyUpdates) {
  const test::SyntheticProblem p = test::multiChartProblem(12);
  MultigridSolver<float> mg;
  mg.init(p.grid, p.system(1.0));
  const int analyses = mg.stats().symbolicAnalyses;
  EXPECT_GT(analyses, 1);  // boundary blocks and the coarsest level
  for (double alpha : {1.0, 1e2, 1e4}) {
    mg.update(p.system(alpha));
    Eigen::MatrixXf x = Eigen::MatrixXf::Zero(p.mass.rows(), 1);
    const Eigen::MatrixXd b = test::randomBlock(p.mass.rows(), 1);
    const SolveReport r = mg.solve(b.cast<float>(), x, {20, 1e-5});
    EXPECT_TRUE(r.converged) << r.toString();
  }
  EXPECT_EQ(mg.stats().symbolicAnalyses, analyses);
  EXPECT_EQ(mg.stats().inits, 1);
  EXPECT_EQ(mg.stats().updates, 3);
  EXPECT_EQ(mg.stats().numericFactorizations, 3 * analyses);
}

TEST(Multigrid, ResultIndependentOfThreadCount) {
  const test::SyntheticProblem p = test::multiChartProblem(16);
  for (bool useFloat : {true, false}) {
    Eigen::MatrixXd results[2];
    for (int threads : {1, 2}) {
      MultigridOptions o;
      o.threads = threads;
      const SolveReport r =
          useFloat ? runCycles<float>(p, 1e3, 3, 3, o) : runCycles<double>(p, 1e3, 3, 3, o);
      results[threads - 1] =
          Eigen::Map<const Eigen::VectorXd>(r.residuals.data(), Eigen::Index(r.residuals.size()));
    }
    EXPECT_EQ(results[0], results[1]);  // bitwise: residual norms use a fixed reduction tree
  }
}

TEST(Multigrid, SolutionBitwiseIndependentOfThreadCount) {
  const test::SyntheticProblem p = test::multiChartProblem(16);
  const Eigen::SparseMatrix<double> a = p.system(1e3);
  const Eigen::MatrixXf b = test::randomBlock(a.rows(), 3).cast<float>();
  Eigen::MatrixXf x[2];
  for (int threads : {1, 2}) {
    MultigridOptions o;
    o.threads = threads;
    MultigridSolver<float> mg(o);
    mg.init(p.grid, a);
    mg.update(a);
    x[threads - 1] = Eigen::MatrixXf::Zero(a.rows(), 3);
    mg.solve(b, x[threads - 1], {3, 0.0});
  }
  EXPECT_EQ(x[0], x[1]);
}

TEST(Multigrid, ManyChannelsMatchOneAtATime) {
  const test::SyntheticProblem p = test::multiChartProblem(8);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 6);
  MultigridSolver<double> mg;
  mg.init(p.grid, a);
  mg.update(a);
  Eigen::MatrixXd all = Eigen::MatrixXd::Zero(a.rows(), 6);
  mg.solve(b, all, {2, 0.0});
  for (int c = 0; c < 6; ++c) {
    Eigen::MatrixXd one = Eigen::MatrixXd::Zero(a.rows(), 1);
    mg.solve(b.col(c), one, {2, 0.0});
    EXPECT_LT((one.col(0) - all.col(c)).norm(), 1e-12 * all.col(c).norm());
  }
}

TEST(Multigrid, RefineIsOneCycleAndReportsTheTrueResidual) {
  // refine(b, x) on double blocks does what cycle does, and its residual (fused into the last
  // sweeps) is ||b - A x|| / ||b|| of the new x as a sparse product computes it.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 3, 7);
  MultigridSolver<double> mg;
  mg.initAndUpdate(p.grid, a);
  Eigen::MatrixXd viaCycle = Eigen::MatrixXd::Zero(a.rows(), 3), viaRefine = viaCycle;
  double previous = 1.0;
  for (int k = 0; k < 4; ++k) {
    mg.cycle(b, viaCycle);
    const double reported = mg.refine(b, viaRefine);
    EXPECT_EQ((viaCycle - viaRefine).cwiseAbs().maxCoeff(), 0.0);
    const double truth = (b - a * viaRefine).norm() / b.norm();
    EXPECT_NEAR(reported, truth, 1e-9 * truth);
    EXPECT_LT(reported, 0.5 * previous);
    previous = reported;
  }
  // Float cycles: the same residual up to float rounding.
  MultigridSolver<float> single;
  single.initAndUpdate(p.grid, a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
  for (int k = 0; k < 3; ++k) {
    const double reported = single.refine(b, x);
    const double truth = (b - a * x).norm() / b.norm();
    EXPECT_NEAR(reported, truth, 1e-3 * truth + 1e-6);
  }
  Eigen::MatrixXd wrong = Eigen::MatrixXd::Zero(a.rows() + 1, 3);
  EXPECT_THROW(single.refine(b, wrong), InvalidInputError);
}

TEST(Multigrid, RefineWithoutResidualMovesXTheSameWay) {
  // Skipping the residual must not change the cycle: x bit for bit, and NaN for the residual.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 2, 8);
  MultigridSolver<float> mg;
  mg.initAndUpdate(p.grid, a);
  Eigen::MatrixXd measured = Eigen::MatrixXd::Zero(a.rows(), 2), unmeasured = measured;
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(std::isfinite(mg.refine(b, measured)));
    EXPECT_TRUE(std::isnan(mg.refine(b, unmeasured, false)));
    EXPECT_EQ((measured - unmeasured).cwiseAbs().maxCoeff(), 0.0) << "refine " << k;
  }
  EXPECT_LT((b - a * unmeasured).norm() / b.norm(), 1e-2);
}

TEST(Multigrid, SummaryListsLevels) {
  const test::SyntheticProblem p = test::multiChartProblem(16);
  MultigridSolver<float> mg;
  mg.init(p.grid, p.system(1.0));
  std::ostringstream os;
  os << mg;
  const std::string s = os.str();
  std::printf("%s", s.c_str());
  EXPECT_NE(s.find("level"), std::string::npos);
  EXPECT_NE(s.find("direct"), std::string::npos);
  EXPECT_EQ(std::count(s.begin(), s.end(), '\n'), 2 + mg.hierarchy().levelCount()) << s;
}

TEST(Multigrid, RejectsMisuse) {
  const test::SyntheticProblem p = test::squareProblem(16);
  const test::SyntheticProblem q = test::squareProblem(17);
  MultigridOptions bad;
  bad.sweeps = 0;
  EXPECT_THROW(MultigridSolver<float>{bad}, InvalidInputError);
  MultigridSolver<double> mg;
  EXPECT_THROW(mg.update(p.system(1.0)), InvalidInputError);
  mg.init(p.grid, p.system(1.0));
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(p.mass.rows(), 1);
  EXPECT_THROW(mg.solve(x, x, {1, 0.0}), InvalidInputError);  // before update
  EXPECT_THROW(mg.update(q.system(1.0)), InvalidInputError);  // other pattern
  EXPECT_THROW(mg.init(p.grid, q.system(1.0)), InvalidInputError);
}

TEST(Multigrid, CoarsestOnlyProblemIsSolvedDirectly) {
  const test::SyntheticProblem p = test::squareProblem(4);
  MultigridOptions o;
  o.minCoarseUnknowns = 1000;
  MultigridSolver<double> mg(o);
  const Eigen::SparseMatrix<double> a = p.system(1.0);
  mg.init(p.grid, a);
  mg.update(a);
  EXPECT_EQ(mg.hierarchy().levelCount(), 1);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 2);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 2);
  const SolveReport r = mg.solve(b, x, {1, 0.0});
  EXPECT_LT(r.residuals.back(), 1e-12);
  // refine after solve (whose residual left values in the workspace) reports the new residual.
  x.setZero();
  mg.solve(b, x, {0, 0.0});
  EXPECT_LT(mg.refine(b, x), 1e-12);
  EXPECT_LT((b - a * x).norm(), 1e-12 * b.norm());
}

TEST(Multigrid, LinesRelaxTexelsCoupledMostlyAlongOneAxis) {
  // A band of cells diffusing 100 times more strongly along one axis (part of a chart that its
  // parameterisation stretches): point Gauss–Seidel barely smooths errors that vary across
  // that axis, and a line cut off from the boundary texels it ends on leaves the error that is
  // smooth along the whole row. Both axes, since x and y lines are separate code paths.
  for (const bool alongY : {false, true}) {
    const test::SyntheticProblem p = test::stretchedBandProblem(96, 100.0, alongY);
    MultigridOptions pointOnly;
    pointOnly.lineRatio = 0.0;
    const SolveReport lines = runCycles<double>(p, 1e-2, 10, 2);
    const SolveReport points = runCycles<double>(p, 1e-2, 10, 2, pointOnly);
    std::printf("stretched along %s: factor %.3f with lines, %.3f without\n", alongY ? "y" : "x",
                lines.convergenceFactor(4), points.convergenceFactor(4));
    EXPECT_LT(lines.convergenceFactor(4), 0.3) << lines.toString();
    EXPECT_GT(points.convergenceFactor(4), 0.6) << points.toString();
  }
}

TEST(Multigrid, DoubleLinesSolveNearlySingularLineBlocksWhole) {
  // A square stretched ~30000:1 with screening 1e-9: every line's block is a 1-D Neumann
  // Laplacian plus ~1e-9, whose last Thomas pivot is 2.5e-7 of its diagonal. Float lines are
  // cut there (the solve would lose every float digit); double lines keep the whole block (1e-9
  // of rounding) and the cycle converges. Cutting them too stalled it at a residual of 6e-9.
  const test::SyntheticProblem p = test::squareProblem(40, 1.0, 1e-9);
  const SolveReport r = runCycles<double>(p, 1e-9, 12, 1);
  std::printf("nearly singular lines: residual %.3g after 12 cycles, factor %.3f\n",
              r.residuals.back(), r.convergenceFactor(4));
  EXPECT_LT(r.residuals.back(), 1e-11) << r.toString();
}

TEST(Multigrid, LineRelaxationKeepsTheCycleSymmetric) {
  // CG needs a symmetric preconditioner: <V(r), s> = <r, V(s)> with lines in both directions.
  const test::SyntheticProblem p = test::squareProblem(40, 1.0, 1e-2);
  const test::SyntheticProblem q = test::squareProblem(40, 1e-2, 1.0);
  for (const test::SyntheticProblem* problem : {&p, &q}) {
    const Eigen::SparseMatrix<double> a = problem->system(1e-2);
    MultigridSolver<double> mg;
    mg.initAndUpdate(problem->grid, a);
    ASSERT_GT(mg.levelInfo().front().lineTexels, 0);
    const Eigen::MatrixXd r = test::randomBlock(a.rows(), 1, 3), s = test::randomBlock(a.rows(), 1, 4);
    Eigen::MatrixXd vr, vs;
    mg.precondition(r, vr);
    mg.precondition(s, vs);
    const double left = vr.col(0).dot(s.col(0)), right = r.col(0).dot(vs.col(0));
    EXPECT_NEAR(left, right, 1e-10 * std::abs(left));
  }
}

TEST(Multigrid, TexelsNearAWeakBoundaryRowAreSolvedWithTheBoundary) {
  // A boundary texel with a tiny diagonal and large mixed-sign couplings (what a texel barely
  // covered by sliver triangles gets): c g gᵀ with g = eps e_u + e_v - e_w keeps A SPD.
  test::SyntheticProblem p = test::squareProblem(32);
  const TexelGrid& g = p.grid;
  auto unknownAt = [&](int x, int y) {
    return g.unknownOfTexel[static_cast<size_t>(g.texelIndex(x, y))];
  };
  const int u = unknownAt(0, 16), v = unknownAt(1, 16), w = unknownAt(1, 17);
  ASSERT_TRUE(u >= 0 && v >= 0 && w >= 0);
  const double c = 4000.0, eps = 1e-3;
  std::vector<Eigen::Triplet<double>> t;
  const std::array<std::pair<int, double>, 3> gv = {{{u, eps}, {v, 1.0}, {w, -1.0}}};
  for (const auto& [i, gi] : gv)
    for (const auto& [j, gj] : gv) t.emplace_back(i, j, c * gi * gj);
  Eigen::SparseMatrix<double> extra(p.stiffness.rows(), p.stiffness.cols());
  extra.setFromTriplets(t.begin(), t.end());
  p.stiffness += extra;
  const Eigen::SparseMatrix<double> a = p.system(1.0);
  ASSERT_LT(a.coeff(u, u), 0.25 * (std::abs(a.coeff(u, v)) + std::abs(a.coeff(u, w))));

  auto levelZero = [&](int reach) {
    MultigridOptions o;
    o.weakRowReach = reach;
    MultigridSolver<double> mg(o);
    mg.initAndUpdate(p.grid, a);
    return mg.levelInfo().front();
  };
  const MultigridLevelInfo paper = levelZero(0), locked = levelZero(2);
  EXPECT_EQ(paper.unknowns, locked.unknowns);
  // Some interior texels of the 5 x 5 window around u moved to the boundary, and no others.
  EXPECT_GT(locked.boundary, paper.boundary);
  EXPECT_LE(locked.boundary, paper.boundary + 25);
  EXPECT_EQ(locked.interior + locked.boundary, paper.interior + paper.boundary);
  // Without a weak row the reach changes nothing.
  const test::SyntheticProblem plain = test::squareProblem(32);
  MultigridSolver<double> mg;
  mg.initAndUpdate(plain.grid, plain.system(1.0));
  MultigridOptions off;
  off.weakRowReach = 0;
  MultigridSolver<double> paperSplit(off);
  paperSplit.initAndUpdate(plain.grid, plain.system(1.0));
  EXPECT_EQ(mg.levelInfo().front().boundary, paperSplit.levelInfo().front().boundary);

  // Still the solution of A x = b.
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 1, 9);
  const Eigen::MatrixXd exact = solveDirect(a, b);
  MultigridSolver<double> solver;
  solver.initAndUpdate(p.grid, a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 1);
  solver.solve(b, x, {40, 1e-13});
  EXPECT_LT((x - exact).norm() / exact.norm(), 1e-9);
}
