// Apps layer: geodesic distances by the heat method on the texel basis (paper Sec. 7.3, Eq. 5-6;
// Crane et al. 2013), as a one-shot function and as a stateful solver for interactive picking.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "texgrad/apps/geodesic_source.h"
#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/solver/solve_report.h"

namespace texgrad {

/// How the additive constant of the distance is fixed (Eq. 6 determines y only up to a constant).
enum class GeodesicOffset : uint8_t {
  /// Match the 3-D chord distance on interior texels 2 to 4 texels away from the nearest source
  /// (median per source), where chord and geodesic agree to O(r^3 curvature^2). Removes the
  /// 0.3-0.4 texel bias that the rounded tip of y at the source gives Source (so the value at a
  /// source is O(texel) rather than exactly 0). Falls back to Source for a source with no such
  /// texel. Beyond the paper.
  NearField,
  /// Value 0 at the sources (paper Sec. 7.3: y -= y_t); mean over several sources.
  Source,
};

/// Parses "near-field" or "source"; throws InvalidInputError otherwise.
GeodesicOffset parseGeodesicOffset(const std::string& text);
/// Name accepted by parseGeodesicOffset.
std::string toString(GeodesicOffset offset);

/// Boundary condition of the diffusion step on surfaces with open boundary edges.
enum class GeodesicBoundary : uint8_t {
  /// Mean of the Neumann and Dirichlet diffusions (Crane et al. 2013, Sec. 3.2.3): keeps level
  /// sets from bending to meet the boundary at right angles. Dirichlet (u = 0) is imposed on the
  /// texels whose footprint an open boundary edge crosses. Costs a third system, and only where
  /// the mesh has open boundary edges.
  Average,
  /// Natural (Neumann) boundary only, as in the paper. Average degenerates to this for a source
  /// within about a texel of the boundary (its Dirichlet diffusion vanishes).
  Neumann,
};

/// Parses "average" or "neumann"; throws InvalidInputError otherwise.
GeodesicBoundary parseGeodesicBoundary(const std::string& text);
/// Name accepted by parseGeodesicBoundary.
std::string toString(GeodesicBoundary boundary);

/// Parameters of the heat method; CLI flags map one-to-one onto these fields.
struct GeodesicOptions {
  /// Screening weight of the diffusion step (Eq. 5) on the unit-area surface: the heat time is
  /// t = 1 / alpha. Larger values follow the surface more tightly but underflow sooner far from
  /// the source; smaller values smooth the distance near the source and around obstacles.
  double alpha = 1e3;
  /// How the constant of the distance is fixed.
  GeodesicOffset offset = GeodesicOffset::NearField;
  /// Boundary condition of the diffusion on surfaces with boundary.
  GeodesicBoundary boundary = GeodesicBoundary::Average;
  /// Solver for both systems; `cycles` V-cycles (or one direct solve) per system in solve().
  SolverSettings solver;
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
  /// Defaults for frame-by-frame GeodesicSolver::update(): kInteractiveSweeps sweeps per level
  /// and the paper's V-cycle (no line relaxation, no weak-row split), the cheapest per frame.
  static GeodesicOptions interactive();
};

/// Gauss–Seidel sweeps per level for interactive updates. The paper uses n = 3 everywhere; with
/// one V-cycle per system per frame, n = 2 gives more updates per second for about the same
/// error per update (spot 1024²: 8% more updates/s; RMS error after 3 updates 6.2e-4 of the
/// largest distance against 5.3e-4 with n = 3, the same ~1e-4 from the 6th update on).
constexpr int kInteractiveSweeps = 2;

/// Wall-clock seconds per stage of the heat method.
struct GeodesicTimings {
  double setup = 0.0;       ///< gradient samples, both solvers' init and update (once per mesh)
  double diffusion = 0.0;   ///< (alpha M + S) u = delta solves (Eq. 5), last solve or update
  double divergence = 0.0;  ///< normalised gradient and its divergence (one-point quadrature)
  double distance = 0.0;    ///< S y = div solves (Eq. 6) and the source offset
};

/// Heat-method distances, ready to store.
struct GeodesicResult {
  /// Per unknown (TexelGrid unknown order): distance in model units (GeodesicOffset says what
  /// the sources get); +infinity on parts of the surface not connected to a source.
  Eigen::VectorXd distances;
  std::vector<ResolvedSource> sources;  ///< where the sources were snapped to
  /// Largest distance (model units) over texels whose centre lies on M (gutter texels, which
  /// extrapolate past the boundary, are left out).
  double maxDistance = 0.0;
  int32_t unreachableTexels = 0;                         ///< texels not connected to any source
  int32_t farthestUnknown = -1;                          ///< unknown holding maxDistance
  Eigen::Vector2d farthestUv = Eigen::Vector2d::Zero();  ///< centre of that texel (UV)
  Eigen::Vector3d farthestPosition = Eigen::Vector3d::Zero();  ///< that centre on the surface (3-D)
  SolveReport diffusionReport;                                 ///< Eq. 5 solve
  SolveReport distanceReport;                                  ///< Eq. 6 solve
  GeodesicTimings timings;
};

/// Heat-method geodesic distances on one TexelDomain (paper Sec. 7.3).
///
/// init (constructor, once per mesh and resolution): per-element gradient samples of the texel
/// basis, symbolic and numeric set-up of both systems A1 = alpha M + S and A2 = S + eps M + G
/// (eps = kDistanceScreening: S alone is singular; G a ghost penalty on the twist of cells that
/// their chart covers only in part, beyond the paper: without it a texel whose basis function
/// barely meets M takes any value that fits the normalised gradient on its sliver, -1.44 on
/// Lantern where distances reach 8.6), and with GeodesicBoundary::Average on a mesh with open
/// boundary, A1 with Dirichlet rows. Per source set: b = sum_s phi_t(p_s) (a unit impulse per
/// source and per sheet of the surface through it), A1 u = b; X = -grad u / |grad u|_g per
/// element with one-point quadrature; A2 y = div_h(g X); the constant of y is fixed by
/// GeodesicOptions::offset in each connected component.
///
/// Units: operators live on the unit-area surface (paper Sec. 7); distances() multiplies
/// by unitScale() = sqrt(3-D area of M) so every distance it returns is in model units.
/// Texels with no path of coupled texels (the support graph of S, which crosses seams) to a
/// source lie on a part of the surface no source reaches: their distance is +infinity.
/// The domain must outlive the solver.
class GeodesicSolver {
 public:
  /// eps of A2 = S + eps M on the unit-area surface (well below S's first nonzero eigenvalue).
  /// eps M is far below float rounding of S: float V-cycles on A2 converge to its solution only
  /// with residuals that keep it (solve(): residuals from the level-0 operator, float interior
  /// stencils in difference form with A2's row sums); update() keeps y in float and stops near
  /// 1e-4 of the largest distance (see update()).
  static constexpr double kDistanceScreening = 1e-5;

