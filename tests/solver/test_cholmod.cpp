// Solver tests: CHOLMOD wrapper phases, accuracy, multi-RHS and failure reporting.
#include <gtest/gtest.h>

#include <Eigen/IterativeLinearSolvers>

#include "synthetic_problem.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/cholmod_solver.h"

using namespace texgrad;

TEST(CholmodSolver, SolvesMultiChannelSystemAccurately) {
  const test::SyntheticProblem p = test::multiChartProblem(8);
  const Eigen::SparseMatrix<double> a = p.system(1e2);
  const Eigen::MatrixXd b = test::randomBlock(a.rows(), 3);
  CholmodSolver solver(a);
  ASSERT_EQ(solver.info(), Eigen::Success);
  const Eigen::MatrixXd x = solver.solve(b);
  EXPECT_LT((a * x - b).norm() / b.norm(), 1e-12);
  EXPECT_EQ(solver.stats().solves, 1);
}

TEST(CholmodSolver, UpdateReusesSymbolicAnalysis) {
  const test::SyntheticProblem p = test::squareProblem(20);
  CholmodSolver solver;
  solver.analyzePattern(p.system(1.0));
  for (double alpha : {1.0, 10.0, 1e4}) solver.factorize(p.system(alpha));
  EXPECT_EQ(solver.stats().analyses, 1);
  EXPECT_EQ(solver.stats().factorizations, 3);
  const Eigen::MatrixXd b = test::randomBlock(p.mass.rows(), 2);
  EXPECT_LT((p.system(1e4) * solver.solve(b) - b).norm() / b.norm(), 1e-12);
  // A different pattern is analysed again, and counted.
  const test::SyntheticProblem q = test::squareProblem(21);
  solver.compute(q.system(1.0));
  EXPECT_EQ(solver.stats().analyses, 2);
}

TEST(CholmodSolver, IndefiniteMatrixThrowsNumericalError) {
  const test::SyntheticProblem p = test::squareProblem(6);
  CholmodSolver solver;
  EXPECT_THROW(solver.compute(p.system(-1e3)), NumericalError);
  EXPECT_THROW(solver.solve(Eigen::MatrixXd::Ones(p.mass.rows(), 1)), InvalidInputError);
}

TEST(CholmodSolver, WorksAsEigenPreconditioner) {
  const test::SyntheticProblem p = test::squareProblem(16);
  const Eigen::SparseMatrix<double> a = p.system(10.0);
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper, CholmodSolver> cg;
  cg.compute(a);
  const Eigen::VectorXd b = test::randomBlock(a.rows(), 1);
  const Eigen::VectorXd x = cg.solve(b);
  EXPECT_LE(cg.iterations(), 2);
  EXPECT_LT((a * x - b).norm() / b.norm(), 1e-10);
}
