// One front for every app's linear solves: multigrid (float or double cycles), multigrid-
// preconditioned CG, or CHOLMOD, with the init / update / solve phases kept apart (paper Sec. 6).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <memory>
#include <string>

#include "texgrad/atlas/texel_grid.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/multigrid_solver.h"
#include "texgrad/solver/solve_report.h"

namespace texgrad {

/// Which algorithm solves the texel systems.
enum class SolverKind {
  Multigrid,    ///< V-cycles (paper §6), starting from the app's initial guess
  MultigridCg,  ///< conjugate gradients preconditioned by one V-cycle (anisotropic metrics)
  Direct,       ///< CHOLMOD on the whole system
};

/// Parses "multigrid", "cg" or "direct"; throws InvalidInputError otherwise.
SolverKind parseSolverKind(const std::string& text);
/// Name accepted by parseSolverKind.
std::string toString(SolverKind kind);
/// Parses "float" or "double" into SolverSettings::singlePrecision (true for float); throws
/// InvalidInputError otherwise.
bool parseSinglePrecision(const std::string& text);

/// Solver choice and stopping rule; every CLI solver flag maps onto one field, and the CLI
/// accepts exactly the values validate() accepts.
struct SolverSettings {
  SolverKind kind = SolverKind::Multigrid;
  MultigridOptions multigrid;  ///< levels, sweeps, threads
  /// Float V-cycles (factorisations stay double); the residual is formed in double each cycle
  /// (mixed-precision refinement, or the double-precision CG around a float V-cycle), so float
  /// cycles reach double-precision accuracy (CG to a tolerance of kFloatOperatorTolerance or
  /// more applies A in float, see there). If a refinement cycle makes the residual diverge
  /// (float rounding on a nearly singular A), the solver undoes it and changes to double cycles
  /// for good (SystemSolver::settings() then says so); one that keeps no copy of A needs a way
  /// to form it again for that (MatrixCopy::NotForRefinement).
  bool singlePrecision = true;
  /// V-cycles per solve (Multigrid; at least 1). MultigridCg uses maxIterations, Direct neither.
  int cycles = 6;
  /// Most conjugate-gradient iterations per solve, each preconditioned by one V-cycle
  /// (MultigridCg; at least 1). The other kinds do not use it.
  int maxIterations = 120;
  /// Stop once the relative residual ||b - A x|| / ||b|| is at most this (0 to 1). 0 means the
  /// kind's default: Multigrid runs every cycle; MultigridCg stops at kDefaultCgTolerance (CG
  /// has no use for iterations past double rounding). Direct solves exactly and ignores it.
  double tolerance = 0.0;
  /// The relative residual MultigridCg stops at when tolerance is 0.
  static constexpr double kDefaultCgTolerance = 1e-8;
  /// MultigridCg with float cycles and an effective tolerance of at least this applies A through
  /// the multigrid's level-0 operator (float interior stencils: A to ~1e-7 relative to |A| |x|)
  /// with float direction and work vectors, and keeps no double copy of A; below it, CG runs
  /// entirely in double on a kept A. Double cycles' level-0 operator is A in double: CG always
  /// uses it. (Spot at 2048², filter --beta 0: see docs/memory.md.)
  static constexpr double kFloatOperatorTolerance = 1e-6;
  /// True if MultigridCg applies A through the multigrid's level-0 operator (see above).
  bool cgUsesLevelZeroOperator() const;
  /// The relative residual this kind stops at: tolerance, or the kind's default for 0.
  double effectiveTolerance() const;
  /// Throws InvalidInputError naming the first bad field and its accepted range.
  void validate() const;
};

/// Thrown by a solve whose float V-cycle diverged on a solver that keeps no copy of A to change
/// to double cycles with (MatrixCopy::NotForRefinement without SystemSolver::formAgainWith);
/// the cycle is undone first.
class FloatCyclesDiverged : public NumericalError {
 public:
  using NumericalError::NumericalError;
};

/// Whether a SystemSolver keeps its own copy of A after update (SystemSolver::matrix()).
enum class MatrixCopy {
  /// Only where its solves use it: Direct (residuals), Multigrid with float cycles (refinement
  /// residuals, the switch to double cycles), MultigridCg unless cgUsesLevelZeroOperator().
  WhenNeeded,
  Kept,  ///< always, for callers that read matrix()
  /// As WhenNeeded, except for Multigrid with float cycles and a tolerance of 0 or at least
  /// kFloatOperatorTolerance, which then keeps neither A nor any refinement vector between
  /// solves: its refinement residuals come from the multigrid's level-0 operator (A with its
  /// interior coefficients rounded to float in difference form, products rounded to float), so
  /// the iterate gets to ~1e-7 of |b| in residual, not to double rounding; the initial guess is
  /// rounded to float in place; a float cycle that diverges is undone and, if the caller said how
  /// to form A again (SystemSolver::formAgainWith), changes to double cycles on it for good, else
  /// throws FloatCyclesDiverged. For callers that run a few cycles per solve from a new initial
  /// guess each time (reaction-diffusion's steps, geodesics' full solves; refine() never reads
  /// A), not for repeated step() on one iterate.
  NotForRefinement,
};

/// Solves A X = B repeatedly for one texel grid and one sparsity pattern of A.
class SystemSolver {
 public:
  /// Reads `grid` here only (the multigrid kinds build their level hierarchy from it, timed as
  /// part of the first init): the grid may change or go afterwards.
  SystemSolver(const TexelGrid& grid, const SolverSettings& settings,
               MatrixCopy copy = MatrixCopy::WhenNeeded);
  ~SystemSolver();
  SystemSolver(SystemSolver&&) noexcept;
  SystemSolver& operator=(SystemSolver&&) noexcept;

