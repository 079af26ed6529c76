// Heat-method geodesics (paper Sec. 7.3): one-point gradient samples of the texel basis for the
// normalised-gradient divergence, the two screened-Poisson solves and the distance offset
// (sources are snapped onto M in geodesic_source.cpp).
#include "texgrad/apps/geodesic.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "apps/closest_point.h"
#include "apps/geodesic_gradients.h"
#include "texgrad/apps/surface_normals.h"
#include "texgrad/core/error.h"

namespace texgrad {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// NearField offset: annulus of chord distances around a source, in texel sizes of its face.
constexpr double kNearFieldInner = 2.0;
constexpr double kNearFieldOuter = 4.0;
/// A source with fewer near-field texels than this falls back to its own value.
constexpr int kMinNearFieldTexels = 4;
/// Barycentric tolerance for "texel centre inside a face" (on-edge centres count for both faces).
constexpr double kInsideTolerance = 1e-9;
/// Step (texels) when walking open boundary edges to find the texels their footprints cross.
constexpr double kBoundaryStep = 0.25;
/// update() stops cycling on the heat once its relative residual is below kHeatSettledCeiling
/// and a cycle reduced it by less than the factor kHeatStallRatio: float cycles have reached
/// float rounding there (spot at 1024²: the residual reaches 2e-6 to 1.4e-5 within 5-7 updates
/// and then moves by a few per cent either way), so more cycles would not change u.
constexpr double kHeatSettledCeiling = 1e-4;
constexpr double kHeatStallRatio = 0.9;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// Last residual of a report, or NaN if it holds none.
double lastResidual(const SolveReport& report) {
  return report.residuals.empty() ? std::nan("") : report.residuals.back();
}

/// Eigenvalues (smaller, larger) of a symmetric 2x2 matrix.
std::pair<double, double> eigenvalues(const Eigen::Matrix2d& m) {
  const double mean = 0.5 * (m(0, 0) + m(1, 1));
  const double half = 0.5 * (m(0, 0) - m(1, 1));
  const double radius = std::sqrt(half * half + m(0, 1) * m(0, 1));
  return {mean - radius, mean + radius};
}

/// A1 = alpha M + S (paper Eq. 5) as a view of M and S, which a solver that keeps no copy of its
/// system never forms (docs/memory.md).
SparseSum heatSum(const TexelOperators& ops, double alpha) {
  return SparseSum(alpha, ops.mass(), 1.0, ops.stiffness());
}

/// A2 = S + eps M + G (see GeodesicSolver) as a view of S, M and the ghost penalty G (entries on
/// cut cells' texels, within M's pattern), formed only where heatSum's is.
SparseSum distanceSum(const TexelOperators& ops, const Eigen::SparseMatrix<double>& ghost) {
  return SparseSum(1.0, ops.stiffness(), GeodesicSolver::kDistanceScreening, ops.mass(), ghost);
}

}  // namespace

GeodesicOffset parseGeodesicOffset(const std::string& text) {
  if (text == "near-field") return GeodesicOffset::NearField;
  if (text == "source") return GeodesicOffset::Source;
  throw InvalidInputError("unknown geodesic offset '" + text + "'; use near-field or source");
}

std::string toString(GeodesicOffset offset) {
  return offset == GeodesicOffset::NearField ? "near-field" : "source";
}

GeodesicBoundary parseGeodesicBoundary(const std::string& text) {
  if (text == "average") return GeodesicBoundary::Average;
  if (text == "neumann") return GeodesicBoundary::Neumann;
  throw InvalidInputError("unknown geodesic boundary condition '" + text +
                          "'; use average or neumann");
}

std::string toString(GeodesicBoundary boundary) {
  return boundary == GeodesicBoundary::Average ? "average" : "neumann";
}

void GeodesicOptions::validate() const {
  if (!(alpha > 0.0) || !std::isfinite(alpha))
    throw InvalidInputError("geodesic alpha must be a positive finite number, got " +
                            std::to_string(alpha));
  solver.validate();
}

GeodesicOptions GeodesicOptions::interactive() {
  GeodesicOptions options;
  options.solver.multigrid.sweeps = kInteractiveSweeps;
  // The paper's cycle: one update a frame matters more than the factor per cycle here. Lines and
  // the weak-row split made an update on spot at 1024² take 40-43 ms against 29-34 ms.
  options.solver.multigrid.lineRatio = 0.0;
  options.solver.multigrid.weakRowReach = 0;
  return options;
}

