// Solver module: texel-grid multigrid with boundary direct solves (paper §6.2, Fig. 8), usable on
// its own (V-cycles) or as a symmetric preconditioner for conjugate gradients.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "texgrad/lattice/texel_grid.h"
#include "texgrad/solver/grid_hierarchy.h"
#include "texgrad/solver/solve_report.h"
#include "texgrad/solver/sparse_sum.h"

namespace texgrad {

/// Multigrid parameters; CLI flags map one-to-one onto these fields.
struct MultigridOptions {
  /// L: coarsenings below the texel grid (paper §6.3 default 4); fewer if the grid gets tiny.
  int levels = 4;
  /// n: Gauss–Seidel sweeps over interior texels per level, before and after (paper default 3).
  int sweeps = 3;
  /// Interior texels whose stencil couples more than this many times as strongly along one grid
  /// axis as across it are also relaxed by lines along that axis (charts stretched by their
  /// parameterisation, where point Gauss–Seidel smooths poorly); 0 turns line relaxation off.
  double lineRatio = 8.0;
  /// Texels within this many texels of a boundary texel with a weak row (diagonal below a
  /// quarter of its off-diagonal magnitudes: texels their chart barely covers) are solved
  /// directly with the boundary, on the texel grid; 0 turns this off (paper §6.1 split).
  int weakRowReach = 3;
  /// A level with fewer unknowns than this is not coarsened further (it is solved directly).
  int minCoarseUnknowns = 256;
  /// Worker threads for relaxation and transfers; 0 = all available. Results do not depend on it.
  int threads = 0;

  // The accepted ranges, which validate() checks and front ends (the CLI's help) quote.
  static constexpr int kMaxLevels = 16;         ///< levels in [0, kMaxLevels]
  static constexpr int kMaxSweeps = 100;        ///< sweeps in [1, kMaxSweeps]
  static constexpr double kMinLineRatio = 1.0;  ///< lineRatio 0 (off) or >= kMinLineRatio
  static constexpr int kMaxWeakRowReach = 8;    ///< weakRowReach in [0, kMaxWeakRowReach]
  static constexpr int kMaxThreads = 1024;      ///< threads in [0, kMaxThreads]
  /// Throws InvalidInputError naming the first bad field and its accepted range.
  void validate() const;
};

/// When solve() stops: after maxCycles, or once the relative residual falls below tolerance.
struct SolveControl {
  int maxCycles = 10;      ///< upper bound on V-cycles (or CG iterations)
  double tolerance = 0.0;  ///< relative residual ||b - A x|| / ||b|| to reach; 0 = run all cycles
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// Counters and timings of the set-up phases (paper §6.3, Table 1: initialization / update).
struct MultigridStats {
  int inits = 0;                  ///< hierarchy builds and symbolic analyses (init calls)
  int updates = 0;                ///< numeric updates (Galerkin products and factorisations)
  int symbolicAnalyses = 0;       ///< CHOLMOD analyses over all boundary and coarse systems
  int numericFactorizations = 0;  ///< CHOLMOD factorisations over all boundary and coarse systems
  double initSeconds = 0.0;       ///< total time in init
  double updateSeconds = 0.0;     ///< total time in update
};

/// One level of a multigrid hierarchy, as MultigridSolver::summary() lists it.
struct MultigridLevelInfo {
  int unknowns = 0;
  int interior = 0;             ///< relaxed by Gauss–Seidel (0 on a coarsest level solved directly)
  int boundary = 0;             ///< solved directly with the interior locked
  int64_t lineTexels = 0;       ///< interior texels also relaxed by lines (lineRatio)
  int64_t nonZeros = 0;         ///< of A^l
  int64_t boundaryNonZeros = 0; ///< of A_bb^l (of A^l on a coarsest level solved directly)
  int64_t factorNonZeros = 0;   ///< of the Cholesky factor of that block
  int64_t slots = 0;            ///< lattice slots of the level's boxes
  /// Bytes of the sparse matrices the last set-up held at once with this level's data: A^l
  /// (A^0 only if handed over, or formed for a direct solve) and A^{l+1}; at level 0 of a numeric
  /// set-up the larger of a handed-over A^0 and A^1, formed after A^0 is freed (docs/memory.md).
  int64_t setUpMatrixBytes = 0;
  bool direct = false;          ///< the coarsest level, solved directly
};

/// Multigrid solver for A x = b over the unknowns of a TexelGrid, A = alpha M + S (n x n SPD,
/// unknown order of the TexelGrid). Interior texels are relaxed by multi-colour Gauss–Seidel on
/// 9-point stencils held as dense per-slot arrays; boundary texels and the coarsest level are
/// solved with CHOLMOD in double precision. Scalar (float or double) is the precision of the
/// relaxation, transfers and right-hand sides. The V-cycle is symmetric (colour order and phase
/// order reversed on the way up), so it is an SPD preconditioner.
template <typename Scalar>
class MultigridSolver {
 public:
  /// Dense n x k block of k channels (RGB: k = 3) in the unknown order of the TexelGrid.
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;

