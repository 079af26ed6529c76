// Solver tests: conjugate gradients with and without the multigrid preconditioner.
#include <gtest/gtest.h>

#include <Eigen/IterativeLinearSolvers>
#include <cstdio>

#include "synthetic_problem.h"
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