/// The solver's state: both systems, the sources and the iterates (see GeodesicSolver).
struct GeodesicSolver::Impl {
  /// With `oneShot`, the gradient samples, the distance system and the distance step's vectors
  /// are made only by solveOnce(), after the heat solve.
  Impl(const TexelDomain& domain, const GeodesicOptions& options, const ProgressCallback& progress,
       bool oneShot = false);
  Impl(const Impl&) = delete;  // the solvers' formAgainWith lambdas hold `this`
  Impl& operator=(const Impl&) = delete;
  void setAlpha(double alpha);
  void setSources(std::span<const GeodesicSource> sources);
  void update();
  double residual() const;
  void solve(const ProgressCallback& progress);
  /// solve() for a one-shot Impl, with one system's solver alive at a time: the heat solve, then
  /// the heat solvers and the impulse are freed, the gradient samples built for the divergence
  /// and the ghost penalty and freed with the heat before the distance system is set up (at
  /// spot 2048² a solver holds ~250 MB of hierarchy, the samples 144 MB; no solver keeps its
  /// system, see kSystemCopy). The object can do nothing but report its results afterwards.
  void solveOnce(const ProgressCallback& progress);
  const Eigen::MatrixXd& diffused() const { return averaged_ ? heat_ : u_; }

  /// Interior texel near a source with its chord distance (unit-area units), for NearField.
  struct NearFieldTexel {
    int32_t unknown = -1;
    int32_t source = -1;
    double distance = 0.0;
  };
  void collectNearField();
  /// Labels the components of `pattern`'s support graph (M's, which A1 and A2 share) in
  /// component_.
  void labelComponents(const Eigen::SparseMatrix<double>& pattern);
  /// Marks the unknowns in a component that holds a source (reachable_).
  void findReachable();
  /// Throws InvalidInputError naming the sources when the components their weights touch hold
  /// no texel inside the image (the output would be all +inf).
  void requireReachInImage(const std::vector<std::vector<fem::TexelWeight>>& weights,
                           const std::vector<ResolvedSource>& sources) const;
  /// Marks the texels held at zero in the Dirichlet diffusion (dirichlet_) and sets averaged_.
  void markDirichlet();
  /// A1 with the rows and columns of the held texels reduced to their diagonal.
  Eigen::SparseMatrix<double> dirichletSystem(const Eigen::SparseMatrix<double>& a1) const;
  /// Labels A1's components and sets up the heat solver on A1 read from M and S (heatSum; first
  /// the Dirichlet one on a formed A1, when averaged), reporting "heat setup".
  void setUpHeat(const ProgressCallback& progress);
  /// Sets up the Dirichlet diffusion's solver on dirichletSystem(a1), reporting "dirichlet heat
  /// setup".
  void setUpDirichlet(const Eigen::SparseMatrix<double>& a1, const ProgressCallback& progress);
  /// A1 at the current alpha.
  Eigen::SparseMatrix<double> formHeatSystem() const;
  /// Per component of A1's support graph: the constant to subtract from y (GeodesicOffset).
  std::vector<double> offsets() const;
  void requireSources() const;
  void resetIterates();
  void diffusionStep(bool full, const ProgressCallback& progress = {});
  /// The divergence of the normalised gradient of diffused(), if the heat changed since the last.
  void computeDivergence();
  /// Builds gradients_ (samples of the basis gradients, on the solver's threads).
  void makeGradients();
  void distanceStep(bool full, const ProgressCallback& progress = {});
  /// Sets up the distance solver on A2 with the ghost penalty `ghost` (see GeodesicSolver), read
  /// from S, M and `ghost` (distanceSum); reports "distance setup".
  void setUpDistance(Eigen::SparseMatrix<double>&& ghost, const ProgressCallback& progress);

  const TexelDomain* domain_;
  GeodesicOptions options_;
  double scale_ = 1.0;
  std::unique_ptr<GeodesicGradients> gradients_;
  /// What the solvers keep of their systems: with float multigrid cycles (the default) nothing
  /// (-244 MB per system at spot 2048², docs/memory.md): the refinement residuals, and
  /// residual()'s products, come from the multigrid's level-0 operator, and a diverging float
  /// cycle forms its system again (formAgainWith, which the solvers' lambdas capture `this`
  /// for) and changes to double cycles. Other settings keep A as MatrixCopy::WhenNeeded says.
  static constexpr MatrixCopy kSystemCopy = MatrixCopy::NotForRefinement;
  /// Each made when first set up (a SystemSolver builds its hierarchy when made, so a solver
  /// made early would hold one before it is needed); solveOnce frees the diffusion one.
  std::optional<SystemSolver> diffusionSolver_, distanceSolver_;
  std::unique_ptr<SystemSolver> dirichletSolver_;  ///< only with Average on meshes with boundary
  Eigen::SparseMatrix<double> ghost_;              ///< the ghost penalty G of A2, to form A2 again
  bool averaged_ = false;  ///< the heat is the mean of two diffusions (a Dirichlet solver is made)
  bool oneShot_ = false;   ///< see the constructor
  std::vector<uint8_t> dirichlet_;  ///< per unknown: held at zero in the Dirichlet diffusion
  int dirichletCount_ = 0;
  std::vector<ResolvedSource> sources_;
  std::vector<std::vector<fem::TexelWeight>> sourceWeights_;  ///< phi_t(p_s) per source
  std::vector<NearFieldTexel> nearField_;                     ///< sorted by source
  std::vector<uint8_t> reachable_;  ///< per unknown: connected to a source
  std::vector<int32_t> component_;  ///< per unknown: its component of A1's support graph
  int32_t componentCount_ = 0;
  std::vector<int32_t> vertexFaceBegin_, vertexFaces_;  ///< faces around each 3-D vertex (CSR)
  /// n x 1 blocks for SystemSolver: impulse b (and b with Dirichlet rows zeroed), Neumann and
  /// Dirichlet diffusions, the heat u used for the gradient, divergence, potential y.
  Eigen::MatrixXd impulse_, impulseDirichlet_, u_, uDirichlet_, heat_, divergence_, y_;
  Eigen::VectorXd distances_;
  SolveReport diffusionReport_, distanceReport_;
  GeodesicTimings timings_;
  bool heatSettled_ = false;  ///< update() no longer cycles on the heat
  double heatResidual_ = std::numeric_limits<double>::infinity();  ///< of the last heat update
  bool heatChanged_ = true;  ///< u changed since the divergence was last computed
};