  /// Builds gradient samples and runs both solvers' init and update phases, reporting stages
  /// "heat setup" and "distance setup" (and "dirichlet heat setup") to `progress`.
  explicit GeodesicSolver(const TexelDomain& domain, const GeodesicOptions& options = {},
                          const ProgressCallback& progress = {});
  ~GeodesicSolver();
  GeodesicSolver(GeodesicSolver&&) noexcept;
  GeodesicSolver& operator=(GeodesicSolver&&) noexcept;

  /// New screening weight: numeric update of A1 (and its Dirichlet variant) only, no symbolic
  /// work. Keeps the sources and restarts the iteration from zero.
  void setAlpha(double alpha);
  /// Replaces the sources (at least one) and resets u and y to zero (paper Sec. 7.3).
  void setSources(std::span<const GeodesicSource> sources);
  /// setSources with a single source.
  void setSource(const GeodesicSource& source);

  /// Interactive refinement (paper Sec. 7.3): one V-cycle on A1 u = b, then one on A2 y = div
  /// with the divergence of the current u. With the direct solver both solves are exact. With
  /// float cycles, both cycles keep their iterates in float (SystemSolver::refine, no double
  /// residual), and y is moved by its offset after each cycle so its constant part stays small:
  /// A2's float rounding then limits the distances to about 1e-4 of the largest distance (RMS;
  /// spot at 1024²), far below what an update changes while it refines; solve() refines with
  /// residuals of A (from float stencils, to ~1e-7 of |b|, with float cycles).
  /// The heat cycle measures its residual (fused into its last sweeps); once that is below 1e-4
  /// and a cycle no longer reduces it by 10% (float rounding: more cycles would not change u),
  /// later updates skip the heat cycle and the divergence and refine only y (heatSettled()).
  /// The distance cycle measures no residual (its report holds none; see residual()).
  void update();
  /// True once update() has stopped cycling on the heat (see update()); false after
  /// setSources, setAlpha and until then.
  bool heatSettled() const;
  /// Largest relative residual ||b - A x|| / ||b|| of the current heat and distance iterates;
  /// with float multigrid cycles (the solvers then keep no copy of A), A x comes from the
  /// multigrids' float level-0 operators (two products per system; ~1e-7 of |b| is its floor).
  /// Displays ask for it a few times a second.
  double residual() const;
  /// Full solves: settings.cycles V-cycles (or CG / direct) on A1, then on A2, reporting stages
  /// "heat solve" (and "dirichlet heat solve") and "distance solve" with their cycle counts to
  /// `progress`, which may cancel (Cancelled; solve again to finish).
  void solve(const ProgressCallback& progress = {});

