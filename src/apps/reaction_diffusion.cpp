// Gray–Scott time stepping with implicit diffusion (M + dt D S) and explicit reaction; seeding by
// a lumped projection of smooth bumps placed at random surface points.
#include "texgrad/apps/reaction_diffusion.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <utility>

#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"
#include "texgrad/fem/metric.h"

namespace texgrad {
namespace {

/// V-cycles per step and species of the default solver. Each step only changes the state a
/// little, so two cycles from the explicit target leave an error of well under 1% of the pattern
/// amplitude after hundreds of steps (one cycle: several %).
constexpr int kReactionCycles = 2;
/// Concentrations inside a seed spot at its centre (Pearson's perturbation u = 1/2, v = 1/4).
constexpr double kSeedUDrop = 0.5;
constexpr double kSeedV = 0.25;
/// Width of a seed spot's fall-off ring, relative to its radius.
constexpr double kSeedFalloff = 0.5;
/// Texels with M_tt below this fraction of the mean diagonal get a pinning term (see
/// pinNegligibleTexels); real atlases have boundary texels down to 1e-17 of the mean.
constexpr double kNegligibleMass = 1e-10;
/// Surface fraction at each end of the u range that the display stretch ignores.
constexpr double kDisplayQuantile = 1e-3;

/// Uniform value in [0, 1) from the top 53 bits of a 64-bit draw (same on every platform).
double unitValue(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

void requirePositive(double value, const char* name) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw InvalidInputError(std::string(name) + " must be a positive number, got " +
                            std::to_string(value));
}

void requireNonNegative(double value, const char* name) {
  if (!(value >= 0.0) || !std::isfinite(value))
    throw InvalidInputError(std::string(name) + " must be a number >= 0, got " +
                            std::to_string(value));
}

/// Seed-spot centres: points drawn uniformly with respect to 3-D area over faces of M.
std::vector<Eigen::Vector3d> seedCentres(const TexturedMesh& mesh, const TexelGrid& grid, int count,
                                         uint64_t seed) {
  std::vector<double> cumulative;
  std::vector<int> faceOf;
  double total = 0.0;
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    if (fem::gridArea(mesh, grid, static_cast<int>(f)) == 0.0) continue;
    const Triangle& t = mesh.triangles[f];
    total += 0.5 * (mesh.positions[t[1]] - mesh.positions[t[0]])
                       .cross(mesh.positions[t[2]] - mesh.positions[t[0]])
                       .norm();
    cumulative.push_back(total);
    faceOf.push_back(static_cast<int>(f));
  }
  std::vector<Eigen::Vector3d> centres;
  if (!(total > 0.0)) return centres;
  std::mt19937_64 rng(seed);
  for (int i = 0; i < count; ++i) {
    const double pick = unitValue(rng) * total;
    const size_t k =
        std::min(cumulative.size() - 1,
                 static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) -
                                     cumulative.begin()));
    double a = unitValue(rng), b = unitValue(rng);
    if (a + b > 1.0) {  // fold the far half of the parallelogram back into the triangle
      a = 1.0 - a;
      b = 1.0 - b;
    }
    const Triangle& t = mesh.triangles[faceOf[k]];
    centres.push_back((1.0 - a - b) * mesh.positions[t[0]] + a * mesh.positions[t[1]] +
                      b * mesh.positions[t[2]]);
  }
  return centres;
}

/// Adds a tiny diagonal term to the rows of texels whose basis function barely touches the
/// surface (M_tt below kNegligibleMass times the mean of diag M). Such rows are numerically
/// singular (pivots at rounding level break the Cholesky factorisations); the term pins their
/// values without measurably changing any other texel or the total mass.
void pinNegligibleTexels(const SparseMatrixd& mass, SparseMatrixd& system) {
  const Eigen::VectorXd diagonal = mass.diagonal();
  const double floor = kNegligibleMass * diagonal.mean();
  for (Eigen::Index t = 0; t < diagonal.size(); ++t)
    if (diagonal(t) < floor) system.coeffRef(t, t) += floor;
}

