// Heat-method geodesics (paper Sec. 7.3): one-point gradient samples of the texel basis for the
// normalised-gradient divergence, the two screened-Poisson solves and the distance offset
// (sources are snapped onto M in geodesic_source.cpp).
#include "texgrad/apps/geodesic.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

#include "apps/closest_point.h"
#include "texgrad/apps/surface_normals.h"
#include "texgrad/core/error.h"

namespace texgrad {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Faces per parallel task when building gradient samples (fixed: results do not depend on
/// threads).
constexpr int kFacesPerTask = 64;
/// Unknowns per task in per-unknown loops.
constexpr Eigen::Index kUnknownsPerTask = 1 << 14;
/// NearField offset: annulus of chord distances around a source, in texel sizes of its face.
constexpr double kNearFieldInner = 2.0;
constexpr double kNearFieldOuter = 4.0;
/// A source with fewer near-field texels than this falls back to its own value.
constexpr int kMinNearFieldTexels = 4;
/// Barycentric tolerance for "texel centre inside a face" (on-edge centres count for both faces).
constexpr double kInsideTolerance = 1e-9;
/// Step (texels) when walking open boundary edges to find the texels their footprints cross.
constexpr double kBoundaryStep = 0.25;

/// Eigenvalues (smaller, larger) of a symmetric 2x2 matrix.
std::pair<double, double> eigenvalues(const Eigen::Matrix2d& m) {
  const double mean = 0.5 * (m(0, 0) + m(1, 1));
  const double half = 0.5 * (m(0, 0) - m(1, 1));
  const double radius = std::sqrt(half * half + m(0, 1) * m(0, 1));
  return {mean - radius, mean + radius};
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
  return options;
}

/// One-point quadrature samples of the texel-basis gradients (paper Sec. 7.3): one per plain
/// piece T ∩ cell (at its centroid) and one per quadratic element of seam pieces (at its
/// centroid). div_h(omega)_t = sum_q weight_q dphi_t(q) . X_q with X_q = g^-1 omega_q.
struct GeodesicSolver::Gradients {
  /// Piece with exactly bilinear basis: four cell texels, centroid in cell-local coordinates.
  /// Compact (the divergence streams every sample once per update); the metric comes from the
  /// face.
  struct CellSample {
    std::array<int32_t, 4> texels;  ///< order (a,b), (a+1,b), (a,b+1), (a+1,b+1); -1 if absent
    int32_t cellX;                  ///< a
    float fx, fy;                   ///< centroid, cell-local
    float area;                     ///< area in texel units
    int32_t face;                   ///< index into faceMetrics
  };
  /// Per face: sqrt|g| and g^-1.
  struct FaceMetric {
    double root = 0.0, hxx = 0.0, hxy = 0.0, hyy = 0.0;
  };
  /// Quadratic element of a seam piece: gradients of its local texels at the centroid.
  struct SeamSample {
    int32_t begin, end;  ///< range in seamTexels / seamGradients
    double weight, hxx, hxy, hyy;
  };

  std::vector<CellSample> cells;  ///< sorted by cell row, then cell column (stable)
  std::vector<FaceMetric> faceMetrics;
  std::vector<int64_t> rowBegin;  ///< cells of row b: [rowBegin[b + 1], rowBegin[b + 2]), b >= -1
  std::vector<SeamSample> seams;
  std::vector<int32_t> seamTexels;
  std::vector<Eigen::Vector2d> seamGradients;
  std::vector<Eigen::Vector2d> seamDirections;  ///< per seam sample: X of the last divergence
  std::vector<int32_t> seamTargets;             ///< the distinct texels of seamTexels, ascending
  std::vector<int32_t> seamTargetOfEntry;  ///< per seam entry: index of its texel in seamTargets
  std::vector<double> seamSums;            ///< per seam target: sum of the last divergence
  tbb::task_arena arena;

  Gradients(const TexelDomain& domain, int threads)
      : arena(threads > 0 ? threads : tbb::task_arena::automatic) {
    arena.execute([&] { build(domain); });
  }

  void build(const TexelDomain& domain);
  /// Sets div (n values) to div_h(-du/|du|) of the function with coefficients u (one-point
  /// quadrature).
  void divergence(const double* u, double* div, Eigen::Index n);
  /// The cell-sample part of divergence for the samples [first, last) of one cell row.
  static void addRowDivergence(const CellSample* first, const CellSample* last,
                               const FaceMetric* metrics, const double* u, double* div);
};

void GeodesicSolver::Gradients::build(const TexelDomain& domain) {
  const fem::TexelBasis& basis = domain.operators().basis();
  const auto& metric = domain.operators().metric();
  const int faces = basis.faceCount();
  const int chunks = (faces + kFacesPerTask - 1) / kFacesPerTask;
  faceMetrics.assign(static_cast<size_t>(faces), FaceMetric{});
  struct Chunk {
    std::vector<CellSample> cells;
    std::vector<int32_t> cellRows;  ///< cell row b of each cell sample (for the colour bands)
    std::vector<SeamSample> seams;
    std::vector<int32_t> texels;
    std::vector<Eigen::Vector2d> gradients;
  };
  std::vector<Chunk> out(static_cast<size_t>(chunks));
  tbb::parallel_for(0, chunks, [&](int c) {
    Chunk& chunk = out[static_cast<size_t>(c)];
    FaceClip clip;
    fem::PieceBasis pb;
    for (int f = c * kFacesPerTask; f < std::min(faces, (c + 1) * kFacesPerTask); ++f) {
      if (!basis.faceValid(f)) continue;
      const Eigen::Matrix2d& g = metric[static_cast<size_t>(f)];
      const double root = std::sqrt(g.determinant());
      const Eigen::Matrix2d h = g.inverse();
      faceMetrics[static_cast<size_t>(f)] = {root, h(0, 0), h(0, 1), h(1, 1)};
      basis.clipFace(f, clip);
      for (const auto& piece : clip.pieces) {
        const auto poly = clip.polygon(piece);
        if (basis.isPlain(f, poly)) {
          const Eigen::Vector2d origin(piece.cellX, piece.cellY);
          double area = 0.0;
          Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
          for (size_t i = 0; i < poly.size(); ++i) {
            const Eigen::Vector2d p = poly[i].p - origin,
                                  q = poly[(i + 1) % poly.size()].p - origin;
            const double cross = p.x() * q.y() - p.y() * q.x();
            area += cross;
            centroid += cross * (p + q);
          }
          if (!(area > 0.0)) continue;
          centroid /= 3.0 * area;
          area *= 0.5;
          chunk.cells.push_back({basis.cellTexels(piece.cellX, piece.cellY), piece.cellX,
                                 static_cast<float>(centroid.x()), static_cast<float>(centroid.y()),
                                 static_cast<float>(area), f});
          chunk.cellRows.push_back(piece.cellY);
          continue;
        }
        basis.buildPieceBasis(f, poly, pb);
        for (size_t e = 0; e < pb.elements.size(); ++e) {
          const auto& t = pb.elements[e];
          Eigen::Matrix2d m;
          m.col(0) = t[1] - t[0];
          m.col(1) = t[2] - t[0];
          const double area = 0.5 * m.determinant();
          if (!(area > 0.0)) continue;
          const Eigen::Matrix2d inv = m.inverse();
          const std::array<Eigen::Vector2d, 3> bg{-(inv.row(0) + inv.row(1)).transpose(),
                                                  inv.row(0).transpose(), inv.row(1).transpose()};
          // Quadratic shape gradients at the centroid (b = 1/3): corners (4 b_i - 1) grad b_i,
          // midpoints of (i, j) 4 (b_j grad b_i + b_i grad b_j).
          Eigen::Matrix<double, 6, 2> dshape;
          for (int i = 0; i < 3; ++i) dshape.row(i) = bg[i].transpose() / 3.0;
          dshape.row(3) = (4.0 / 3.0) * (bg[0] + bg[1]).transpose();
          dshape.row(4) = (4.0 / 3.0) * (bg[1] + bg[2]).transpose();
          dshape.row(5) = (4.0 / 3.0) * (bg[2] + bg[0]).transpose();
          const auto coefficients = pb.coefficients.middleRows(static_cast<Eigen::Index>(6 * e), 6);
          const Eigen::MatrixXd grads = coefficients.transpose() * dshape;  // k x 2
          SeamSample s{
              static_cast<int32_t>(chunk.texels.size()), 0, area * root, h(0, 0), h(0, 1), h(1, 1)};
          for (size_t k = 0; k < pb.texels.size(); ++k) {
            if (pb.texels[k] < 0) continue;
            chunk.texels.push_back(pb.texels[k]);
            chunk.gradients.emplace_back(grads.row(static_cast<Eigen::Index>(k)).transpose());
          }
          s.end = static_cast<int32_t>(chunk.texels.size());
          chunk.seams.push_back(s);
        }
      }
    }
  });
  const TexelGrid& grid = domain.grid();
  rowBegin.assign(static_cast<size_t>(grid.ny) + 2, 0);
  for (const Chunk& chunk : out)
    for (int32_t row : chunk.cellRows) ++rowBegin[static_cast<size_t>(row) + 2];
  for (size_t r = 1; r < rowBegin.size(); ++r) rowBegin[r] += rowBegin[r - 1];
  std::vector<int64_t> cursor(rowBegin.begin(), rowBegin.end() - 1);
  cells.resize(static_cast<size_t>(rowBegin.back()));
  for (Chunk& chunk : out) {
    for (size_t i = 0; i < chunk.cells.size(); ++i)
      cells[static_cast<size_t>(cursor[static_cast<size_t>(chunk.cellRows[i]) + 1]++)] =
          chunk.cells[i];
    const auto base = static_cast<int32_t>(seamTexels.size());
    for (SeamSample s : chunk.seams) {
      s.begin += base;
      s.end += base;
      seams.push_back(s);
    }
    seamTexels.insert(seamTexels.end(), chunk.texels.begin(), chunk.texels.end());
    seamGradients.insert(seamGradients.end(), chunk.gradients.begin(), chunk.gradients.end());
    chunk = Chunk();
  }
  tbb::parallel_for(size_t(0), rowBegin.size() - 1, [&](size_t row) {
    std::stable_sort(cells.begin() + rowBegin[row], cells.begin() + rowBegin[row + 1],
                     [](const CellSample& a, const CellSample& b) { return a.cellX < b.cellX; });
  });
  seamTargets = seamTexels;
  std::sort(seamTargets.begin(), seamTargets.end());
  seamTargets.erase(std::unique(seamTargets.begin(), seamTargets.end()), seamTargets.end());
  seamTargetOfEntry.resize(seamTexels.size());
  for (size_t k = 0; k < seamTexels.size(); ++k)
    seamTargetOfEntry[k] = static_cast<int32_t>(
        std::lower_bound(seamTargets.begin(), seamTargets.end(), seamTexels[k]) -
        seamTargets.begin());
  seamSums.assign(seamTargets.size(), 0.0);
  seamDirections.resize(seams.size());
}

namespace {

/// X = -g^-1 du / |du|_{g^-1} (unit in g) times `weight`: the direction of steepest descent of
/// u; zero where du = 0.
inline Eigen::Vector2d descentDirection(double gx, double gy, double hxx, double hxy, double hyy,
                                        double weight) {
  const double zx = hxx * gx + hxy * gy, zy = hxy * gx + hyy * gy;
  const double norm2 = gx * zx + gy * zy;
  if (!(norm2 > 0.0) || !std::isfinite(norm2)) return Eigen::Vector2d(0.0, 0.0);
  const double s = -weight / std::sqrt(norm2);
  return Eigen::Vector2d(s * zx, s * zy);
}

}  // namespace

void GeodesicSolver::Gradients::addRowDivergence(const CellSample* first, const CellSample* last,
                                                 const FaceMetric* metrics, const double* u,
                                                 double* div) {
  // The samples of one cell row come by column, so the sums for the two texel columns of the
  // current cell stay in registers and each texel is written once per row: adding every sample
  // straight into div chains each addition behind the previous sample's store to that texel.
  std::array<int32_t, 4> texels{-1, -1, -1, -1};  // of the current cell
  std::array<double, 4> sum{};                    // same order as texels
  int32_t column = std::numeric_limits<int32_t>::min();
  auto flush = [&](int k) {
    if (texels[k] >= 0) div[texels[k]] += sum[k];
  };
  for (const CellSample* s = first; s != last; ++s) {
    if (s->cellX != column) {
      const bool next = s->cellX == column + 1;
      flush(0);
      flush(2);
      if (!next) {
        flush(1);
        flush(3);
      }
      sum = {next ? sum[1] : 0.0, 0.0, next ? sum[3] : 0.0, 0.0};
      texels = s->texels;
      column = s->cellX;
    }
    std::array<double, 4> v{};
    for (int k = 0; k < 4; ++k) v[k] = texels[k] >= 0 ? u[texels[k]] : 0.0;
    const double fx = s->fx, fy = s->fy;
    const double gx = (1 - fy) * (v[1] - v[0]) + fy * (v[3] - v[2]);
    const double gy = (1 - fx) * (v[2] - v[0]) + fx * (v[3] - v[1]);
    const FaceMetric& m = metrics[s->face];
    const Eigen::Vector2d x = descentDirection(gx, gy, m.hxx, m.hxy, m.hyy, s->area * m.root);
    const double xx = x.x(), xy = x.y();
    sum[0] += -(1 - fy) * xx - (1 - fx) * xy;
    sum[1] += (1 - fy) * xx - fx * xy;
    sum[2] += -fy * xx + (1 - fx) * xy;
    sum[3] += fy * xx + fx * xy;
  }
  for (int k = 0; k < 4; ++k) flush(k);
}

void GeodesicSolver::Gradients::divergence(const double* u, double* div, Eigen::Index n) {
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, kUnknownsPerTask),
                      [&](const tbb::blocked_range<Eigen::Index>& range) {
                        std::fill(div + range.begin(), div + range.end(), 0.0);
                      });
    const int rows = static_cast<int>(rowBegin.size()) - 1;  // cell rows -1 .. ny - 1
    // Cell rows b and b + 2 touch disjoint texel rows, so each colour runs its rows in parallel;
    // every texel gets its contributions in the same order for any thread count.
    auto cellPart = [&] {
      for (int colour = 0; colour < 2; ++colour) {
        tbb::parallel_for(0, (rows + 1 - colour) / 2, [&](int half) {
          const size_t slot = static_cast<size_t>(2 * half + colour);
          addRowDivergence(cells.data() + rowBegin[slot], cells.data() + rowBegin[slot + 1],
                           faceMetrics.data(), u, div);
        });
      }
    };
    // Seam samples share texels in no fixed pattern: directions in parallel, then the sums in
    // entry order into a compact array per seam texel, alongside the cell part.
    auto seamPart = [&] {
      tbb::parallel_for(size_t(0), seams.size(), [&](size_t i) {
        const SeamSample& s = seams[i];
        Eigen::Vector2d grad = Eigen::Vector2d::Zero();
        for (int32_t k = s.begin; k < s.end; ++k) grad += u[seamTexels[k]] * seamGradients[k];
        seamDirections[i] = descentDirection(grad.x(), grad.y(), s.hxx, s.hxy, s.hyy, s.weight);
      });
      std::fill(seamSums.begin(), seamSums.end(), 0.0);
      for (size_t i = 0; i < seams.size(); ++i)
        for (int32_t k = seams[i].begin; k < seams[i].end; ++k)
          seamSums[static_cast<size_t>(seamTargetOfEntry[static_cast<size_t>(k)])] +=
              seamGradients[k].dot(seamDirections[i]);
    };
    tbb::parallel_invoke(cellPart, seamPart);
    tbb::parallel_for(size_t(0), seamTargets.size(),
                      [&](size_t j) { div[seamTargets[j]] += seamSums[j]; });
  });
}