  /// Symbolic phase for the sparsity pattern of every later A (multigrid: its values guide the
  /// interior/boundary split, MultigridOptions::weakRowReach; the direct solver ignores them).
  void init(const Eigen::SparseMatrix<double>& pattern);
  /// Numeric phase for a new A with the same pattern (new alpha, beta or metric). The solver
  /// keeps a copy of A where MatrixCopy says so. Reports stage "solver setup" to `progress` before
  /// (0) and after (1) the factorisations, which cannot be cancelled while they run.
  void update(const Eigen::SparseMatrix<double>& a, const ProgressCallback& progress = {});
  /// As update, but takes over a's storage (a temporary, or std::move(a): a is left empty)
  /// instead of copying it. Eigen 3.4's SparseMatrix has no move constructor or assignment, so
  /// this overload is what spares the copy. A solver that keeps no copy hands A on to the
  /// multigrid, which frees it once level 0 is built (MultigridSolver::update(a&&)).
  void update(Eigen::SparseMatrix<double>&& a, const ProgressCallback& progress = {});
  /// For MatrixCopy::NotForRefinement: how to form the current A again, should a float cycle
  /// diverge (the solver then keeps that A and cycles in double, as a solver with a copy does,
  /// instead of throwing FloatCyclesDiverged). Kept until replaced: after an update with a new
  /// A, `form` must form that one (call again, or let `form` read what it depends on).
  void formAgainWith(std::function<Eigen::SparseMatrix<double>()> form);
  /// init(a) then update(a); multigrid forms its Galerkin products once instead of twice.
  void initAndUpdate(const Eigen::SparseMatrix<double>& a, const ProgressCallback& progress = {});
  /// As initAndUpdate, taking over a's storage (see update).
  void initAndUpdate(Eigen::SparseMatrix<double>&& a, const ProgressCallback& progress = {});
  /// initAndUpdate on A read from a view (alpha M + S, say): a multigrid solver that keeps no copy
  /// of A (see MatrixCopy) does not form it, its set-up reading the entries from the view (but
  /// for a grid too small to coarsen, solved directly); other solvers form A
  /// (SparseSum::toMatrix) and take it over. The view's operands need to live through the call
  /// only.
  void initAndUpdate(const SparseSum& a, const ProgressCallback& progress = {});
  /// update on A read from a view, forming it only where initAndUpdate(const SparseSum&) does.
  void update(const SparseSum& a, const ProgressCallback& progress = {});
  /// True if this solver takes A as a FloatSystem as well as the unrounded A: float multigrid
  /// cycles keeping no copy of A (see MatrixCopy), whose interior stencils and row sums come out
  /// the same (MultigridSolver::initAndUpdate(FloatSystem&&)). A caller can then form A in float
  /// only (TexelOperators::screenedSystemInFloat: about 8 bytes per entry instead of 12).
  bool takesFloatSystem() const;
  /// takesFloatSystem() of a solver constructed with these settings and copy (before any change
  /// to double cycles), for a caller that forms A before it builds the solver.
  static bool takesFloatSystem(const SolverSettings& settings,
                               MatrixCopy copy = MatrixCopy::WhenNeeded);
  /// initAndUpdate on A as a FloatSystem, taken over (a is left empty): handed on to the
  /// multigrid if takesFloatSystem(), else formed in double first (formedMatrix).
  void initAndUpdate(FloatSystem&& a, const ProgressCallback& progress = {});
  /// update on A as a FloatSystem, taken over as initAndUpdate(FloatSystem&&) takes it.
  void update(FloatSystem&& a, const ProgressCallback& progress = {});
  /// Solves A X = B (n x k), using X as the initial guess for the iterative kinds. Reports stage
  /// "solve" to `progress` before every V-cycle or CG iteration (before and after the direct
  /// solve) and at the end, with the count done and the most the settings allow
  /// (reportSolveProgress). If it asks to cancel, throws Cancelled; X then holds an iterate (or
  /// the initial guess) and the solver is ready for the next solve.
  SolveReport solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                    const ProgressCallback& progress = {});
  /// As solve, for B and X in float: CG around float cycles keeps its iterate and residual in
  /// float too where floatIterates() (no double copy of B, X or the residual: 16 bytes per
  /// texel and channel less), the residual in B's storage (pass B with std::move to spare a
  /// copy); any other solver solves on double copies of them.
  SolveReport solve(Eigen::MatrixXf b, Eigen::MatrixXf& x, const ProgressCallback& progress = {});
  /// True if solve on float B and X iterates in float: MultigridCg with float cycles on the
  /// level-0 operator, to a tolerance of at least kFloatIterateTolerance.
  bool floatIterates() const;
  /// One V-cycle (Multigrid and MultigridCg kinds) or an exact solve (Direct), for interactive
  /// refinement; reports and cancels as solve.
  SolveReport step(const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                   const ProgressCallback& progress = {});
  /// As step, but float multigrid cycles x without the double-precision residual of step
  /// (faster: no sparse product in double; accuracy stops improving near float rounding). For
  /// frame-by-frame display. The report holds the relative residual of the new x only, or no
  /// residual with measureResidual false (the cycle then skips computing it). Other kinds and
  /// double cycles: step.
  SolveReport refine(const Eigen::MatrixXd& b, Eigen::MatrixXd& x, bool measureResidual = true);
  /// ||b - A x|| / ||b|| in double (one sparse product; ||A x|| if b = 0). Without a kept A,
  /// A x is the multigrid's level-0 operator on x rounded to the cycle precision.
  double relativeResidual(const Eigen::MatrixXd& b, const Eigen::MatrixXd& x) const;
  /// The system matrix A of the last update (compressed). Throws Error if the solver keeps no
  /// copy (construct it with MatrixCopy::Kept to read this).
  const Eigen::SparseMatrix<double>& matrix() const;
  /// Bytes held between solves: the kept copy of A (if any), the multigrid hierarchy or the
  /// direct factorisation, and the refinement vectors (docs/memory.md).
  int64_t storageBytes() const;
  /// Multigrid hierarchy summary, or a one-line description for the direct solver.
  std::string summary() const;
  /// Seconds spent in init and in the last update.
  double initSeconds() const;
  double updateSeconds() const;
  /// Settings in use.
  const SolverSettings& settings() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace texgrad