GeodesicSolver::Impl::Impl(const TexelDomain& domain, const GeodesicOptions& options,
                           const ProgressCallback& progress, bool oneShot)
    : domain_(&domain),
      options_([&] {
        options.validate();
        return options;
      }()),
      oneShot_(oneShot) {
  const auto start = Clock::now();
  const TexelOperators& ops = domain.operators();
  const double area = ops.report().metric.surfaceArea;
  if (!(area > 0.0)) throw InvalidInputError("the mesh has zero surface area; no distances exist");
  scale_ = std::sqrt(area);
  if (!oneShot) makeGradients();
  if (options_.boundary == GeodesicBoundary::Average && !domain.atlas().openBoundary.empty())
    markDirichlet();
  setUpHeat(progress);
  // The cut-cell ghost penalty keeps barely covered texels from amplifying the inconsistency
  // of the normalised gradient (see Gradients::stabiliser).
  if (!oneShot) setUpDistance(gradients_->stabiliser(domain.unknowns()), progress);
  const TexturedMesh& mesh = domain.mesh();
  vertexFaceBegin_.assign(mesh.positions.size() + 1, 0);
  for (const Triangle& t : mesh.triangles)
    for (int32_t v : t) ++vertexFaceBegin_[static_cast<size_t>(v) + 1];
  for (size_t v = 1; v < vertexFaceBegin_.size(); ++v)
    vertexFaceBegin_[v] += vertexFaceBegin_[v - 1];
  vertexFaces_.resize(static_cast<size_t>(vertexFaceBegin_.back()));
  std::vector<int32_t> cursor(vertexFaceBegin_.begin(), vertexFaceBegin_.end() - 1);
  for (size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int32_t v : mesh.triangles[f])
      vertexFaces_[static_cast<size_t>(cursor[static_cast<size_t>(v)]++)] = static_cast<int32_t>(f);
  const int n = domain.unknowns();
  impulse_ = Eigen::MatrixXd::Zero(n, 1);
  resetIterates();
  timings_.setup = secondsSince(start);
}

void GeodesicSolver::Impl::makeGradients() {
  gradients_ = std::make_unique<GeodesicGradients>(*domain_, options_.solver.multigrid.threads);
}

void GeodesicSolver::Impl::setUpHeat(const ProgressCallback& progress) {
  const TexelOperators& ops = domain_->operators();
  labelComponents(ops.mass());  // A1 is on M's pattern
  if (averaged_) setUpDirichlet(formHeatSystem(), progress);
  diffusionSolver_.emplace(domain_->grid(), options_.solver, kSystemCopy);
  diffusionSolver_->formAgainWith([this] { return formHeatSystem(); });
  diffusionSolver_->initAndUpdate(heatSum(ops, options_.alpha),
                                  renameStage(progress, "heat setup"));
}

void GeodesicSolver::Impl::setUpDirichlet(const Eigen::SparseMatrix<double>& a1,
                                          const ProgressCallback& progress) {
  dirichletSolver_ = std::make_unique<SystemSolver>(domain_->grid(), options_.solver, kSystemCopy);
  dirichletSolver_->formAgainWith([this] { return dirichletSystem(formHeatSystem()); });
  dirichletSolver_->init(a1);  // A1's values guide the interior/boundary split, as A1's solver's
  dirichletSolver_->update(dirichletSystem(a1), renameStage(progress, "dirichlet heat setup"));
}

Eigen::SparseMatrix<double> GeodesicSolver::Impl::formHeatSystem() const {
  return heatSum(domain_->operators(), options_.alpha).toMatrix();
}

void GeodesicSolver::Impl::setUpDistance(Eigen::SparseMatrix<double>&& ghost,
                                         const ProgressCallback& progress) {
  ghost_.swap(ghost);  // Eigen 3.4's SparseMatrix has no move constructor: a by-value copy
  distanceSolver_.emplace(domain_->grid(), options_.solver, kSystemCopy);
  distanceSolver_->formAgainWith(
      [this] { return distanceSum(domain_->operators(), ghost_).toMatrix(); });
  distanceSolver_->initAndUpdate(distanceSum(domain_->operators(), ghost_),
                                 renameStage(progress, "distance setup"));
}