GeodesicSolver::GeodesicSolver(const TexelDomain& domain, const GeodesicOptions& options)
    : domain_(&domain),
      options_([&] {
        options.validate();
        return options;
      }()),
      diffusionSolver_(domain.grid(), options.solver),
      distanceSolver_(domain.grid(), options.solver) {
  const auto start = Clock::now();
  const TexelOperators& ops = domain.operators();
  const double area = ops.report().metric.surfaceArea;
  if (!(area > 0.0)) throw InvalidInputError("the mesh has zero surface area; no distances exist");
  scale_ = std::sqrt(area);
  gradients_ = std::make_unique<Gradients>(domain, options_.solver.multigrid.threads);
  a1_ = options_.alpha * ops.mass() + ops.stiffness();
  a2_ = ops.stiffness() + kDistanceScreening * ops.mass();
  labelComponents();
  diffusionSolver_.initAndUpdate(a1_);
  distanceSolver_.initAndUpdate(a2_);
  if (options_.boundary == GeodesicBoundary::Average && !domain.atlas().openBoundary.empty())
    buildDirichlet();
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

GeodesicSolver::~GeodesicSolver() = default;
GeodesicSolver::GeodesicSolver(GeodesicSolver&&) noexcept = default;
GeodesicSolver& GeodesicSolver::operator=(GeodesicSolver&&) noexcept = default;

void GeodesicSolver::buildDirichlet() {
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
  dirichletSolver_ = std::make_unique<SystemSolver>(grid, options_.solver);
  dirichletSolver_->init(a1_);
  updateDirichlet();
}

void GeodesicSolver::updateDirichlet() {
  // A1 with the rows and columns of held texels reduced to their diagonal: same pattern, SPD.
  a1Dirichlet_ = a1_;
  for (int j = 0; j < a1Dirichlet_.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a1Dirichlet_, j); it; ++it)
      if ((dirichlet_[static_cast<size_t>(it.row())] || dirichlet_[static_cast<size_t>(j)]) &&
          it.row() != j)
        it.valueRef() = 0.0;
  dirichletSolver_->update(a1Dirichlet_);
}

