// Solver module: sparse Cholesky (CHOLMOD) with separate symbolic, numeric and solve phases.
// Used for the full direct path, for boundary blocks and for the coarsest multigrid level (§6.2).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <memory>

namespace texgrad {

/// Counters and timings that show which phases ran (paper §6.3: init / update / solution).
struct CholmodStats {
  int analyses = 0;               ///< symbolic analyses (fill-reducing ordering, elimination tree)
  int factorizations = 0;         ///< numeric factorisations
  int solves = 0;                 ///< calls to solve (each may hold many right-hand sides)
  double analyzeSeconds = 0.0;    ///< total time in symbolic analysis
  double factorizeSeconds = 0.0;  ///< total time in numeric factorisation
  double solveSeconds = 0.0;      ///< total time in forward/back substitution
  long factorNonZeros = 0;        ///< non-zeros of the Cholesky factor L
};

/// Sparse LLᵀ / LDLᵀ factorisation of a symmetric positive-definite matrix by CHOLMOD.
/// Matrices are n x n, column-major, holding both triangles or only the lower one (only the lower
/// triangle is read). Shaped like Eigen's solvers (compute / solve / info), so it can also serve as
/// a preconditioner for Eigen::ConjugateGradient.
class CholmodSolver {
 public:
  /// Creates an empty solver; call analyzePattern and factorize (or compute) before solve.
  CholmodSolver();
  /// Analyses and factorises `a` at once.
  explicit CholmodSolver(const Eigen::SparseMatrix<double>& a);
  ~CholmodSolver();
  CholmodSolver(CholmodSolver&&) noexcept;
  CholmodSolver& operator=(CholmodSolver&&) noexcept;
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  /// Symbolic analysis of the sparsity pattern of `a` (values are ignored); run once per pattern.
  void analyzePattern(const Eigen::SparseMatrix<double>& a);
  /// Numeric factorisation of `a`; reuses the analysis when the pattern is unchanged (and analyses
  /// again, counted in stats(), when it differs). Throws NumericalError if `a` is not positive
  /// definite.
  void factorize(const Eigen::SparseMatrix<double>& a);
  /// analyzePattern (only if the pattern changed) followed by factorize; returns *this.
  CholmodSolver& compute(const Eigen::SparseMatrix<double>& a);
  /// Solves A X = B for every column of B (n x k); throws InvalidInputError before factorisation.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  /// Solves A X = B in place (n x k, column-major), reusing internal workspace between calls.
  void solveInPlace(Eigen::Ref<Eigen::MatrixXd> bx) const;
  /// Eigen::Success once factorised, Eigen::InvalidInput before.
  Eigen::ComputationInfo info() const;
  /// Number of rows of the factorised matrix.
  Eigen::Index rows() const;
  /// Number of columns of the factorised matrix.
  Eigen::Index cols() const { return rows(); }
  /// Phase counters and timings accumulated since construction.
  const CholmodStats& stats() const;
  /// Bytes held: the copied lower triangle plus all CHOLMOD holds (factor and workspace, its
  /// own count memory_inuse).
  int64_t storageBytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One-shot full direct solve of A X = B (ground truth, LIC): analyse, factorise, solve.
Eigen::MatrixXd solveDirect(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b);

}  // namespace texgrad
