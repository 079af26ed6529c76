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

/// r = B - A X for an iterate X in double, with A applied in the work precision of `apply`
/// (`apply(p, ap)` sets ap = A p on Block-typed n x k blocks) as A x_hi + A x_lo, x_hi = X
/// rounded to that precision: the residual of X itself, not of x_hi, whose rounding A would
/// amplify by its largest eigenvalues. `p` and `ap` are work blocks.
template <typename Block, typename Apply>
void residualOfDoubleIterate(const Apply& apply, const Eigen::MatrixXd& b, const Eigen::MatrixXd& x,
                             Eigen::MatrixXd& r, Block& p, Block& ap) {
  using Scalar = typename Block::Scalar;
  p = x.template cast<Scalar>();
  apply(p, ap);
  r = b - ap.template cast<double>();
  p = (x - p.template cast<double>()).template cast<Scalar>();
  apply(p, ap);
  r -= ap.template cast<double>();
}

/// A CG system given by its actions on n x k blocks, so that A need not be stored as a matrix.
/// Directions p, products A p and preconditioned residuals z are Scalar blocks; the iterate X,
/// the right-hand side B and the residual are Iterate blocks (double by default; every dot
/// product and norm is double either way). Float halves the work vectors' memory and loses
/// nothing with a float multigrid, whose V-cycle and level-0 operator give float results; a
/// float iterate and residual (Iterate = float) halve those too, for tolerances of
/// kFloatIterateTolerance and above.
template <typename Scalar, typename Iterate = double>
struct CgOperator {
  /// n x k block of the work precision.
  using Block = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  /// n x k block of the iterate's precision (X, B, the residual).
  using Vectors = Eigen::Matrix<Iterate, Eigen::Dynamic, Eigen::Dynamic>;
  Eigen::Index rows = 0;                                   ///< n
  std::function<void(const Block& p, Block& ap)> product;  ///< ap = A p (A SPD)
  /// z = M⁻¹ r (M SPD); an empty function means z = r.
  std::function<void(const Vectors& r, Block& z)> preconditioner;
};

/// The smallest tolerance for CG with float iterates (CgOperator<float, float>): their residual,
/// updated in float, drifts from b - A x by some 1e-7 of |b| per hundred iterations, well below
/// this.
inline constexpr double kFloatIterateTolerance = 1e-5;

/// Preconditioned CG on `a` as conjugateGradient below, with three n x k work blocks (the
/// residual in Iterate, the direction and one shared for A p and M⁻¹ r in Scalar) and, once the
/// residual has risen, the best iterate kept in Scalar (returned, rounded to Scalar, if the
/// residual diverges).
template <typename Scalar, typename Iterate>
SolveReport conjugateGradient(const CgOperator<Scalar, Iterate>& a,
                              const typename CgOperator<Scalar, Iterate>::Vectors& b,
                              typename CgOperator<Scalar, Iterate>::Vectors& x,
                              const CgOptions& options = {}, const ProgressCallback& progress = {});
/// As above, with B's storage taken over for the residual: one n x k block less.
template <typename Scalar, typename Iterate>
SolveReport conjugateGradient(const CgOperator<Scalar, Iterate>& a,
                              typename CgOperator<Scalar, Iterate>::Vectors&& b,
                              typename CgOperator<Scalar, Iterate>::Vectors& x,
                              const CgOptions& options = {}, const ProgressCallback& progress = {});
extern template SolveReport conjugateGradient<float, float>(const CgOperator<float, float>&,
                                                            Eigen::MatrixXf&&, Eigen::MatrixXf&,
                                                            const CgOptions&,
                                                            const ProgressCallback&);
extern template SolveReport conjugateGradient<float, double>(const CgOperator<float>&,
                                                             Eigen::MatrixXd&&, Eigen::MatrixXd&,
                                                             const CgOptions&,
                                                             const ProgressCallback&);
extern template SolveReport conjugateGradient<double, double>(const CgOperator<double>&,
                                                              Eigen::MatrixXd&&, Eigen::MatrixXd&,
                                                              const CgOptions&,
                                                              const ProgressCallback&);
extern template SolveReport conjugateGradient<float, double>(const CgOperator<float>&,
                                                             const Eigen::MatrixXd&,
                                                             Eigen::MatrixXd&, const CgOptions&,
                                                             const ProgressCallback&);
extern template SolveReport conjugateGradient<double, double>(const CgOperator<double>&,
                                                              const Eigen::MatrixXd&,
                                                              Eigen::MatrixXd&, const CgOptions&,
                                                              const ProgressCallback&);
extern template SolveReport conjugateGradient<float, float>(const CgOperator<float, float>&,
                                                            const Eigen::MatrixXf&,
                                                            Eigen::MatrixXf&, const CgOptions&,
                                                            const ProgressCallback&);

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

/// A applied by the multigrid's level-0 operator (MultigridSolver::applyOperator) and
/// preconditioned by one V-cycle from zero, both in the cycle precision, for iterates in
/// Iterate: CG with no copy of A. `solver` must outlive the result.
template <typename Scalar, typename Iterate = double>
CgOperator<Scalar, Iterate> multigridOperator(const MultigridSolver<Scalar>& solver) {
  using Operator = CgOperator<Scalar, Iterate>;
  Operator op;
  op.rows = solver.hierarchy().levelCount() > 0 ? solver.hierarchy().level(0).unknownCount() : 0;
  op.product = [&solver](const typename Operator::Block& p, typename Operator::Block& ap) {
    solver.applyOperator(p, ap);
  };
  op.preconditioner = [&solver](const typename Operator::Vectors& r, typename Operator::Block& z) {
    solver.preconditionInto(r, z);
  };
  return op;
}

/// y = A x for a symmetric A with both triangles stored (n x n), x and y n x k; parallel. A may be
/// a matrix or a view on one (Eigen::Map): the Ref binds to either without a copy.
void symmetricProduct(const Eigen::Ref<const Eigen::SparseMatrix<double>>& a,
                      const Eigen::MatrixXd& x, Eigen::MatrixXd& y);
/// y = A x (n x 1) for a float x, each value read as the double it is: the same bits as the
/// product with x cast to double, without that n x 1 double copy.
void symmetricProduct(const Eigen::Ref<const Eigen::SparseMatrix<double>>& a,
                      const Eigen::VectorXf& x, Eigen::MatrixXd& y);
/// y = scale A x (n x 1) rounded to float: each value that of the double product above times
/// `scale`, rounded once, without an n x 1 double in between.
void symmetricProduct(const Eigen::Ref<const Eigen::SparseMatrix<double>>& a,
                      const Eigen::VectorXf& x, double scale, Eigen::MatrixXf& y);

}  // namespace texgrad
