// Solver module: the report every iterative or direct solve returns (iterations, residuals, timing).
#pragma once

#include <string>
#include <vector>

#include "texgrad/core/progress.h"

namespace texgrad {

/// Wall-clock seconds spent in each phase of a multigrid V-cycle (paper §6.3, Fig. 10).
struct PhaseTimes {
  double relaxation = 0.0;  ///< interior Gauss–Seidel sweeps, all levels
  double boundary = 0.0;    ///< boundary direct solves with interior locked, all levels
  double coarse = 0.0;      ///< direct solve at the coarsest level
  double transfer = 0.0;    ///< residuals, restriction and prolongation
  double matvec = 0.0;      ///< sparse matrix-vector products (conjugate gradients)
  double preconditioner = 0.0;  ///< preconditioner applications (conjugate gradients)
  double other = 0.0;       ///< everything else (scatter/gather, norms, vector updates)
  /// Sum of all phases.
  double total() const {
    return relaxation + boundary + coarse + transfer + matvec + preconditioner + other;
  }
};

/// Outcome of solve(): non-convergence is reported here, never thrown.
struct SolveReport {
  int iterations = 0;           ///< V-cycles or CG iterations performed
  bool converged = false;       ///< true when the requested tolerance was reached
  /// True when the solve stopped early because its residual grew far above the best it had
  /// reached (conjugate gradients: kCgDivergenceGrowth); converged is then false.
  bool diverged = false;
  /// Relative residual ||b - A x||_F / ||b||_F (all channels together); entry 0 is the initial guess.
  std::vector<double> residuals;
  /// Root-mean-square change of x per iteration (over all unknowns and channels).
  std::vector<double> rmsChange;
  PhaseTimes times;             ///< time per phase, summed over iterations
  /// Mean residual reduction factor per iteration over the last `window` iterations (0 if unknown).
  double convergenceFactor(int window = 3) const;
  /// One line per iteration: index, residual, RMS change; then the phase times.
  std::string toString() const;
};

/// Share of a solve done after report.iterations of at most maxIterations, for progress bars:
/// the larger of iterations / maxIterations and the share of the way, in log residual, from the
/// first residual to `tolerance` that the best residual so far has gone (0: iterations only).
/// Non-decreasing over the iterations of one solve; 1 once converged or at maxIterations.
double solveFraction(const SolveReport& report, int maxIterations, double tolerance);

/// Reports a solve to `progress` (stage "solve", step = report.iterations, steps =
/// maxIterations, fraction = solveFraction, or 1 once `finished`); throws Cancelled if it asks to
/// stop. Solvers call it before each iteration and once finished.
void reportSolveProgress(const ProgressCallback& progress, const SolveReport& report,
                         int maxIterations, double tolerance, bool finished = false);

}  // namespace texgrad
