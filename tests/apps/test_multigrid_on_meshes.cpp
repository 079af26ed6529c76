// The paper's Fig. 11 set-up on every shared mesh at 1024²: (alpha M + S) x = M psi, alpha = 1e4,
// psi random, x = 0 initially. Multigrid must converge geometrically to the CHOLMOD solution.
#include <gtest/gtest.h>

#include <random>

#include "shared_meshes.h"
#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/atlas/distortion.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/conjugate_gradient.h"
#include "texgrad/solver/multigrid_solver.h"

namespace texgrad {
namespace {

struct Problem {
  Eigen::SparseMatrix<double> a;
  Eigen::MatrixXd b, truth;
};

Problem fig11Problem(const TexelDomain& domain) {
  const TexelOperators& ops = domain.operators();
  Problem p;
  p.a = 1e4 * ops.mass() + ops.stiffness();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> value(0.0, 1.0);
  Eigen::MatrixXd psi(domain.unknowns(), 1);
  for (Eigen::Index k = 0; k < psi.rows(); ++k) psi(k, 0) = value(rng);
  p.b = ops.mass() * psi;
  p.truth = solveDirect(p.a, p.b);
  return p;
}

/// Relative RMS error to the direct solution after each V-cycle from x = 0, until it reaches
/// `target` or after `cycles` cycles.
template <typename Scalar>
std::vector<double> errorPerCycle(const TexelDomain& domain, const Problem& p, int cycles,
                                  double target) {
  MultigridSolver<Scalar> solver;
  solver.init(domain.grid(), p.a);
  solver.update(p.a);
  using Matrix = typename MultigridSolver<Scalar>::Matrix;
  const Matrix b = p.b.cast<Scalar>();
  Matrix x = Matrix::Zero(p.b.rows(), p.b.cols());
  std::vector<double> errors;
  const double scale = p.truth.norm();
  for (int k = 0; k < cycles; ++k) {
    solver.cycle(b, x);
    errors.push_back((x.template cast<double>() - p.truth).norm() / scale);
    if (errors.back() <= target) break;
  }
  return errors;
}

class Fig11Slow : public ::testing::TestWithParam<test::SharedMesh> {};

TEST_P(Fig11Slow, MultigridConvergesGeometricallyToTheDirectSolution) {
  const test::SharedMesh& s = GetParam();
  const TexturedMesh mesh = readMesh(test::sharedData() / s.obj);
  const Distortion distortion = measureDistortion(mesh);
  const TexelDomain domain(mesh, 1024, 1024);
  const Problem p = fig11Problem(domain);

  const std::vector<double> d = errorPerCycle<double>(domain, p, 150, 1e-10);
  // Per-cycle reduction: geometric mean over the cycles before the error reaches 1e-9.
  int last = 0;
  while (last + 1 < static_cast<int>(d.size()) && d[last + 1] > 1e-9) ++last;
  const double factor = last > 0 ? std::pow(d[last] / d[0], 1.0 / last) : 0.0;
  std::cout << "[ fig11 ] " << s.name << " texels " << domain.unknowns() << " factor " << factor
            << " conformal99 " << distortion.conformal99 << " authalic99 "
            << distortion.authalic99 << " cycles to 1e-10 ";
  int reached = -1;
  for (size_t k = 0; k < d.size(); ++k)
    if (d[k] <= 1e-10) {
      reached = static_cast<int>(k) + 1;
      break;
    }
  std::cout << reached << "\n";
  // The target for the worst mesh (the median target, 0.3, is a property of the set).
  EXPECT_LE(factor, 0.6);
  EXPECT_LE(*std::min_element(d.begin(), d.end()), 1e-10) << "double cycles stall at "
                                                          << d.back();
  // Geometric decay: every block of 5 cycles (until 1e-9) cuts the error by a constant factor.
  for (int k = 5; k <= last; k += 5) EXPECT_LT(d[k], 0.9 * d[k - 5]) << "cycle " << k;

  // The same V-cycle as a CG preconditioner (one V-cycle per iteration, paper §8): the few slow
  // modes that limit plain cycles on some atlases are what CG removes first. CG stops at a
  // relative residual of 1e-12 and must be within 1e-8 of the CHOLMOD reference, whose own error
  // reaches ~1e-10 on Lantern (one step of iterative refinement moves it by that much; with
  // OpenBLAS a 1e-14 residual stop left CG 1.4e-10 away and the factor measured the reference).
  MultigridSolver<double> preconditioner;
  preconditioner.initAndUpdate(domain.grid(), p.a);
  Eigen::MatrixXd xc = Eigen::MatrixXd::Zero(p.b.rows(), p.b.cols());
  CgOptions cg;
  cg.maxIterations = 60;
  cg.tolerance = 1e-12;
  const SolveReport pcg = conjugateGradient(p.a, p.b, xc, multigridPreconditioner(preconditioner), cg);
  const double pcgError = (xc - p.truth).norm() / p.truth.norm();
  const double pcgFactor = std::pow(pcgError, 1.0 / std::max(1, pcg.iterations));
  std::cout << "[ fig11 ] " << s.name << " MG-PCG: error " << pcgError << " after "
            << pcg.iterations << " iterations, factor " << pcgFactor << " per iteration\n";
  EXPECT_LE(pcgError, 1e-8);
  EXPECT_LE(pcgFactor, factor);

  // Float cycles as the apps run them: float V-cycles, residual in double (SystemSolver).
  SolverSettings settings;
  settings.singlePrecision = true;
  settings.cycles = 1;
  SystemSolver solver(domain.grid(), settings);
  solver.init(p.a);
  solver.update(p.a);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(p.b.rows(), p.b.cols());
  double floatError = 1.0;
  int floatCycles = 0;
  while (floatCycles < 60 && floatError > 1e-5) {
    solver.step(p.b, x);
    ++floatCycles;
    floatError = (x - p.truth).norm() / p.truth.norm();
  }
  std::cout << "[ fig11 ] " << s.name << " float cycles to " << floatError << ": " << floatCycles
            << "\n";
  EXPECT_LE(floatError, 1e-5);
}

INSTANTIATE_TEST_SUITE_P(AllMeshes, Fig11Slow, ::testing::ValuesIn(test::sharedMeshes()),
                         test::sharedMeshName);

}  // namespace
}  // namespace texgrad
