// Gradient-domain filtering (`texgrad filter`, paper §7.1): smooth or sharpen a texture without
// opening seams, globally (beta) or locally (a per-cell beta map).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "texgrad/apps/barely_covered.h"
#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/image.h"
#include "texgrad/solver/solve_report.h"

namespace texgrad {

/// Parameters of the screened Poisson filter (alpha M + S) x* = (alpha M + beta S) x. Both
/// filters round the right-hand side to float (relative 6e-8, far below the solver's
/// tolerance), so that the one-shot filter holds it at half the bytes and both solve alike.
struct FilterOptions {
  /// Screening weight (paper default 1e4 on the unit-area surface): larger keeps closer to the
  /// input; smaller lets the gradient change spread further.
  double alpha = 1e4;
  /// Gradient modulation: < 1 smooths, > 1 sharpens, 1 returns the input.
  double beta = 1.0;
  /// Optional per-cell beta (TexelGrid::cellIndex), replacing `beta` (paper §7.1 local filtering).
  std::vector<double> betaPerCell;
  /// Treat the texture as a tangent-space normal map (decode, filter, renormalise, encode).
  bool normalMap = false;
  /// Keep the solver's values at barely covered texels; by default they are clamped into the
  /// range the surface shows around them (boundBarelyCovered), which keeps beta <= 1 results
  /// within 0.1 of the input's range (the exact values reach -9.66 on spot's [0, 1] texture).
  bool rawSolution = false;
  /// Solver, from the input texture. Default: CG preconditioned by one V-cycle per iteration,
  /// to a relative residual of 1e-4 (at most 320 iterations): measured 0.0014 of an 8-bit step
  /// from the direct solution on white noise over spot at 1024², 0.003 on spot's texture at
  /// 2048², where 16 plain V-cycles (the paper's solver, `kind = Multigrid`) only reach 0.07
  /// (spot's atlas has slow V-cycle modes).
  SolverSettings solver = [] {
    SolverSettings s;
    s.kind = SolverKind::MultigridCg;
    s.cycles = 16;  // if the kind is changed to Multigrid
    s.maxIterations = 320;
    s.tolerance = 1e-4;
    return s;
  }();
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// Output of filterTexture: the image plus what the solve did.
struct FilterResult {
  Image image;  ///< same size, channels and format as the input; inactive texels kept
  /// The solve, one channel at a time, as one (iterations summed over the channels; residuals[i]
  /// the largest relative residual ||b_c - A x_c|| / ||b_c|| over the channels after i
  /// iterations of each, so residuals.back() is the worst channel's final one; converged if
  /// every channel converged); phase times summed.
  SolveReport report;
  double initSeconds = 0.0, updateSeconds = 0.0;
  /// SystemSolver::storageBytes() after the last channel's solve (its level vectors hold one
  /// channel).
  int64_t solverStorageBytes = 0;
};

/// Filters `texture` (at the domain's resolution), solving for one channel at a time with the
/// same solver (its vectors then hold one channel, not all); the iterative kinds start from the
/// input texture. Reports stages "solver setup" and "solve" to `progress`, which may cancel
/// (Cancelled): "solve" goes once from 0 to 1 over all channels, its step counting the V-cycles
/// or CG iterations of every channel so far, of channels times the most per channel. Keeps neither
/// M x0 nor S x0 (InteractiveFilter keeps them for new parameters), holds an 8-bit texture as its
/// levels during set-up and solve (exactByteLevels), and writes the result into `texture`'s
/// storage: move a texture in that the caller no longer needs.
FilterResult filterTexture(const TexelDomain& domain, Image texture, const FilterOptions& options,
                           const ProgressCallback& progress = {});

/// As above, for a caller done with the operators: `operators` (the domain's, handed over by
/// TexelDomain::releaseOperators) are freed once the right-hand side and the system matrix
/// alpha M + S are formed, before the solver's set-up, so M, S and C (~190 bytes per active
/// texel) are not held through set-up and solve. Without a beta map, the right-hand side and
/// the bound on barely covered texels are formed column by column while M and S become A
/// (TexelOperators::screenedSystem's visitor), so operators built with
/// OperatorOptions::deferAssembly are welcome: assembled only then, they never hold S whole. If
/// the domain no longer holds operators, the grid's per-texel maps go too
/// (TexelDomain::releaseImageMaps: ~8 bytes per active texel at half coverage), all but those
/// the solver's hierarchy reads (texels' class and chart) before it is built, those once it
/// exists. Same result, bit for bit.
FilterResult filterTexture(TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                           Image texture, const FilterOptions& options,
                           const ProgressCallback& progress = {});

/// As above, for an 8-bit texture held as its levels: `levels` is exactByteLevels(texture), whose
/// pixels are not read (a caller that held the texture so while the operators were built hands
/// it over as it is: no float copy at the operators' peak). Throws InvalidInputError if texture
/// is not UInt8 or `levels` does not hold one value per texel and channel. Same result, bit for
/// bit.
FilterResult filterTexture(TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                           Image texture, std::vector<uint8_t> levels, const FilterOptions& options,
                           const ProgressCallback& progress = {});

/// The filter as a stateful solver for interactive use: change alpha / beta map, then step.
class InteractiveFilter {
 public:
  /// Sets up the solver (init + update phases) for `texture` on `domain`, which must outlive it
  /// and keep its operators; reports stage "solver setup" to `progress`, which may cancel.
  InteractiveFilter(const TexelDomain& domain, Image texture, const FilterOptions& options,
                    const ProgressCallback& progress = {});
  /// New alpha, uniform beta and optional per-cell beta (replaces beta): numeric update only.
  void setParameters(double alpha, double beta, std::vector<double> betaPerCell = {});
  /// One V-cycle (or an exact solve with the direct solver) towards the current target.
  SolveReport step(const ProgressCallback& progress = {});
  /// Runs the configured number of cycles (or the direct solve) on every channel at once,
  /// reporting stage "solve" to `progress` (SystemSolver::solve); after a cancel the filter can
  /// solve again, every channel advanced alike.
  SolveReport solve(const ProgressCallback& progress = {});
  /// Current solution as an image (input's size, channels and format; inactive texels as input),
  /// barely covered texels replaced unless FilterOptions::rawSolution.
  Image image() const;
  /// Seconds of the init phase and of the last update.
  double initSeconds() const { return solver_.initSeconds(); }
  double updateSeconds() const { return solver_.updateSeconds(); }

 private:
  /// setParameters, reporting the numeric update to `progress`.
  void applyParameters(double alpha, double beta, std::vector<double> betaPerCell,
                       const ProgressCallback& progress);

  const TexelDomain& domain_;
  Image input_;    ///< texture as given
  Image working_;  ///< a normal map's decoded vectors (empty otherwise: the solve acts on input_)
  bool normalMap_;
  double alpha_ = 0.0;  ///< alpha of the last numeric update (0: none yet)
  Eigen::MatrixXd x0_, x_, rhs_;
  Eigen::MatrixXd massX0_, stiffnessX0_;  ///< M x0 and S x0: fixed, reused by every setParameters
  BarelyCoveredNeighbours barely_;        ///< bounded in image() (none with rawSolution)
  SystemSolver solver_;
  /// The operators' exactUnknowns, for A rounded as the one-shot filter rounds it (found once).
  std::vector<uint8_t> exactUnknowns_;
};

}  // namespace texgrad