void GeodesicSolver::resetIterates() {
  const int n = domain_->unknowns();
  u_ = Eigen::MatrixXd::Zero(n, 1);
  uDirichlet_ = Eigen::MatrixXd::Zero(n, 1);
  heat_ = Eigen::MatrixXd::Zero(n, 1);
  divergence_ = Eigen::MatrixXd::Zero(n, 1);
  y_ = Eigen::MatrixXd::Zero(n, 1);
  distances_ = Eigen::VectorXd::Zero(n);
}

void GeodesicSolver::setAlpha(double alpha) {
  GeodesicOptions next = options_;
  next.alpha = alpha;
  next.validate();
  options_ = next;
  const TexelOperators& ops = domain_->operators();
  a1_ = options_.alpha * ops.mass() + ops.stiffness();
  diffusionSolver_.update(a1_);
  if (dirichletSolver_) updateDirichlet();
  resetIterates();
}

void GeodesicSolver::setSources(std::span<const GeodesicSource> sources) {
  if (sources.empty()) throw InvalidInputError("geodesic distances need at least one source");
  std::vector<ResolvedSource> resolved;
  std::vector<std::vector<fem::TexelWeight>> weights;
  Eigen::MatrixXd impulse = Eigen::MatrixXd::Zero(domain_->unknowns(), 1);
  for (const GeodesicSource& source : sources) {
    resolved.push_back(resolveSource(*domain_, source));
    weights.push_back(domain_->operators().basis().evaluate(resolved.back().point));
    if (weights.back().empty())
      throw InvalidInputError("no texel basis function covers the source at UV (" +
                              std::to_string(resolved.back().uv.x()) + ", " +
                              std::to_string(resolved.back().uv.y()) + ")");
    for (const fem::TexelWeight& w : weights.back()) impulse(w.unknown, 0) += w.weight;
  }
  sources_ = std::move(resolved);
  sourceWeights_ = std::move(weights);
  impulse_ = std::move(impulse);
  impulseDirichlet_ = impulse_;
  for (size_t u = 0; u < dirichlet_.size(); ++u)
    if (dirichlet_[u]) impulseDirichlet_(static_cast<Eigen::Index>(u), 0) = 0.0;
  collectNearField();
  findReachable();
  resetIterates();
}