  /// Creates a solver with the given options (validated).
  explicit MultigridSolver(const MultigridOptions& options = {});
  ~MultigridSolver();
  MultigridSolver(MultigridSolver&&) noexcept;
  MultigridSolver& operator=(MultigridSolver&&) noexcept;

  /// Symbolic phase: builds the hierarchy, the coarse sparsity patterns, the interior/boundary
  /// split and the CHOLMOD analyses. `pattern` has the sparsity of every later A; its values
  /// only guide the split (weakRowReach), so pass the first A when it is known.
  /// Matrices reach init, update and initAndUpdate as SparseSum: they must be compressed.
  void init(const TexelGrid& grid, const SparseSum& pattern);
  /// Numeric phase: Galerkin products A^{l+1} = Pᵀ A^l P, stencils, boundary and coarse
  /// factorisations. `a` (a matrix, or a SparseSum such as alpha M + S, which is then never
  /// formed) must have the pattern given to init and is not referenced afterwards. Throws
  /// NumericalError if a block is not positive definite.
  void update(const SparseSum& a);
  /// As update, but the solver takes a over (a is left empty) and frees it once level 0's data
  /// and A^1 exist (with one level, once it is factorised), before the coarser levels are built:
  /// same result, lower peak memory.
  void update(Eigen::SparseMatrix<double>&& a);
  /// init(grid, a) then update(a) with one chain of Galerkin products instead of two (for
  /// one-shot solves; the result is identical).
  void initAndUpdate(const TexelGrid& grid, const SparseSum& a);
  /// As initAndUpdate, but the solver takes a over and frees it as update(a&&) does.
  void initAndUpdate(const TexelGrid& grid, Eigen::SparseMatrix<double>&& a);
  /// Builds the hierarchy for `grid` now, init's first step, so that the grid is not read again:
  /// the grid-free initAndUpdate and analyzePattern then use it.
  void buildHierarchy(const TexelGrid& grid);
  /// Uses `hierarchy`, built for the same grid (another solver's hierarchy()), as buildHierarchy.
  void setHierarchy(GridHierarchy hierarchy);
  /// initAndUpdate(grid, a) on the hierarchy already built (buildHierarchy, setHierarchy or an
  /// earlier init); throws InvalidInputError if there is none.
  void initAndUpdate(const SparseSum& a);
  /// initAndUpdate(grid, a&&) on the hierarchy already built, as initAndUpdate(a).
  void initAndUpdate(Eigen::SparseMatrix<double>&& a);
  /// initAndUpdate(a&&) for A as a FloatSystem (entries in float, about 8 bytes each where a
  /// double matrix takes 12): the interior stencils and row sums are the same as from the
  /// unrounded A (lines, whose pivots read the rounded diagonals, differ by rounding); the
  /// rounded diagonals of boundary rows and of a direct coarsest level are set from the row sums,
  /// so each row keeps its sum, as the difference form of the interior rows does. For float
  /// cycles (double cycles would lose the entries' last bits). The set-up drops the pages of the
  /// system's pattern as it reads them.
  void initAndUpdate(FloatSystem&& a);
  /// update(a&&) for A as a FloatSystem (see initAndUpdate(FloatSystem&&)).
  void update(FloatSystem&& a);
  /// One V-cycle (Fig. 8) improving x in place for right-hand side b (both n x k).
  void cycle(const Matrix& b, Matrix& x);
  /// V-cycles from the initial guess x until control is met; residual and change per cycle.
  /// Reports to `progress` before every cycle and at the end (reportSolveProgress); if it asks
  /// to cancel, throws Cancelled with x unchanged and the solver ready for the next solve.
  SolveReport solve(const Matrix& b, Matrix& x, const SolveControl& control,
                    const ProgressCallback& progress = {});
  /// One V-cycle on x in place for right-hand side b, both given in double and converted to
  /// the cycle precision and back (float cycles thus stop improving near float rounding).
  /// Returns ||b - A x|| / ||b|| for the new x in the cycle precision, fused into the last
  /// relaxation sweeps (0 if b = 0); with measureResidual false, NaN, and the cycle skips that
  /// residual (a level-0 stencil pass and the boundary rows: about a sixth of a cycle).
  double refine(const Eigen::MatrixXd& b, Eigen::MatrixXd& x, bool measureResidual = true);
  /// Preconditioner application z = V(r): one V-cycle from z = 0 (double in, double out).
  void precondition(const Eigen::MatrixXd& r, Eigen::MatrixXd& z) const;
  /// As precondition, with z in the cycle precision (which holds the cycle's result exactly).
  void preconditionInto(const Eigen::MatrixXd& r, Matrix& z) const;
  /// As preconditionInto, for a float r (CG with float iterates: no double copy of r).
  void preconditionInto(const Eigen::MatrixXf& r, Matrix& z) const;
  /// y = A x (n x k) with the level-0 operator the cycles hold (no copy of A): interior rows
  /// from their stencils in difference form, sum_k w_k (x_k - x_u) + (row sum of A) x_u,
  /// boundary rows in double; x is rounded to Scalar, sums are formed in double. Float stencils
  /// then perturb only the differences (relative ~6e-8), not the row sums (the screening term).
  void applyOperator(const Matrix& x, Matrix& y) const;