void GeodesicSolver::Impl::markDirichlet() {
  const TexelGrid& grid = domain_->grid();
  const fem::TexelBasis& basis = domain_->operators().basis();
  dirichlet_.assign(static_cast<size_t>(domain_->unknowns()), 0);
  auto mark = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= grid.nx || y >= grid.ny) return;
    const int32_t u = grid.unknownOfTexel[static_cast<size_t>(grid.texelIndex(x, y))];
    if (u >= 0) dirichlet_[static_cast<size_t>(u)] = 1;
  };
  for (const FaceEdge& edge : domain_->atlas().openBoundary) {
    if (!basis.faceValid(edge.face)) continue;
    const auto& c = basis.faceCorners(edge.face);
    const Eigen::Vector2d a = c[static_cast<size_t>(edge.corner)];
    const Eigen::Vector2d b = c[static_cast<size_t>((edge.corner + 1) % 3)];
    const int steps = static_cast<int>(std::ceil((b - a).norm() / kBoundaryStep)) + 1;
    for (int k = 0; k <= steps; ++k) {
      const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(k) / steps);
      const int x0 = static_cast<int>(std::floor(p.x())), y0 = static_cast<int>(std::floor(p.y()));
      for (int y = y0; y <= y0 + 1; ++y)
        for (int x = x0; x <= x0 + 1; ++x) mark(x, y);
    }
  }
  dirichletCount_ = static_cast<int>(std::count(dirichlet_.begin(), dirichlet_.end(), 1));
  averaged_ = true;
}

Eigen::SparseMatrix<double> GeodesicSolver::Impl::dirichletSystem(
    const Eigen::SparseMatrix<double>& a1) const {
  // A1 with the rows and columns of held texels reduced to their diagonal: same pattern, SPD.
  Eigen::SparseMatrix<double> a = a1;
  for (int j = 0; j < a.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, j); it; ++it)
      if ((dirichlet_[static_cast<size_t>(it.row())] || dirichlet_[static_cast<size_t>(j)]) &&
          it.row() != j)
        it.valueRef() = 0.0;
  return a;
}

void GeodesicSolver::Impl::resetIterates() {
  const int n = domain_->unknowns();
  heatSettled_ = false;
  heatResidual_ = std::numeric_limits<double>::infinity();
  heatChanged_ = true;
  u_ = Eigen::MatrixXd::Zero(n, 1);
  // The Dirichlet diffusion and the mean exist only when averaged (diffused()); a one-shot
  // solve makes the distance step's vectors only after the heat solve.
  const int dirichletRows = averaged_ ? n : 0, distanceRows = oneShot_ ? 0 : n;
  uDirichlet_ = Eigen::MatrixXd::Zero(dirichletRows, 1);
  heat_ = Eigen::MatrixXd::Zero(dirichletRows, 1);
  divergence_ = Eigen::MatrixXd::Zero(distanceRows, 1);
  y_ = Eigen::MatrixXd::Zero(distanceRows, 1);
  distances_ = Eigen::VectorXd::Zero(distanceRows);
}

void GeodesicSolver::Impl::setAlpha(double alpha) {
  GeodesicOptions next = options_;
  next.alpha = alpha;
  next.validate();
  options_ = next;
  if (dirichletSolver_) dirichletSolver_->update(dirichletSystem(formHeatSystem()));
  diffusionSolver_->update(heatSum(domain_->operators(), alpha));
  resetIterates();
}

void GeodesicSolver::Impl::setSources(std::span<const GeodesicSource> sources) {
  if (sources.empty()) throw InvalidInputError("geodesic distances need at least one source");
  std::vector<ResolvedSource> resolved;
  std::vector<std::vector<fem::TexelWeight>> weights;
  Eigen::MatrixXd impulse = Eigen::MatrixXd::Zero(domain_->unknowns(), 1);
  for (const GeodesicSource& source : sources) {
    resolved.push_back(resolveSource(*domain_, source));
    // A unit impulse on every sheet through the source: at a non-manifold vertex the sheets
    // share no texel, and heat put on one of them would never reach the others.
    weights.emplace_back();
    for (const fem::SurfacePoint& sheet : resolved.back().sheets)
      for (const fem::TexelWeight& w : domain_->operators().basis().evaluate(sheet))
        weights.back().push_back(w);
    if (weights.back().empty())
      throw InvalidInputError("no texel basis function covers the source at UV (" +
                              std::to_string(resolved.back().uv.x()) + ", " +
                              std::to_string(resolved.back().uv.y()) + ")");
    for (const fem::TexelWeight& w : weights.back()) impulse(w.unknown, 0) += w.weight;
  }
  requireReachInImage(weights, resolved);
  sources_ = std::move(resolved);
  sourceWeights_ = std::move(weights);
  impulse_ = std::move(impulse);
  if (averaged_) {
    impulseDirichlet_ = impulse_;
    for (size_t u = 0; u < dirichlet_.size(); ++u)
      if (dirichlet_[u]) impulseDirichlet_(static_cast<Eigen::Index>(u), 0) = 0.0;
  }
  collectNearField();
  findReachable();
  resetIterates();
}

