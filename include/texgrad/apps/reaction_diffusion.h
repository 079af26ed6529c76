// Gray–Scott reaction-diffusion on the surface, stored in the atlas (`texgrad react`): implicit
// diffusion through the texel operators, explicit reaction, one solver set-up per species.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>

#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/core/progress.h"
#include "texgrad/io/image.h"

namespace texgrad {

/// Named Gray–Scott parameter pairs in Pearson's parametrisation (Science 261, 1993; sigma =
/// Du / Dv = 2), as catalogued in R. Munafo's xmorphia pages.
enum class ReactionPreset {
  Stripes,  ///< F = 0.050, k = 0.065: worms grow to fill the surface, tending to parallel lines
  Dots,     ///< F = 0.030, k = 0.062: stable spots of one size that fill the surface
};

/// Parses "stripes" or "dots"; throws InvalidInputError otherwise.
ReactionPreset parseReactionPreset(const std::string& text);

/// Feed rate F and kill rate k of a preset.
struct GrayScottRates {
  double feed = 0.0;
  double kill = 0.0;
};
/// The rates of a preset.
GrayScottRates presetRates(ReactionPreset preset);

/// Solver settings reaction-diffusion starts from: two float V-cycles per step and species (the
/// systems M + dt D S are mass-dominated), starting from the explicit target c + dt R.
SolverSettings defaultReactionSolver();

/// Gray–Scott model  du/dt = Du Δu - u v² + F (1 - u),  dv/dt = Dv Δv + u v² - (F + k) v  on the
/// unit-area surface (paper §7 scaling), time in Pearson's units.
struct ReactionDiffusionOptions {
  double feed = 0.050;  ///< F: feed rate of u (preset stripes)
  double kill = 0.065;  ///< k: kill rate of v (preset stripes)
  /// Diffusion rates on the unit-area surface (Pearson's 2e-5 and 1e-5); pattern features scale
  /// with their square root, so 4x the rates gives 2x larger stripes or dots.
  double diffusionU = 2e-5;
  double diffusionV = 1e-5;
  /// Time step dt. Diffusion is implicit (unconditionally stable); the reaction is explicit
  /// Euler, accurate for dt up to about 1 (Pearson used 1).
  double timeStep = 1.0;
  /// Initial state: u = 1, v = 0 except in this many seed spots placed uniformly at random over
  /// the surface area, where u = 1 - psi / 2 and v = psi / 4 (Pearson's perturbation) with psi
  /// = 1 inside the spot and a smooth fall-off outside.
  int seedSpots = 40;
  /// Radius of a seed spot on the unit-area surface (3-D distance); spots much smaller than the
  /// pattern's feature size die out.
  double seedRadius = 0.06;
  /// Seed of the spot placement: the same seed and inputs give the same pattern.
  uint64_t seed = 1;
  SolverSettings solver = defaultReactionSolver();
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// Time stepper: per step and species s, (M + dt D_s S) s_{n+1} = M (s_n + dt R_s(u_n, v_n)).
/// R is evaluated per texel on concentrations clamped to [0, 1] (their physical range): texels
/// whose basis barely touches the surface have tiny mass, can overshoot in the diffusion solve,
/// and would otherwise feed the cubic reaction term and blow up.
/// Each species' solver is initialised and updated once, then reused every step. The solvers keep
/// no double copy of their systems (MatrixCopy::NotForRefinement): with float cycles, a step's
/// refinement residuals come from the multigrid's level-0 operator, and float cycles that diverge
/// (a time step so large that the system is nearly singular) throw Error naming double cycles.
/// `domain` must outlive the object.
class ReactionDiffusion {
 public:
  /// Sets up both solvers and the seeded initial state (options.seed).
  ReactionDiffusion(const TexelDomain& domain, const ReactionDiffusionOptions& options);
  /// As above, for a caller done with the operators (`operators`: the domain's, handed over by
  /// TexelDomain::releaseOperators): once both systems are formed, only M is kept (S, the basis
  /// and the rest are freed, ~80 bytes per active texel at spot 2048²). Same states, bit for
  /// bit; reseed() then throws InvalidInputError (seeding needs the basis).
  ReactionDiffusion(const TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                    const ReactionDiffusionOptions& options);
  ~ReactionDiffusion();
  ReactionDiffusion(const ReactionDiffusion&) = delete;
  ReactionDiffusion& operator=(const ReactionDiffusion&) = delete;

  /// Replaces the state (unknownCount values each); throws InvalidInputError on a size mismatch.
  void setState(Eigen::VectorXd u, Eigen::VectorXd v);
  /// Resets to the seeded initial state for `seed`; throws InvalidInputError if the operators
  /// were handed over to the constructor.
  void reseed(uint64_t seed);
  /// One time step. If v's solve throws (float cycles that diverge, see the class), u has
  /// already taken the step and v has not; setState or reseed starts over.
  void step();
  /// `steps` time steps, reporting progress (stage "react", step counts) after every step.
  void run(int steps, const ProgressCallback& progress = {});

  /// Concentration of u (1 = no pattern) per unknown.
  const Eigen::VectorXd& u() const;
  /// Concentration of v (0 = no pattern) per unknown.
  const Eigen::VectorXd& v() const;
  /// Time steps taken since the last reset.
  int stepsTaken() const;
  /// Solve reports of the last step: [0] for u, [1] for v.
  const SolveReport& lastReport(int species) const;
  /// reactionImage of the current state, from the model's own M (also once the operators were
  /// handed over).
  Image image() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Grey image of a state: u clamped to [0, 1] and stretched linearly from its range to [1, 0],
/// so the pattern (low u, high v) is light on dark. The range is taken between the 0.1% and
/// 99.9% surface-area weighted quantiles (weights M 1), so texels that barely touch the surface
/// do not set it. Inactive texels are 0.
Image reactionImage(const TexelDomain& domain, const Eigen::VectorXd& u);

/// Output of reactionDiffusion.
struct ReactionResult {
  Image image;           ///< reactionImage of the final state
  Eigen::VectorXd u, v;  ///< final state per unknown
  double seconds = 0.0;  ///< time spent stepping
};

/// One-shot: seeded state, `steps` time steps, image.
ReactionResult reactionDiffusion(const TexelDomain& domain, const ReactionDiffusionOptions& options,
                                 int steps, const ProgressCallback& progress = {});

/// As above, for a caller done with the operators (handed over by
/// TexelDomain::releaseOperators): S and the rest are freed once both systems are formed, only
/// M is kept for the steps (the ReactionDiffusion constructor that takes them). Same result, bit
/// for bit.
ReactionResult reactionDiffusion(const TexelDomain& domain,
                                 std::unique_ptr<TexelOperators> operators,
                                 const ReactionDiffusionOptions& options, int steps,
                                 const ProgressCallback& progress = {});

}  // namespace texgrad