void GeodesicSolver::labelComponents() {
  const int n = static_cast<int>(a1_.outerSize());
  component_.assign(static_cast<size_t>(n), -1);
  componentCount_ = 0;
  const int* outer = a1_.outerIndexPtr();
  const int* inner = a1_.innerIndexPtr();
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

void GeodesicSolver::findReachable() {
  std::vector<uint8_t> reached(static_cast<size_t>(componentCount_), 0);
  for (const auto& weights : sourceWeights_)
    for (const fem::TexelWeight& w : weights)
      reached[static_cast<size_t>(component_[static_cast<size_t>(w.unknown)])] = 1;
  reachable_.resize(component_.size());
  for (size_t u = 0; u < component_.size(); ++u)
    reachable_[u] = reached[static_cast<size_t>(component_[u])];
}

void GeodesicSolver::collectNearField() {
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

double GeodesicSolver::offset() const {
  // Per source: median of y - chord over its near-field texels (the median shrugs off texels
  // across a crease, where chord < geodesic), else the value at the source; then the mean.
  double total = 0.0;
  std::vector<double> differences;
  auto texel = nearField_.begin();
  for (size_t s = 0; s < sources_.size(); ++s) {
    differences.clear();
    for (; texel != nearField_.end() && texel->source == static_cast<int32_t>(s); ++texel)
      differences.push_back(y_(texel->unknown, 0) - texel->distance);
    if (static_cast<int>(differences.size()) >= kMinNearFieldTexels) {
      const auto middle = differences.begin() + static_cast<std::ptrdiff_t>(differences.size() / 2);
      std::nth_element(differences.begin(), middle, differences.end());
      total += *middle;
      continue;
    }
    for (const fem::TexelWeight& w : sourceWeights_[s]) total += w.weight * y_(w.unknown, 0);
  }
  return total / static_cast<double>(sources_.size());
}

void GeodesicSolver::setSource(const GeodesicSource& source) {
  setSources({&source, 1});
}

void GeodesicSolver::requireSources() const {
  if (sources_.empty())
    throw InvalidInputError("GeodesicSolver: call setSources before update or solve");
}

void GeodesicSolver::diffusionStep(bool full) {
  const auto start = Clock::now();
  diffusionReport_ =
      full ? diffusionSolver_.solve(impulse_, u_) : diffusionSolver_.refine(impulse_, u_, false);
  if (dirichletSolver_) {
    if (full)
      dirichletSolver_->solve(impulseDirichlet_, uDirichlet_);
    else
      dirichletSolver_->refine(impulseDirichlet_, uDirichlet_, false);
    heat_ = 0.5 * (u_ + uDirichlet_);
  }
  timings_.diffusion = secondsSince(start);
}

void GeodesicSolver::distanceStep(bool full) {
  auto start = Clock::now();
  gradients_->divergence(diffused().data(), divergence_.data(), divergence_.rows());
  timings_.divergence = secondsSince(start);
  start = Clock::now();
  distanceReport_ = full ? distanceSolver_.solve(divergence_, y_)
                         : distanceSolver_.refine(divergence_, y_, false);
  // y moves by its offset every time, so its constant part stays the size of the distances. With
  // float V-cycles (refine), S's float rounding perturbs its null space (the constants) by far
  // more than eps M: a drifting constant in y would leak into the distances.
  const double shift = offset();
  const double infinity = std::numeric_limits<double>::infinity();
  gradients_->arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, y_.rows(), kUnknownsPerTask),
                      [&](const tbb::blocked_range<Eigen::Index>& range) {
                        for (Eigen::Index u = range.begin(); u != range.end(); ++u) {
                          y_(u, 0) -= shift;
                          distances_[u] =
                              reachable_[static_cast<size_t>(u)] ? y_(u, 0) * scale_ : infinity;
                        }
                      });
  });
  timings_.distance = secondsSince(start);
}

void GeodesicSolver::update() {
  requireSources();
  diffusionStep(false);
  distanceStep(false);
}

double GeodesicSolver::residual() const {
  requireSources();
  double worst = diffusionSolver_.relativeResidual(impulse_, u_);
  if (dirichletSolver_)
    worst = std::max(worst, dirichletSolver_->relativeResidual(impulseDirichlet_, uDirichlet_));
  return std::max(worst, distanceSolver_.relativeResidual(divergence_, y_));
}

void GeodesicSolver::solve() {
  requireSources();
  diffusionStep(true);
  distanceStep(true);
}

GeodesicResult geodesicDistance(const TexelDomain& domain, std::span<const GeodesicSource> sources,
                                const GeodesicOptions& options) {
  GeodesicSolver solver(domain, options);
  solver.setSources(sources);
  solver.solve();
  GeodesicResult result;
  result.distances = solver.distances();
  result.sources = solver.sources();
  result.diffusionReport = solver.diffusionReport();
  result.distanceReport = solver.distanceReport();
  result.timings = solver.timings();
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