void GeodesicSolver::Impl::labelComponents(const Eigen::SparseMatrix<double>& pattern) {
  const int n = static_cast<int>(pattern.outerSize());
  component_.assign(static_cast<size_t>(n), -1);
  componentCount_ = 0;
  const int* outer = pattern.outerIndexPtr();
  const int* inner = pattern.innerIndexPtr();
  std::vector<int32_t> queue;
  for (int seed = 0; seed < n; ++seed) {
    if (component_[static_cast<size_t>(seed)] >= 0) continue;
    component_[static_cast<size_t>(seed)] = componentCount_;
    queue.assign(1, seed);
    for (size_t head = 0; head < queue.size(); ++head)
      for (int k = outer[queue[head]]; k < outer[queue[head] + 1]; ++k)
        if (component_[static_cast<size_t>(inner[k])] < 0) {
          component_[static_cast<size_t>(inner[k])] = componentCount_;
          queue.push_back(inner[k]);
        }
    ++componentCount_;
  }
}

void GeodesicSolver::Impl::findReachable() {
  std::vector<uint8_t> reached(static_cast<size_t>(componentCount_), 0);
  for (const auto& weights : sourceWeights_)
    for (const fem::TexelWeight& w : weights)
      reached[static_cast<size_t>(component_[static_cast<size_t>(w.unknown)])] = 1;
  reachable_.resize(component_.size());
  for (size_t u = 0; u < component_.size(); ++u)
    reachable_[u] = reached[static_cast<size_t>(component_[u])];
}

void GeodesicSolver::Impl::requireReachInImage(
    const std::vector<std::vector<fem::TexelWeight>>& weights,
    const std::vector<ResolvedSource>& sources) const {
  std::vector<uint8_t> reached(static_cast<size_t>(componentCount_), 0);
  for (const auto& source : weights)
    for (const fem::TexelWeight& w : source)
      reached[static_cast<size_t>(component_[static_cast<size_t>(w.unknown)])] = 1;
  const TexelGrid& grid = domain_->grid();
  for (size_t u = 0; u < component_.size(); ++u) {
    const int texel = grid.texelOfUnknown[u];
    if (reached[static_cast<size_t>(component_[u])] &&
        grid.inImage(texel % grid.nx, texel / grid.nx))
      return;
  }
  std::string where;
  for (const ResolvedSource& s : sources)
    where += (where.empty() ? "UV (" : ", (") + std::to_string(s.uv.x()) + ", " +
             std::to_string(s.uv.y()) + ")";
  throw InvalidInputError("no texel inside the image is reached from the geodesic source(s) at " +
                          where +
                          ": the parts of the surface holding them have their UVs outside "
                          "[0, 1]^2, so every distance in the output would be +inf; pick a "
                          "source on a part inside the image");
}