  /// Current distances per unknown, model units (see GeodesicOffset for the value at sources);
  /// +infinity on parts of the surface not connected to a source.
  const Eigen::VectorXd& distances() const;
  /// Current diffused impulse u per unknown (Eq. 5, unit-area surface; n x 1); the mean of the
  /// Neumann and Dirichlet diffusions when those are averaged.
  const Eigen::MatrixXd& diffused() const;
  /// Per unknown: 1 if connected to a source (finite distance), else 0.
  const std::vector<uint8_t>& reachable() const;
  /// Number of unknowns held at zero by the Dirichlet diffusion (0 when it is not used).
  int dirichletTexels() const;
  /// Factor from unit-area-surface lengths to model units: sqrt of the 3-D area of M.
  double unitScale() const;
  /// Sources as snapped onto M.
  const std::vector<ResolvedSource>& sources() const;
  /// Reports of the last diffusion and distance solve (or update).
  const SolveReport& diffusionReport() const;
  const SolveReport& distanceReport() const;
  /// Stage timings; setup is the constructor's, the others are of the last solve() or update().
  const GeodesicTimings& timings() const;
  /// Options in use.
  const GeodesicOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  /// Runs an Impl that keeps one system's solver at a time (Impl::solveOnce).
  friend GeodesicResult geodesicDistance(const TexelDomain& domain,
                                         std::span<const GeodesicSource> sources,
                                         const GeodesicOptions& options,
                                         const ProgressCallback& progress);
};

/// One-shot heat-method distances from `sources` (at least one): the distances of GeodesicSolver
/// + solve(), bit for bit, plus the farthest texel; reports the stages of both to `progress`,
/// which may cancel. Holds one system's solver at a time and the gradient samples only between
/// the two solves (spot 2048²: `texgrad geodesic` peaks at 1.10 GB, 2.13 GB when it ran the
/// stateful solver; docs/memory.md).
GeodesicResult geodesicDistance(const TexelDomain& domain, std::span<const GeodesicSource> sources,
                                const GeodesicOptions& options = {},
                                const ProgressCallback& progress = {});

}  // namespace texgrad
