// Apps layer: geodesic distances by the heat method on the texel basis (paper Sec. 7.3, Eq. 5-6;
// Crane et al. 2013), as a one-shot function and as a stateful solver for interactive picking.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/fem/texel_basis.h"
#include "texgrad/solver/solve_report.h"

namespace texgrad {

/// Where a distance source lies: a mesh vertex, a UV point or a 3-D point (model units).
struct GeodesicSource {
  enum class Kind : uint8_t { Vertex, Uv, Point };
  Kind kind = Kind::Vertex;
  int64_t vertex = -1;                               ///< Kind::Vertex: index into positions
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();      ///< Kind::Uv: texture coordinates
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< Kind::Point: 3-D position

  static GeodesicSource atVertex(int64_t index) { return {Kind::Vertex, index, {}, {}}; }
  static GeodesicSource atUv(const Eigen::Vector2d& uv) { return {Kind::Uv, -1, uv, {}}; }
  static GeodesicSource atPoint(const Eigen::Vector3d& p) { return {Kind::Point, -1, {}, p}; }
};

/// A source snapped onto the atlas domain M.
struct ResolvedSource {
  fem::SurfacePoint point;                              ///< face and grid coordinates
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();         ///< texture coordinates of the point
  Eigen::Vector3d position = Eigen::Vector3d::Zero();   ///< 3-D position (model units)
  /// How far the request was moved to reach M: UV units for UV sources, model units for 3-D
  /// points, 0 for vertices.
  double snapDistance = 0.0;
};

/// Snaps a source to the nearest point of M (faces with zero UV area are not part of M): a vertex
/// to one of its corners, a UV point to the nearest point of a UV triangle, a 3-D point to the
/// nearest point of a 3-D triangle. Throws InvalidInputError for a vertex index out of range or a
/// vertex that only touches UV-degenerate faces.
ResolvedSource resolveSource(const TexelDomain& domain, const GeodesicSource& source);

/// Parameters of the heat method; CLI flags map one-to-one onto these fields.
struct GeodesicOptions {
  /// Screening weight of the diffusion step (Eq. 5) on the unit-area surface: the heat time is
  /// t = 1 / alpha. Larger values follow the surface more tightly but underflow sooner far from
  /// the source; smaller values smooth the distance near the source and around obstacles.
  double alpha = 1e3;
  /// Solver for both systems; `cycles` V-cycles (or one direct solve) per system in solve().
  SolverSettings solver;
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// Wall-clock seconds per stage of the heat method.
struct GeodesicTimings {
  double setup = 0.0;       ///< gradient samples, both solvers' init and update (once per mesh)
  double diffusion = 0.0;   ///< (alpha M + S) u = delta solves (Eq. 5), last solve or update
  double divergence = 0.0;  ///< normalised gradient and its divergence (one-point quadrature)
  double distance = 0.0;    ///< S y = div solves (Eq. 6) and the source offset
};

/// Heat-method distances, ready to store.
struct GeodesicResult {
  /// Per unknown (TexelGrid unknown order): distance in model units, 0 at the sources.
  Eigen::VectorXd distances;
  std::vector<ResolvedSource> sources;  ///< where the sources were snapped to
  double maxDistance = 0.0;             ///< largest texel value (model units)
  int32_t farthestUnknown = -1;         ///< unknown holding maxDistance
  Eigen::Vector2d farthestUv = Eigen::Vector2d::Zero();        ///< centre of that texel (UV)
  Eigen::Vector3d farthestPosition = Eigen::Vector3d::Zero();  ///< nearest surface point (3-D)
  SolveReport diffusionReport;          ///< Eq. 5 solve
  SolveReport distanceReport;           ///< Eq. 6 solve
  GeodesicTimings timings;
};

/// Heat-method geodesic distances on one TexelDomain (paper Sec. 7.3).
///
/// init (constructor, once per mesh and resolution): per-element gradient samples of the texel
/// basis, symbolic and numeric set-up of both systems A1 = alpha M + S and A2 = S + eps M
/// (eps = kDistanceScreening: S alone is singular). Per source: b = sum_s phi_t(p_s) (a unit
/// impulse per source), A1 u = b; X = -grad u / |grad u|_g per element with one-point quadrature;
/// A2 y = div_h(g X); y -= mean of y over the sources.
///
/// Units: operators live on the unit-area surface (DESIGN.md Sec. 2); distances() multiplies
/// by unitScale() = sqrt(3-D area of M) so every distance it returns is in model units.
/// Assumes M is connected: on a component without a source the distance is meaningless.
/// The domain must outlive the solver.
class GeodesicSolver {
 public:
  /// eps of A2 = S + eps M on the unit-area surface (well below S's first nonzero eigenvalue).
  static constexpr double kDistanceScreening = 1e-5;