/// M + dtD S on M's pattern (a copy of it allocated to size: no sparse merge, whose result
/// Eigen over-allocates), with negligible texels pinned.
SparseMatrixd diffusionSystem(const TexelOperators& ops, double dtD) {
  SparseMatrixd system = ops.combined([dtD](Eigen::Index, Eigen::Index, double mass,
                                            double stiffness) { return mass + dtD * stiffness; });
  pinNegligibleTexels(ops.mass(), system);
  return system;
}

/// M of operators handed over, in its own storage; S, the basis and the rest are freed.
SparseMatrixd keepOnlyMass(std::unique_ptr<TexelOperators> operators) {
  return TexelOperators::combined(
      std::move(operators), [](Eigen::Index, Eigen::Index, double mass, double) { return mass; });
}

/// The operators handed over to a ReactionDiffusion; throws InvalidInputError unless they are
/// the domain's.
const TexelOperators& handedOver(const std::unique_ptr<TexelOperators>& operators,
                                 const TexelDomain& domain) {
  if (!operators || operators->mass().rows() != domain.unknowns())
    throw InvalidInputError(
        "ReactionDiffusion: the operators handed over are not the domain's "
        "(TexelDomain::releaseOperators)");
  return *operators;
}

const ReactionDiffusionOptions& validated(const ReactionDiffusionOptions& options) {
  options.validate();
  return options;
}

/// Value below which a fraction q of the total weight lies (weights >= 0).
double weightedQuantile(const Eigen::VectorXd& values, const Eigen::VectorXd& weights, double q) {
  std::vector<int> order(static_cast<size_t>(values.size()));
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return values(a) < values(b); });
  const double target = q * weights.cwiseMax(0.0).sum();
  double cumulative = 0.0;
  for (int i : order) {
    cumulative += std::max(0.0, weights(i));
    if (cumulative >= target) return values(i);
  }
  return values(order.back());
}

/// reactionImage of u, with surface-area weights M 1.
Image stateImage(const TexelGrid& grid, const SparseMatrixd& mass, const Eigen::VectorXd& u) {
  Image image(grid.imageWidth, grid.imageHeight, 1, PixelFormat::UInt8);
  if (u.size() != grid.unknownCount())
    throw InvalidInputError("reactionImage: " + std::to_string(u.size()) + " values for " +
                            std::to_string(grid.unknownCount()) + " unknowns");
  if (u.size() == 0) return image;
  // The clamped values become the shown ones in place, once the weights are freed.
  Eigen::VectorXd shown = u.cwiseMax(0.0).cwiseMin(1.0);
  double low = 0.0, high = 0.0;
  {
    const Eigen::VectorXd weight = mass * Eigen::VectorXd::Ones(u.size());
    low = weightedQuantile(shown, weight, kDisplayQuantile);
    high = weightedQuantile(shown, weight, 1.0 - kDisplayQuantile);
  }
  if (high > low)
    shown = ((high - shown.array()) / (high - low)).cwiseMax(0.0).cwiseMin(1.0);
  else
    shown.setZero();
  scatterTexels(grid, shown, image);
  return image;
}

/// Runs `steps` time steps of a freshly set-up model and collects the one-shot result.
ReactionResult runToResult(ReactionDiffusion& model, int steps, const ProgressCallback& progress) {
  const auto start = std::chrono::steady_clock::now();
  model.run(steps, progress);
  ReactionResult result;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // The image first: its temporaries and the copies of u and v are not alive together.
  result.image = model.image();
  result.u = model.u();
  result.v = model.v();
  return result;
}

}  // namespace

ReactionPreset parseReactionPreset(const std::string& text) {
  if (text == "stripes") return ReactionPreset::Stripes;
  if (text == "dots") return ReactionPreset::Dots;
  throw InvalidInputError("unknown reaction-diffusion preset '" + text + "'; use stripes or dots");
}

GrayScottRates presetRates(ReactionPreset preset) {
  switch (preset) {
    case ReactionPreset::Stripes:
      return {0.050, 0.065};
    case ReactionPreset::Dots:
      return {0.030, 0.062};
  }
  return {};
}

SolverSettings defaultReactionSolver() {
  SolverSettings settings;
  settings.kind = SolverKind::Multigrid;
  settings.cycles = kReactionCycles;
  return settings;
}