void GeodesicSolver::Impl::collectNearField() {
  nearField_.clear();
  if (options_.offset != GeodesicOffset::NearField) return;
  const TexturedMesh& mesh = domain_->mesh();
  const fem::TexelBasis& basis = domain_->operators().basis();
  const TexelGrid& grid = domain_->grid();
  const auto& metric = domain_->operators().metric();
  std::vector<double> inner, outer;  // model units
  for (const ResolvedSource& source : sources_) {
    const double texel =
        std::sqrt(eigenvalues(metric[static_cast<size_t>(source.point.face)]).second) * scale_;
    inner.push_back(kNearFieldInner * texel);
    outer.push_back(kNearFieldOuter * texel);
  }
  // Interior texels whose centres lie in faces within `outer` of a source (breadth-first over
  // faces sharing a 3-D vertex, so the search crosses seams), with their 3-D positions.
  std::vector<std::pair<int32_t, Eigen::Vector3d>> candidates;
  std::vector<int32_t> stamp(mesh.triangles.size(), -1);
  std::vector<int32_t> queue;
  for (size_t s = 0; s < sources_.size(); ++s) {
    const Eigen::Vector3d& centre = sources_[s].position;
    queue.assign(1, sources_[s].point.face);
    stamp[static_cast<size_t>(queue[0])] = static_cast<int32_t>(s);
    for (size_t head = 0; head < queue.size(); ++head) {
      const int f = queue[head];
      const Triangle& tri = mesh.triangles[static_cast<size_t>(f)];
      const Eigen::Vector3d &p0 = mesh.positions[tri[0]], &p1 = mesh.positions[tri[1]],
                            &p2 = mesh.positions[tri[2]];
      const Eigen::Vector3d b = closestBarycentric(centre, p0, p1, p2);
      if ((b[0] * p0 + b[1] * p1 + b[2] * p2 - centre).norm() > outer[s]) continue;
      for (int32_t v : tri)
        for (int32_t k = vertexFaceBegin_[static_cast<size_t>(v)];
             k < vertexFaceBegin_[static_cast<size_t>(v) + 1]; ++k) {
          const int32_t g = vertexFaces_[static_cast<size_t>(k)];
          if (stamp[static_cast<size_t>(g)] == static_cast<int32_t>(s)) continue;
          stamp[static_cast<size_t>(g)] = static_cast<int32_t>(s);
          queue.push_back(g);
        }
      if (!basis.faceValid(f)) continue;
      // Affine map grid -> 3-D of the face; texel centres within `outer` lie in an ellipse around
      // the grid point nearest (in 3-D) to the source.
      const auto& c = basis.faceCorners(f);
      Eigen::Matrix2d e;
      e.col(0) = c[1] - c[0];
      e.col(1) = c[2] - c[0];
      const Eigen::Matrix2d eInv = e.inverse();
      Eigen::Matrix<double, 3, 2> edges;
      edges.col(0) = p1 - p0;
      edges.col(1) = p2 - p0;
      const Eigen::Matrix<double, 3, 2> jacobian = edges * eInv;
      const Eigen::Matrix2d g = jacobian.transpose() * jacobian;
      const double smallest = eigenvalues(g).first;
      if (!(smallest > 0.0)) continue;
      const Eigen::Vector2d nearest = c[0] + g.inverse() * (jacobian.transpose() * (centre - p0));
      const double radius = outer[s] / std::sqrt(smallest);
      const Eigen::Vector2d reach = Eigen::Vector2d::Constant(radius);
      const Eigen::Vector2d lo = c[0].cwiseMin(c[1]).cwiseMin(c[2]).cwiseMax(nearest - reach);
      const Eigen::Vector2d hi = c[0].cwiseMax(c[1]).cwiseMax(c[2]).cwiseMin(nearest + reach);
      const int x0 = std::max(0, static_cast<int>(std::ceil(lo.x())));
      const int y0 = std::max(0, static_cast<int>(std::ceil(lo.y())));
      const int x1 = std::min(grid.nx - 1, static_cast<int>(std::floor(hi.x())));
      const int y1 = std::min(grid.ny - 1, static_cast<int>(std::floor(hi.y())));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const int texel = grid.texelIndex(x, y);
          if (grid.texelClass[static_cast<size_t>(texel)] != TexelClass::Interior) continue;
          const Eigen::Vector2d st = eInv * (Eigen::Vector2d(x, y) - c[0]);
          if (st.minCoeff() < -kInsideTolerance || st.sum() > 1.0 + kInsideTolerance) continue;
          candidates.emplace_back(grid.unknownOfTexel[static_cast<size_t>(texel)], p0 + edges * st);
        }
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  candidates.erase(std::unique(candidates.begin(), candidates.end(),
                               [](const auto& a, const auto& b) { return a.first == b.first; }),
                   candidates.end());
  // Keep a texel if it lies in the annulus of its nearest source.
  for (const auto& [unknown, position] : candidates) {
    size_t nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    for (size_t s = 0; s < sources_.size(); ++s) {
      const double d = (position - sources_[s].position).norm();
      if (d < best) {
        best = d;
        nearest = s;
      }
    }
    if (best >= inner[nearest] && best <= outer[nearest])
      nearField_.push_back({unknown, static_cast<int32_t>(nearest), best / scale_});
  }
  std::stable_sort(
      nearField_.begin(), nearField_.end(),
      [](const NearFieldTexel& a, const NearFieldTexel& b) { return a.source < b.source; });
}

std::vector<double> GeodesicSolver::Impl::offsets() const {
  // Each component of A2's support graph has its own constant. Per source and component: median
  // of y - chord over its near-field texels there (the median shrugs off texels across a crease,
  // where chord < geodesic), else the value at the source; then the mean over the sources.
  std::vector<double> total(static_cast<size_t>(componentCount_), 0.0);
  std::vector<int> count(static_cast<size_t>(componentCount_), 0);
  std::vector<std::pair<int32_t, double>> differences;  // (component, y - chord)
  std::vector<double> value, weight, group;
  auto texel = nearField_.begin();
  for (size_t s = 0; s < sources_.size(); ++s) {
    differences.clear();
    for (; texel != nearField_.end() && texel->source == static_cast<int32_t>(s); ++texel)
      differences.emplace_back(component_[static_cast<size_t>(texel->unknown)],
                               y_(texel->unknown, 0) - texel->distance);
    std::sort(differences.begin(), differences.end());
    value.assign(total.size(), 0.0);
    weight.assign(total.size(), 0.0);
    for (const fem::TexelWeight& w : sourceWeights_[s]) {
      const auto c = static_cast<size_t>(component_[static_cast<size_t>(w.unknown)]);
      value[c] += w.weight * y_(w.unknown, 0);
      weight[c] += w.weight;
    }
    for (size_t c = 0; c < total.size(); ++c) {
      if (!(weight[c] > 0.0)) continue;
      const auto lo = std::lower_bound(differences.begin(), differences.end(),
                                       std::make_pair(static_cast<int32_t>(c), -kInfinity));
      const auto hi = std::lower_bound(lo, differences.end(),
                                       std::make_pair(static_cast<int32_t>(c + 1), -kInfinity));
      group.clear();
      for (auto it = lo; it != hi; ++it) group.push_back(it->second);
      if (static_cast<int>(group.size()) >= kMinNearFieldTexels) {
        const auto middle = group.begin() + static_cast<std::ptrdiff_t>(group.size() / 2);
        std::nth_element(group.begin(), middle, group.end());
        total[c] += *middle;
      } else {
        total[c] += value[c] / weight[c];
      }
      ++count[c];
    }
  }
  for (size_t c = 0; c < total.size(); ++c)
    if (count[c] > 0) total[c] /= count[c];
  return total;
}

void GeodesicSolver::Impl::requireSources() const {
  if (sources_.empty())
    throw InvalidInputError("GeodesicSolver: call setSources before update or solve");
}

void GeodesicSolver::Impl::diffusionStep(bool full, const ProgressCallback& progress) {
  const auto start = Clock::now();
  timings_.diffusion = 0.0;
  timings_.divergence = 0.0;
  if (!full && heatSettled_) return;  // u, and so the divergence, stay as they are
  diffusionReport_ =
      full ? diffusionSolver_->solve(impulse_, u_, renameStage(progress, "heat solve"))
           : diffusionSolver_->refine(impulse_, u_, true);
  double residual = lastResidual(diffusionReport_);
  if (dirichletSolver_) {
    const SolveReport report =
        full ? dirichletSolver_->solve(impulseDirichlet_, uDirichlet_,
                                       renameStage(progress, "dirichlet heat solve"))
             : dirichletSolver_->refine(impulseDirichlet_, uDirichlet_, true);
    residual = std::max(residual, lastResidual(report));
    heat_ = 0.5 * (u_ + uDirichlet_);
  }
  heatChanged_ = true;
  // NaN (no residual) never settles.
  if (!full) {
    heatSettled_ = residual <= kHeatSettledCeiling && residual >= kHeatStallRatio * heatResidual_;
    heatResidual_ = residual;
  }
  timings_.diffusion = secondsSince(start);
}

void GeodesicSolver::Impl::computeDivergence() {
  if (!heatChanged_) return;
  const auto start = Clock::now();
  gradients_->divergence(diffused().data(), divergence_.data(), divergence_.rows());
  heatChanged_ = false;
  timings_.divergence = secondsSince(start);
}

void GeodesicSolver::Impl::distanceStep(bool full, const ProgressCallback& progress) {
  computeDivergence();
  const auto start = Clock::now();
  distanceReport_ =
      full ? distanceSolver_->solve(divergence_, y_, renameStage(progress, "distance solve"))
           : distanceSolver_->refine(divergence_, y_, false);
  // y moves by its offset every time, so its constant part stays the size of the distances. With
  // float V-cycles (refine), S's float rounding perturbs its null space (the constants) by far
  // more than eps M: a drifting constant in y would leak into the distances.
  const std::vector<double> shift = offsets();
  gradients_->arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<Eigen::Index>(0, y_.rows(), kGeodesicUnknownsPerTask),
        [&](const tbb::blocked_range<Eigen::Index>& range) {
          for (Eigen::Index u = range.begin(); u != range.end(); ++u) {
            y_(u, 0) -= shift[static_cast<size_t>(component_[static_cast<size_t>(u)])];
            distances_[u] = reachable_[static_cast<size_t>(u)] ? y_(u, 0) * scale_ : kInfinity;
          }
        });
  });
  timings_.distance = secondsSince(start);
}