  /// Builds gradient samples and runs both solvers' init and update phases.
  explicit GeodesicSolver(const TexelDomain& domain, const GeodesicOptions& options = {});
  ~GeodesicSolver();
  GeodesicSolver(GeodesicSolver&&) noexcept;
  GeodesicSolver& operator=(GeodesicSolver&&) noexcept;

  /// New screening weight: numeric update of A1 only (no symbolic work). Keeps the sources and
  /// restarts the iteration from zero.
  void setAlpha(double alpha);
  /// Replaces the sources (at least one) and resets u and y to zero (paper Sec. 7.3).
  void setSources(std::span<const GeodesicSource> sources);
  /// setSources with a single source.
  void setSource(const GeodesicSource& source);

  /// Interactive refinement (paper Sec. 7.3): one V-cycle on A1 u = b, then one on A2 y = div
  /// with the divergence of the current u. With the direct solver both solves are exact.
  void update();
  /// Full solves: settings.cycles V-cycles (or CG / direct) on A1, then on A2.
  void solve();

  /// Current distances per unknown, model units, 0 at the sources (mean over several sources).
  const Eigen::VectorXd& distances() const { return distances_; }
  /// Current diffused impulse u per unknown (Eq. 5, unit-area surface; n x 1).
  const Eigen::MatrixXd& diffused() const { return u_; }
  /// Factor from unit-area-surface lengths to model units: sqrt of the 3-D area of M.
  double unitScale() const { return scale_; }
  /// Sources as snapped onto M.
  const std::vector<ResolvedSource>& sources() const { return sources_; }
  /// Reports of the last diffusion and distance solve (or update).
  const SolveReport& diffusionReport() const { return diffusionReport_; }
  const SolveReport& distanceReport() const { return distanceReport_; }
  /// Stage timings; setup is the constructor's, the others are of the last solve() or update().
  const GeodesicTimings& timings() const { return timings_; }
  /// Options in use.
  const GeodesicOptions& options() const { return options_; }

 private:
  struct Gradients;
  void requireSources() const;
  void resetIterates();
  void diffusionStep(bool full);
  void distanceStep(bool full);

  const TexelDomain* domain_;
  GeodesicOptions options_;
  double scale_ = 1.0;
  std::unique_ptr<Gradients> gradients_;
  SystemSolver diffusionSolver_, distanceSolver_;
  Eigen::SparseMatrix<double> a1_, a2_;
  std::vector<ResolvedSource> sources_;
  std::vector<std::vector<fem::TexelWeight>> sourceWeights_;  ///< phi_t(p_s) per source
  Eigen::MatrixXd impulse_, u_, divergence_, y_;              ///< n x 1 blocks for SystemSolver
  Eigen::VectorXd distances_;
  SolveReport diffusionReport_, distanceReport_;
  GeodesicTimings timings_;
};

/// One-shot heat-method distances from `sources` (at least one): GeodesicSolver + solve(), plus
/// the farthest texel.
GeodesicResult geodesicDistance(const TexelDomain& domain,
                                std::span<const GeodesicSource> sources,
                                const GeodesicOptions& options = {});

}  // namespace texgrad
