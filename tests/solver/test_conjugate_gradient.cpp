// Solver tests: conjugate gradients with and without the multigrid preconditioner.
#include <gtest/gtest.h>

#include <Eigen/IterativeLinearSolvers>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "synthetic_problem.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/conjugate_gradient.h"

using namespace texgrad;

TEST(ConjugateGradient, MultigridPreconditionerHandlesStrongAnisotropy) {
  // Diffusion tensor diag(1, 1e-3) (metric distortion of LIC) and screening epsilon = 1e-3.
  const test::SyntheticProblem p = test::squareProblem(128, 1.0, 1e-3);
  const Eigen::SparseMatrix<double> a = p.system(1e-3);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 3, 5);
  MultigridSolver<double> mg;
  mg.init(p.grid, a);
  mg.update(a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
  const SolveReport pcg = conjugateGradient(a, b, x, multigridPreconditioner(mg), {500, 1e-6});
  EXPECT_TRUE(pcg.converged) << pcg.toString();
  EXPECT_LT((a * x - b).norm() / b.norm(), 1.1e-6);
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(a.rows(), 3);
  const SolveReport plain = conjugateGradient(a, b, y, {}, {2000, 1e-6});
  std::printf("anisotropic 129^2: MG-PCG %d iterations, CG %d iterations (converged %d)\n",
              pcg.iterations, plain.iterations, int(plain.converged));
  EXPECT_LT(pcg.iterations * 10, plain.iterations)
      << "MG-PCG " << pcg.iterations << ", CG " << plain.iterations;
  const Eigen::MatrixXd exact = solveDirect(a, b);
  EXPECT_LT((x - exact).norm() / exact.norm(), 1e-3);
}

TEST(ConjugateGradient, FloatMultigridPreconditionerAlsoConverges) {
  const test::SyntheticProblem p = test::squareProblem(64, 1.0, 1e-3);
  const Eigen::SparseMatrix<double> a = p.system(1e-3);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 1, 2);
  MultigridSolver<float> mg;
  mg.init(p.grid, a);
  mg.update(a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 1);
  const SolveReport r = conjugateGradient(a, b, x, multigridPreconditioner(mg), {300, 1e-6});
  EXPECT_TRUE(r.converged) << r.toString();
}

TEST(ConjugateGradient, MultigridWorksAsEigenPreconditioner) {
  const test::SyntheticProblem p = test::squareProblem(48, 1.0, 1e-2);
  const Eigen::SparseMatrix<double> a = p.system(1.0);
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper,
                           MultigridSolver<double>> cg;
  cg.preconditioner().init(p.grid, a);
  cg.setTolerance(1e-8);
  cg.compute(a);
  const Eigen::VectorXd b = test::randomBlock(a.rows(), 1);
  const Eigen::VectorXd x = cg.solve(b);
  EXPECT_EQ(cg.info(), Eigen::Success);
  EXPECT_LT(cg.iterations(), 30);
  EXPECT_LT((a * x - b).norm() / b.norm(), 1e-7);
}