  /// Eigen preconditioner shape: re-runs init's symbolic phase for a new pattern (same grid, or
  /// the hierarchy of buildHierarchy or setHierarchy).
  MultigridSolver& analyzePattern(const Eigen::SparseMatrix<double>& a);
  /// Eigen preconditioner shape: update(a).
  MultigridSolver& factorize(const Eigen::SparseMatrix<double>& a);
  /// Eigen preconditioner shape: update(a) (init must have been called with the grid).
  MultigridSolver& compute(const Eigen::SparseMatrix<double>& a);
  /// Eigen preconditioner shape: one V-cycle from zero for a single column (not thread-safe:
  /// cycles share workspace).
  Eigen::VectorXd solve(const Eigen::VectorXd& r) const;
  /// Eigen::Success after update, Eigen::InvalidInput before.
  Eigen::ComputationInfo info() const;

  /// The grid hierarchy (valid after init).
  const GridHierarchy& hierarchy() const;
  /// Set-up counters and timings.
  const MultigridStats& stats() const;
  /// Time per phase accumulated over every cycle since the last update.
  const PhaseTimes& cycleTimes() const;
  /// Per level: unknowns, interior/boundary split, line texels and non-zeros (valid after update).
  std::vector<MultigridLevelInfo> levelInfo() const;
  /// Table of levelInfo().
  std::string summary() const;
  /// Bytes held: hierarchy, stencils, line coefficients, boundary rows, CHOLMOD factors and
  /// workspace, and the per-level vectors once a cycle has run (docs/memory.md).
  int64_t storageBytes() const;
  /// Options in use.
  const MultigridOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Prints summary().
template <typename Scalar>
std::ostream& operator<<(std::ostream& os, const MultigridSolver<Scalar>& solver);

extern template class MultigridSolver<float>;
extern template class MultigridSolver<double>;

}  // namespace texgrad
