// Solver module: preconditioned conjugate gradients on all channels at once, for systems where
// plain multigrid converges slowly (anisotropic metrics, LIC; paper §8 limitations).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>

#include "texgrad/solver/multigrid_solver.h"
#include "texgrad/solver/solve_report.h"

namespace texgrad {

/// Stopping rule for conjugateGradient.
struct CgOptions {
  int maxIterations = 1000;  ///< upper bound on iterations
  double tolerance = 1e-6;   ///< relative residual ||b - A x||_F / ||b||_F to reach
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// Applies z = M⁻¹ r to an n x k block (M SPD); an empty function means the identity.
using Preconditioner = std::function<void(const Eigen::MatrixXd& r, Eigen::MatrixXd& z)>;

/// A conjugate-gradient solve stops as diverged once its relative residual exceeds this many
/// times the smallest it has reached (rounding lets the residual of an SPD system rise a little
/// between iterations, never by orders of magnitude).
inline constexpr double kCgDivergenceGrowth = 1e4;

/// Solves A X = B (A n x n SPD with both triangles stored; B, X n x k) by preconditioned CG, one
/// independent recurrence per column, starting from X. Non-convergence is reported, not thrown;
/// so is divergence (SolveReport::diverged, kCgDivergenceGrowth), X then holding the iterate
/// with the smallest residual. Throws NumericalError, naming the iteration and column, if B or X
/// holds a NaN or infinity, if one appears (in A, or from the preconditioner), or if
/// p^T A p <= 0 or r^T M^-1 r <= 0 for a nonzero direction (A or the preconditioner is not
/// positive definite), as the multigrid solver does for a non-positive diagonal.
/// Reports to `progress` before every iteration and at the end (reportSolveProgress); if it asks
/// to cancel, throws Cancelled with X holding the last iterate.
SolveReport conjugateGradient(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b,
                              Eigen::MatrixXd& x, const Preconditioner& preconditioner,
                              const CgOptions& options = {}, const ProgressCallback& progress = {});

/// One symmetric V-cycle from zero as an SPD preconditioner; `solver` must outlive the result.
template <typename Scalar>
Preconditioner multigridPreconditioner(const MultigridSolver<Scalar>& solver) {
  return [&solver](const Eigen::MatrixXd& r, Eigen::MatrixXd& z) { solver.precondition(r, z); };
}

/// y = A x for a symmetric A with both triangles stored (n x n), x and y n x k; parallel. A may be
/// a matrix or a view on one (Eigen::Map): the Ref binds to either without a copy.
void symmetricProduct(const Eigen::Ref<const Eigen::SparseMatrix<double>>& a,
                      const Eigen::MatrixXd& x, Eigen::MatrixXd& y);

}  // namespace texgrad