void GeodesicSolver::Impl::update() {
  requireSources();
  diffusionStep(false);
  distanceStep(false);
}

double GeodesicSolver::Impl::residual() const {
  requireSources();
  double worst = diffusionSolver_->relativeResidual(impulse_, u_);
  if (dirichletSolver_)
    worst = std::max(worst, dirichletSolver_->relativeResidual(impulseDirichlet_, uDirichlet_));
  return std::max(worst, distanceSolver_->relativeResidual(divergence_, y_));
}

void GeodesicSolver::Impl::solve(const ProgressCallback& progress) {
  requireSources();
  diffusionStep(true, progress);
  distanceStep(true, progress);
}

void GeodesicSolver::Impl::solveOnce(const ProgressCallback& progress) {
  requireSources();
  diffusionStep(true, progress);
  diffusionSolver_.reset();
  dirichletSolver_.reset();
  impulse_ = impulseDirichlet_ = Eigen::MatrixXd();
  auto start = Clock::now();
  makeGradients();
  timings_.setup += secondsSince(start);
  const int n = domain_->unknowns();
  divergence_ = Eigen::MatrixXd::Zero(n, 1);
  computeDivergence();
  u_ = uDirichlet_ = heat_ = Eigen::MatrixXd();
  start = Clock::now();
  Eigen::SparseMatrix<double> ghost = gradients_->stabiliser(n);
  gradients_->releaseSamples();  // the arena stays for distanceStep
  setUpDistance(std::move(ghost), progress);
  timings_.setup += secondsSince(start);
  y_ = Eigen::MatrixXd::Zero(n, 1);
  distances_ = Eigen::VectorXd::Zero(n);
  distanceStep(true, progress);
}