namespace {

/// Diagonal n x n matrix with the given entries (both triangles trivially stored).
Eigen::SparseMatrix<double> diagonal(const Eigen::VectorXd& d) {
  Eigen::SparseMatrix<double> a(d.size(), d.size());
  for (Eigen::Index i = 0; i < d.size(); ++i) a.insert(i, i) = d(i);
  a.makeCompressed();
  return a;
}

/// The message of the NumericalError `solve` throws ("" if it throws none).
template <typename F>
std::string numericalErrorOf(F&& solve) {
  try {
    solve();
  } catch (const NumericalError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ConjugateGradient, IndefiniteMatrixIsANumericalErrorNotASilentZeroStep) {
  // Half the diagonal negative: p^T A p < 0 on the first direction (b = 1).
  Eigen::VectorXd d = Eigen::VectorXd::Ones(8);
  d.tail(4).setConstant(-3.0);
  const Eigen::SparseMatrix<double> a = diagonal(d);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Ones(8, 2);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(8, 2);
  const std::string message = numericalErrorOf([&] {
    conjugateGradient(a, b, x, {}, {50, 1e-10});
  });
  EXPECT_NE(message.find("not positive definite at iteration 1, column 0"), std::string::npos)
      << message;
  // A Poisson system shifted past its smallest eigenvalues: indefinite, found within the solve.
  const test::SyntheticProblem p = test::squareProblem(16);
  const Eigen::SparseMatrix<double> shifted = p.system(-0.05);
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(shifted.rows(), 1);
  const std::string found = numericalErrorOf([&] {
    conjugateGradient(shifted, test::randomBlock(shifted.rows(), 1, 3), y, {}, {500, 1e-12});
  });
  EXPECT_NE(found.find("not positive definite"), std::string::npos) << found;
}

TEST(ConjugateGradient, NanInTheRightHandSideOrFromThePreconditionerIsANumericalError) {
  const test::SyntheticProblem p = test::squareProblem(16);
  const Eigen::SparseMatrix<double> a = p.system(1.0);
  Eigen::MatrixXd b = test::randomBlock(a.rows(), 2, 4);
  b(5, 1) = std::numeric_limits<double>::quiet_NaN();
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 2);
  const std::string message = numericalErrorOf([&] { conjugateGradient(a, b, x, {}, {}); });
  EXPECT_NE(message.find("right-hand side holds nan at row 5, column 1"), std::string::npos)
      << message;
  // A preconditioner that turns to NaN at its third application.
  b(5, 1) = 0.5;
  int calls = 0;
  const Preconditioner poisoned = [&calls](const Eigen::MatrixXd& r, Eigen::MatrixXd& z) {
    z = r;
    if (++calls == 3) z(0, 0) = std::numeric_limits<double>::quiet_NaN();
  };
  x.setZero();
  const std::string arose = numericalErrorOf([&] {
    conjugateGradient(a, b, x, poisoned, {100, 1e-12});
  });
  EXPECT_NE(arose.find("a NaN or infinity arose at iteration 2"), std::string::npos) << arose;
}

TEST(ConjugateGradient, ResidualBlowUpStopsAsDivergedWithTheBestIterate) {
  // diag(1, -1) with b = (1, 1 - 1e-6): p^T A p = 2e-6 > 0 passes the curvature check, but the
  // step 1 / 2e-6 multiplies the residual by about 7e5 (indefinite A, not caught by a sign).
  const Eigen::SparseMatrix<double> a = diagonal(Eigen::Vector2d(1.0, -1.0));
  const Eigen::MatrixXd b = Eigen::Vector2d(1.0, 1.0 - 1e-6);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(2, 1);
  const SolveReport report = conjugateGradient(a, b, x, {}, {20, 1e-10});
  EXPECT_TRUE(report.diverged) << report.toString();
  EXPECT_FALSE(report.converged);
  EXPECT_EQ(report.iterations, 1);
  EXPECT_GT(report.residuals.back(), kCgDivergenceGrowth * report.residuals.front());
  EXPECT_EQ(x, Eigen::MatrixXd::Zero(2, 1)) << "the best iterate: the initial guess";
  EXPECT_NE(report.toString().find("(diverged)"), std::string::npos);
  // From a nonzero guess the best iterate, copied only once the residual rose, is that guess.
  const Eigen::Vector2d guess(0.25, -0.25);  // r = (0.75, 0.75 - 1e-6): the same blow-up
  Eigen::MatrixXd y = guess;
  const SolveReport fromGuess = conjugateGradient(a, b, y, {}, {20, 1e-10});
  ASSERT_TRUE(fromGuess.diverged) << fromGuess.toString();
  EXPECT_EQ(y, Eigen::MatrixXd(guess)) << y.transpose();
}

TEST(ConjugateGradient, FloatLevelZeroOperatorKeepsTheSmallRowSumsOfAScreenedSystem) {
  // alpha M + S with alpha M's row sums about 1/2600 of the diagonal, as the filter's system at
  // 2048²: a float stencil summed as is would miss them by ~1e-7 of the diagonal (~3e-4 of A 1).
  const test::SyntheticProblem p = test::squareProblem(64);
  const Eigen::SparseMatrix<double> a = p.system(10.0);
  MultigridSolver<float> mg;
  mg.initAndUpdate(p.grid, a);
  const Eigen::Index n = a.rows();
  Eigen::MatrixXf x(n, 3);
  x.col(0).setOnes();                                    // A 1: the row sums alone
  x.col(1) = Eigen::VectorXf::LinSpaced(n, 1.0f, 2.0f);  // smooth along the unknown order
  x.col(2) = test::randomBlock(n, 1, 9).cast<float>();   // every frequency
  Eigen::MatrixXf y;
  mg.applyOperator(x, y);
  const Eigen::MatrixXd exact = a * x.cast<double>();
  for (Eigen::Index c = 0; c < 3; ++c)
    EXPECT_LT((y.col(c).cast<double>() - exact.col(c)).norm() / exact.col(c).norm(), 1e-6)
        << "column " << c;
  // CG on it stops after as many iterations as on the double A, at the same accuracy.
  const Eigen::MatrixXd b = p.mass * Eigen::MatrixXd::Ones(n, 1) * 10.0;
  const CgOptions options{100, 1e-6};
  Eigen::MatrixXd onA = Eigen::MatrixXd::Zero(n, 1), onStencils = onA;
  const SolveReport reference = conjugateGradient(a, b, onA, multigridPreconditioner(mg), options);
  const SolveReport report = conjugateGradient(multigridOperator(mg), b, onStencils, options);
  EXPECT_TRUE(report.converged) << report.toString();
  EXPECT_EQ(report.iterations, reference.iterations);
  EXPECT_LT((a * onStencils - b).norm() / b.norm(), 2e-6);
}

TEST(ConjugateGradient, FloatIteratesReachTheirToleranceInTheTrueResidual) {
  // The filter's kind of system (alpha M + S, alpha M small next to S) and a strongly
  // anisotropic one: CG with float iterate and residual, from zero and from a rough guess,
  // stops where its residual says the true one, b - A x in double, is at the tolerance, after
  // about as many iterations as with double iterates.
  struct Case {
    test::SyntheticProblem problem;
    double screening;
  };
  const Case cases[] = {{test::squareProblem(128), 10.0},
                        {test::squareProblem(128, 1.0, 1e-3), 1e-3}};
  for (const Case& c : cases) {
    const Eigen::SparseMatrix<double> a = c.problem.system(c.screening);
    MultigridSolver<float> mg;
    mg.initAndUpdate(c.problem.grid, a);
    const Eigen::Index n = a.rows();
    const Eigen::MatrixXd b = a * test::randomBlock(n, 1, 4);
    const CgOptions options{300, kFloatIterateTolerance};
    for (const bool fromZero : {true, false}) {
      const Eigen::MatrixXd start =
          fromZero ? Eigen::MatrixXd::Zero(n, 1) : Eigen::MatrixXd(test::randomBlock(n, 1, 8));
      Eigen::MatrixXd xd = start;
      const SolveReport doubled = conjugateGradient(multigridOperator(mg), b, xd, options);
      Eigen::MatrixXf xf = start.cast<float>();
      const Eigen::MatrixXf bf = b.cast<float>();
      const SolveReport floated =
          conjugateGradient(multigridOperator<float, float>(mg), bf, xf, options);
      ASSERT_TRUE(floated.converged) << floated.toString();
      // B handed over (its storage becomes the residual): the same iterates, bit for bit.
      Eigen::MatrixXf xMoved = start.cast<float>();
      Eigen::MatrixXf bMoved = bf;
      const SolveReport moved = conjugateGradient(multigridOperator<float, float>(mg),
                                                  std::move(bMoved), xMoved, options);
      EXPECT_EQ(moved.residuals, floated.residuals);
      EXPECT_TRUE(xMoved == xf);
      const double trueResidual = (b - a * xf.cast<double>()).norm() / b.norm();
      EXPECT_LT(trueResidual, 1.5 * kFloatIterateTolerance)
          << "screening " << c.screening << (fromZero ? ", from zero" : ", from a guess");
      EXPECT_LE(std::abs(floated.iterations - doubled.iterations), 1)
          << floated.toString() << "\n" << doubled.toString();
    }
  }
}