void ReactionDiffusionOptions::validate() const {
  requireNonNegative(feed, "feed rate F");
  requireNonNegative(kill, "kill rate k");
  requirePositive(diffusionU, "diffusion rate Du");
  requirePositive(diffusionV, "diffusion rate Dv");
  requirePositive(timeStep, "time step");
  if (seedSpots < 0)
    throw InvalidInputError("seed spots must be >= 0, got " + std::to_string(seedSpots));
  requirePositive(seedRadius, "seed radius");
  solver.validate();
}

struct ReactionDiffusion::Impl {
  const TexelDomain& domain;
  ReactionDiffusionOptions options;
  /// The domain's operators, or null when they were handed over (then only ownedMass is kept).
  const TexelOperators* operators;
  SparseMatrixd ownedMass;
  SystemSolver solverU, solverV;
  Eigen::VectorXd u, v;
  int steps = 0;
  SolveReport reports[2];

  /// Seeds the state and sets up both solvers from `ops`; if `owned` (holding `ops`) is given,
  /// keeps only its M once both systems are formed, before the second solver's set-up.
  Impl(const TexelDomain& d, const ReactionDiffusionOptions& o, const TexelOperators& ops,
       std::unique_ptr<TexelOperators> owned)
      : domain(d),
        options(o),
        operators(owned ? nullptr : &ops),
        // A step runs a few cycles from the explicit target: no solver needs a double copy of
        // its system for the refinement residuals (MatrixCopy::NotForRefinement).
        solverU(d.grid(), o.solver, MatrixCopy::NotForRefinement),
        solverV(d.grid(), o.solver, MatrixCopy::NotForRefinement) {
    seedState(ops, options.seed);
    const double dt = options.timeStep;
    // One system at a time: each is handed to its solver, which frees it once its level 0 is
    // built, before the next is formed; the operators go once the last one is formed.
    solverU.initAndUpdate(diffusionSystem(ops, dt * options.diffusionU));
    SparseMatrixd systemV = diffusionSystem(ops, dt * options.diffusionV);
    if (owned) {
      // Swapped in: Eigen 3.4's SparseMatrix has no move assignment, so `=` would copy M.
      SparseMatrixd mass = keepOnlyMass(std::move(owned));
      ownedMass.swap(mass);
    }
    solverV.initAndUpdate(std::move(systemV));
  }

  const SparseMatrixd& mass() const { return operators ? operators->mass() : ownedMass; }

  void seedState(const TexelOperators& ops, uint64_t seed) {
    const TexturedMesh& mesh = domain.mesh();
    const double surfaceArea = ops.report().metric.surfaceArea;
    // Seed radius is given on the unit-area surface; centres and distances are in mesh units.
    const double radius = options.seedRadius * std::sqrt(surfaceArea > 0.0 ? surfaceArea : 1.0);
    const std::vector<Eigen::Vector3d> centres =
        seedCentres(mesh, domain.grid(), options.seedSpots, seed);
    const fem::TexelBasis& basis = ops.basis();
    const SurfaceScalar bump = [&](const fem::SurfacePoint& p) {
      const Eigen::Vector3d x = basis.position(p);
      double psi = 0.0;
      for (const Eigen::Vector3d& c : centres) {
        // 1 inside the radius, then a smooth (C1) fall-off to 0 over half a radius.
        const double d = ((x - c).norm() - radius) / (kSeedFalloff * radius);
        const double w = d <= 0.0 ? 1.0 : d >= 1.0 ? 0.0 : (1.0 - d) * (1.0 - d) * (1.0 + 2.0 * d);
        psi = std::max(psi, w);
      }
      return psi;
    };
    // Lumped L2 projection: psi_t = int phi_t psi / int phi_t (seam-consistent, no solve).
    const Eigen::VectorXd weight = ops.mass() * Eigen::VectorXd::Ones(domain.unknowns());
    const Eigen::VectorXd integral = ops.massOf(bump);
    Eigen::VectorXd psi(domain.unknowns());
    for (int t = 0; t < domain.unknowns(); ++t)
      psi(t) = weight(t) > 0.0 ? std::clamp(integral(t) / weight(t), 0.0, 1.0) : 0.0;
    u = Eigen::VectorXd::Ones(domain.unknowns()) - kSeedUDrop * psi;
    v = kSeedV * psi;
    steps = 0;
  }
};

ReactionDiffusion::ReactionDiffusion(const TexelDomain& domain,
                                     const ReactionDiffusionOptions& options)
    : impl_(std::make_unique<Impl>(domain, validated(options), domain.operators(), nullptr)) {}