GeodesicSolver::GeodesicSolver(const TexelDomain& domain, const GeodesicOptions& options,
                               const ProgressCallback& progress)
    : impl_(std::make_unique<Impl>(domain, options, progress)) {}
GeodesicSolver::~GeodesicSolver() = default;
GeodesicSolver::GeodesicSolver(GeodesicSolver&&) noexcept = default;
GeodesicSolver& GeodesicSolver::operator=(GeodesicSolver&&) noexcept = default;

void GeodesicSolver::setAlpha(double alpha) {
  impl_->setAlpha(alpha);
}
void GeodesicSolver::setSources(std::span<const GeodesicSource> sources) {
  impl_->setSources(sources);
}
void GeodesicSolver::setSource(const GeodesicSource& source) {
  impl_->setSources({&source, 1});
}
void GeodesicSolver::update() {
  impl_->update();
}
bool GeodesicSolver::heatSettled() const {
  return impl_->heatSettled_;
}
double GeodesicSolver::residual() const {
  return impl_->residual();
}
void GeodesicSolver::solve(const ProgressCallback& progress) {
  impl_->solve(progress);
}
const Eigen::VectorXd& GeodesicSolver::distances() const {
  return impl_->distances_;
}
const Eigen::MatrixXd& GeodesicSolver::diffused() const {
  return impl_->diffused();
}
const std::vector<uint8_t>& GeodesicSolver::reachable() const {
  return impl_->reachable_;
}
int GeodesicSolver::dirichletTexels() const {
  return impl_->dirichletCount_;
}
double GeodesicSolver::unitScale() const {
  return impl_->scale_;
}
const std::vector<ResolvedSource>& GeodesicSolver::sources() const {
  return impl_->sources_;
}
const SolveReport& GeodesicSolver::diffusionReport() const {
  return impl_->diffusionReport_;
}
const SolveReport& GeodesicSolver::distanceReport() const {
  return impl_->distanceReport_;
}
const GeodesicTimings& GeodesicSolver::timings() const {
  return impl_->timings_;
}
const GeodesicOptions& GeodesicSolver::options() const {
  return impl_->options_;
}

GeodesicResult geodesicDistance(const TexelDomain& domain, std::span<const GeodesicSource> sources,
                                const GeodesicOptions& options, const ProgressCallback& progress) {
  GeodesicSolver::Impl solver(domain, options, progress, true);
  solver.setSources(sources);
  solver.solveOnce(progress);
  GeodesicResult result;
  result.distances = std::move(solver.distances_);
  result.sources = std::move(solver.sources_);
  result.diffusionReport = std::move(solver.diffusionReport_);
  result.distanceReport = std::move(solver.distanceReport_);
  result.timings = solver.timings_;
  // Farthest texel among those whose centre lies on M (gutter texels extrapolate past the
  // boundary); any reachable texel if no centre does (charts narrower than a texel).
  const TexelGrid& grid = domain.grid();
  const std::vector<int32_t> faces = texelCentreFaces(domain);
  Eigen::Index best = -1;
  for (int pass = 0; pass < 2 && best < 0; ++pass)
    for (Eigen::Index u = 0; u < result.distances.size(); ++u) {
      if (!std::isfinite(result.distances[u])) continue;
      if (pass == 0 && faces[static_cast<size_t>(u)] < 0) continue;
      if (best < 0 || result.distances[u] > result.distances[best]) best = u;
    }
  for (Eigen::Index u = 0; u < result.distances.size(); ++u)
    if (!std::isfinite(result.distances[u])) ++result.unreachableTexels;
  result.maxDistance = result.distances[best];  // sources' texels are always reachable
  result.farthestUnknown = static_cast<int32_t>(best);
  const int texel = grid.texelOfUnknown[static_cast<size_t>(best)];
  const Eigen::Vector2d centre(texel % grid.nx, texel / grid.nx);
  result.farthestUv = grid.toUv(centre);
  const int32_t face = faces[static_cast<size_t>(best)];
  result.farthestPosition =
      face >= 0 ? domain.operators().basis().position({face, centre})
                : resolveSource(domain, GeodesicSource::atUv(result.farthestUv)).position;
  return result;
}

}  // namespace texgrad