ReactionDiffusion::ReactionDiffusion(const TexelDomain& domain,
                                     std::unique_ptr<TexelOperators> operators,
                                     const ReactionDiffusionOptions& options)
    : impl_(std::make_unique<Impl>(domain, validated(options), handedOver(operators, domain),
                                   std::move(operators))) {}

ReactionDiffusion::~ReactionDiffusion() = default;

void ReactionDiffusion::setState(Eigen::VectorXd u, Eigen::VectorXd v) {
  const int n = impl_->domain.unknowns();
  if (u.size() != n || v.size() != n)
    throw InvalidInputError("reaction-diffusion state needs " + std::to_string(n) +
                            " values per species, got " + std::to_string(u.size()) + " and " +
                            std::to_string(v.size()));
  impl_->u = std::move(u);
  impl_->v = std::move(v);
  impl_->steps = 0;
}

void ReactionDiffusion::reseed(uint64_t seed) {
  if (!impl_->operators)
    throw InvalidInputError(
        "ReactionDiffusion::reseed: the operators were handed over (seeding needs them)");
  impl_->seedState(*impl_->operators, seed);
}

void ReactionDiffusion::step() {
  Impl& s = *impl_;
  const SparseMatrixd& mass = s.mass();
  const double dt = s.options.timeStep, feed = s.options.feed, kill = s.options.kill;
  // The explicit targets c + dt R(u, v) are the initial guesses (their residual is the
  // diffusion increment only), formed in one pass straight into the solves' storage.
  const Eigen::Index n = s.u.size();
  Eigen::MatrixXd xU(n, 1), xV(n, 1);
  for (Eigen::Index t = 0; t < n; ++t) {
    const double cu = std::clamp(s.u(t), 0.0, 1.0), cv = std::clamp(s.v(t), 0.0, 1.0);
    const double uvv = cu * cv * cv;
    xU(t) = s.u(t) + dt * (feed * (1.0 - cu) - uvv);
    xV(t) = s.v(t) + dt * (uvv - (feed + kill) * cv);
  }
  s.reports[0] = s.solverU.solve(mass * xU.col(0), xU);
  s.u = xU.col(0);
  xU.resize(0, 1);
  s.reports[1] = s.solverV.solve(mass * xV.col(0), xV);
  s.v = xV.col(0);
  ++s.steps;
}

void ReactionDiffusion::run(int steps, const ProgressCallback& progress) {
  if (steps < 0) throw InvalidInputError("steps must be >= 0, got " + std::to_string(steps));
  // Every step polls, so a cancel lands within one step; front ends choose how often to draw.
  reportProgress(progress, Progress{"react", 0.0, 0, steps});
  for (int i = 0; i < steps; ++i) {
    step();
    reportProgress(progress, Progress{"react", static_cast<double>(i + 1) / steps, i + 1, steps});
  }
}

const Eigen::VectorXd& ReactionDiffusion::u() const {
  return impl_->u;
}
const Eigen::VectorXd& ReactionDiffusion::v() const {
  return impl_->v;
}
int ReactionDiffusion::stepsTaken() const {
  return impl_->steps;
}
const SolveReport& ReactionDiffusion::lastReport(int species) const {
  return impl_->reports[species == 0 ? 0 : 1];
}

Image ReactionDiffusion::image() const {
  return stateImage(impl_->domain.grid(), impl_->mass(), impl_->u);
}

Image reactionImage(const TexelDomain& domain, const Eigen::VectorXd& u) {
  return stateImage(domain.grid(), domain.operators().mass(), u);
}

ReactionResult reactionDiffusion(const TexelDomain& domain, const ReactionDiffusionOptions& options,
                                 int steps, const ProgressCallback& progress) {
  ReactionDiffusion model(domain, options);
  return runToResult(model, steps, progress);
}

ReactionResult reactionDiffusion(const TexelDomain& domain,
                                 std::unique_ptr<TexelOperators> operators,
                                 const ReactionDiffusionOptions& options, int steps,
                                 const ProgressCallback& progress) {
  ReactionDiffusion model(domain, std::move(operators), options);
  return runToResult(model, steps, progress);
}

}  // namespace texgrad
