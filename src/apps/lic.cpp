// Line integral convolution (paper §7.4): anisotropic metric from a per-face field, screened
// diffusion of seeded noise under it, then gradient-domain sharpening with the immersion metric
// (as in the authors' reference implementation).
#include "texgrad/apps/lic.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"
#include "texgrad/fem/metric.h"

namespace texgrad {
namespace {

/// Most CG iterations per LIC solve (SolverSettings::maxIterations).
constexpr int kLicIterations = 600;
/// V-cycles per LIC solve when the multigrid kind is chosen instead (SolverSettings::cycles).
constexpr int kLicCycles = 30;
/// Relative residual LIC solves aim for with the iterative solvers.
constexpr double kLicTolerance = 1e-8;
/// Texels with a mass diagonal below this fraction of the mean get a pinning term (see
/// pinNegligibleTexels); real atlases have boundary texels down to 1e-17 of the mean.
constexpr double kNegligibleMass = 1e-10;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// SplitMix64 finaliser: a well-mixed 64-bit hash of its input.
uint64_t mix(uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/// Uniform value in [0, 1) from the top 53 bits of a hash.
double unitValue(uint64_t hash) {
  return static_cast<double>(hash >> 11) * 0x1.0p-53;
}

/// Fully saturated, full-value colour of hue h in [0, 1).
Eigen::Vector3d hueColour(double hue) {
  const double h6 = hue * 6.0;
  const int sector = std::min(5, static_cast<int>(h6));
  const double f = h6 - sector;
  switch (sector) {
    case 0:
      return {1.0, f, 0.0};
    case 1:
      return {1.0 - f, 1.0, 0.0};
    case 2:
      return {0.0, 1.0, f};
    case 3:
      return {0.0, 1.0 - f, 1.0};
    case 4:
      return {f, 0.0, 1.0};
    default:
      return {1.0, 0.0, 1.0 - f};
  }
}

/// Area of face f on the surface of metric m: sqrt(det m) times its texel-coordinate area.
double metricArea(const TexturedMesh& mesh, const TexelGrid& grid, const Eigen::Matrix2d& m,
                  int f) {
  return std::sqrt(std::max(0.0, m.determinant())) * std::abs(fem::gridArea(mesh, grid, f));
}

/// Adds a tiny diagonal term to the rows of texels whose basis function barely touches the
/// surface (`diagonal`, the mass matrix's, below kNegligibleMass times its mean): such rows are
/// numerically singular (rounding-level Cholesky pivots) and their values would be noise. Other
/// texels are not measurably affected.
void pinNegligibleTexels(const Eigen::VectorXd& diagonal, double scale, SparseMatrixd& system) {
  const double floor = kNegligibleMass * diagonal.mean();
  for (Eigen::Index t = 0; t < diagonal.size(); ++t)
    if (diagonal(t) < floor) system.coeffRef(t, t) += scale * floor;
}

void requirePositive(double value, const char* name) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw InvalidInputError(std::string(name) + " must be a positive number, got " +
                            std::to_string(value));
}

}  // namespace

SolverSettings defaultLicSolver() {
  SolverSettings settings;
  settings.kind = SolverKind::MultigridCg;
  settings.cycles = kLicCycles;
  settings.maxIterations = kLicIterations;
  settings.tolerance = kLicTolerance;
  return settings;
}

void LicOptions::validate() const {
  requirePositive(epsilon, "LIC epsilon");
  requirePositive(alpha, "LIC alpha");
  requirePositive(sharpenAlpha, "LIC sharpening alpha");
  if (!(sharpenBeta >= 0.0) || !std::isfinite(sharpenBeta))
    throw InvalidInputError("LIC sharpening beta must be a number >= 0, got " +
                            std::to_string(sharpenBeta));
  if (!(contrast >= 0.0) || !std::isfinite(contrast))
    throw InvalidInputError("LIC contrast must be a number >= 0, got " + std::to_string(contrast));
  if (channels != 1 && channels != 3)
    throw InvalidInputError("LIC noise must have 1 (grey) or 3 (colour) channels, got " +
                            std::to_string(channels));
  solver.validate();
}

std::vector<Eigen::Matrix2d> anisotropicMetric(const TexturedMesh& mesh, const TexelGrid& grid,
                                               const std::vector<Eigen::Matrix2d>& g,
                                               const std::vector<Eigen::Vector2d>& fieldTexel,
                                               double epsilon) {
  requirePositive(epsilon, "LIC epsilon");
  const int faces = static_cast<int>(mesh.faceCount());
  if (static_cast<int>(g.size()) != faces || static_cast<int>(fieldTexel.size()) != faces)
    throw InvalidInputError("anisotropicMetric: expected one metric and one vector per face (" +
                            std::to_string(faces) + "), got " + std::to_string(g.size()) + " and " +
                            std::to_string(fieldTexel.size()));
  // Area-weighted RMS g-length of the field, so epsilon is relative to a unit field.
  double weighted = 0.0, area = 0.0;
  for (int f = 0; f < faces; ++f) {
    const double a = metricArea(mesh, grid, g[f], f);
    weighted += a * fieldTexel[f].dot(g[f] * fieldTexel[f]);
    area += a;
  }
  if (!(weighted > 0.0) || !std::isfinite(weighted))
    throw InvalidInputError(
        "the vector field is zero on every face (or not finite), so LIC has no direction to "
        "follow; a principal-curvature field vanishes on planar meshes, use a field file there");
  const double rms = std::sqrt(weighted / area);

  std::vector<Eigen::Matrix2d> h(g);
  double hArea = 0.0;
  for (int f = 0; f < faces; ++f) {
    if (fem::gridArea(mesh, grid, f) == 0.0) continue;
    const Eigen::Vector2d gu = g[f] * (fieldTexel[f] / rms);
    // u⊥ = R g u / sqrt(det g) (R: rotation by 90 degrees) is g-orthogonal to u, same g-length.
    const Eigen::Vector2d perp = Eigen::Vector2d(-gu.y(), gu.x()) / std::sqrt(g[f].determinant());
    const Eigen::Vector2d form = g[f] * perp;  // the 1-form g(., u⊥)
    Eigen::Matrix2d m = form * form.transpose() + epsilon * g[f];
    m(0, 1) = m(1, 0) = 0.5 * (m(0, 1) + m(1, 0));
    h[f] = m;
    hArea += metricArea(mesh, grid, m, f);
  }
  for (int f = 0; f < faces; ++f)
    if (fem::gridArea(mesh, grid, f) != 0.0) h[f] /= hArea;  // unit area under h (paper §7)
  return h;
}

Eigen::MatrixXd licNoise(const TexelGrid& grid, int channels, uint64_t seed) {
  if (channels != 1 && channels != 3)
    throw InvalidInputError("LIC noise must have 1 or 3 channels, got " + std::to_string(channels));
  Eigen::MatrixXd noise(grid.unknownCount(), channels);
  const uint64_t seedHash = mix(seed);
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const int t = grid.texelOfUnknown[u];
    const auto i = static_cast<uint32_t>(t % grid.nx + grid.x0);
    const auto j = static_cast<uint32_t>(t / grid.nx + grid.y0);
    const double value = unitValue(mix(seedHash ^ mix((static_cast<uint64_t>(j) << 32) | i)));
    if (channels == 1)
      noise(u, 0) = value;
    else
      noise.row(u) = hueColour(value).transpose();
  }
  return noise;
}

struct LineIntegralConvolution::Impl {
  const TexelDomain& domain;
  LicOptions options;
  std::vector<Eigen::Matrix2d> metric;
  SparseMatrixd massH;      ///< M_h
  SparseMatrixd mass;       ///< M (immersion metric)
  SparseMatrixd stiffness;  ///< S (immersion metric)
  SystemSolver diffusion;
  std::optional<SystemSolver> sharpening;
  LicReport setup;

  Impl(const TexelDomain& d, const LicOptions& o)
      : domain(d), options(o), diffusion(d.grid(), o.solver) {}

  bool sharpens() const { return options.sharpenBeta != 1.0; }
};

LineIntegralConvolution::LineIntegralConvolution(const TexelDomain& domain,
                                                 const std::vector<Eigen::Vector2d>& fieldTexel,
                                                 const LicOptions& options) {
  options.validate();
  const auto start = std::chrono::steady_clock::now();
  impl_ = std::make_unique<Impl>(domain, options);
  Impl& s = *impl_;
  const TexelOperators& ops = domain.operators();
  s.mass = ops.mass();
  s.stiffness = ops.stiffness();
  s.metric =
      anisotropicMetric(domain.mesh(), domain.grid(), ops.metric(), fieldTexel, options.epsilon);
  for (size_t f = 0; f < fieldTexel.size(); ++f)
    if (fem::gridArea(domain.mesh(), domain.grid(), static_cast<int>(f)) != 0.0 &&
        fieldTexel[f].isZero(0.0))
      ++s.setup.zeroFieldFaces;

  // M_h and S_h on the domain's pattern; the domain's own M and S keep the immersion metric.
  MassStiffness h = ops.assembledFor(s.metric);
  s.massH.swap(h.mass);  // Eigen 3.4 sparse matrices copy on assignment
  SparseMatrixd system = options.alpha * s.massH + h.stiffness;
  pinNegligibleTexels(s.massH.diagonal(), options.alpha, system);

  const auto solverStart = std::chrono::steady_clock::now();
  s.diffusion.initAndUpdate(std::move(system));
  if (s.sharpens()) {
    SparseMatrixd sharpenSystem = options.sharpenAlpha * s.mass + s.stiffness;
    pinNegligibleTexels(s.mass.diagonal(), options.sharpenAlpha, sharpenSystem);
    s.sharpening.emplace(domain.grid(), options.solver);
    s.sharpening->initAndUpdate(std::move(sharpenSystem));
  }
  s.setup.solverSetupSeconds = secondsSince(solverStart);
  s.setup.setupSeconds = secondsSince(start);
}

LineIntegralConvolution::~LineIntegralConvolution() = default;

Eigen::MatrixXd LineIntegralConvolution::convolve(const Eigen::MatrixXd& noise, LicReport* report,
                                                  const ProgressCallback& progress) {
  Impl& s = *impl_;
  if (noise.rows() != s.domain.unknowns())
    throw InvalidInputError("LIC noise has " + std::to_string(noise.rows()) +
                            " rows, the domain has " + std::to_string(s.domain.unknowns()) +
                            " unknowns");
  LicReport local = s.setup;
  const Eigen::MatrixXd b = s.options.alpha * (s.massH * noise);
  // Start from the noise's mean (S_h kills constants): residual below that of x = 0 or x = noise.
  Eigen::MatrixXd x = noise.colwise().mean().replicate(noise.rows(), 1);
  local.diffusion = s.diffusion.solve(b, x, progress);
  if (s.sharpens()) {
    const Eigen::MatrixXd rhs =
        s.options.sharpenAlpha * (s.mass * x) + s.options.sharpenBeta * (s.stiffness * x);
    Eigen::MatrixXd y = x;
    local.sharpening = s.sharpening->solve(rhs, y, renameStage(progress, "sharpen solve"));
    x = std::move(y);
  }
  if (report) *report = std::move(local);
  return x;
}

const std::vector<Eigen::Matrix2d>& LineIntegralConvolution::metric() const {
  return impl_->metric;
}

const LicReport& LineIntegralConvolution::setupReport() const {
  return impl_->setup;
}

Eigen::MatrixXd licContrast(const Eigen::MatrixXd& values, const Eigen::VectorXd& weights,
                            double contrast) {
  if (weights.size() != values.rows())
    throw InvalidInputError("licContrast: " + std::to_string(weights.size()) + " weights for " +
                            std::to_string(values.rows()) + " values");
  Eigen::MatrixXd out = values;
  const double total = weights.sum();
  if (contrast > 0.0 && total > 0.0)
    for (Eigen::Index c = 0; c < values.cols(); ++c) {
      const double mean = weights.dot(values.col(c)) / total;
      const Eigen::ArrayXd centred = values.col(c).array() - mean;
      const double deviation = std::sqrt((weights.array() * centred.square()).sum() / total);
      const double gain = deviation > 0.0 ? contrast / deviation : 0.0;
      out.col(c).array() = 0.5 + centred * gain;
    }
  return out.cwiseMax(0.0).cwiseMin(1.0);
}

namespace {

/// Faces with positive UV area on which the field vanishes.
int zeroFieldFaces(const TexelDomain& domain, const std::vector<Eigen::Vector2d>& fieldTexel) {
  int count = 0;
  for (size_t f = 0; f < fieldTexel.size(); ++f)
    if (fem::gridArea(domain.mesh(), domain.grid(), static_cast<int>(f)) != 0.0 &&
        fieldTexel[f].isZero(0.0))
      ++count;
  return count;
}

/// alpha M + S entry by entry on M's pattern, with no seam term: LIC's two systems are the plain
/// screened systems of their metrics.
EntryCombination screening(double alpha) {
  return [alpha](Eigen::Index, Eigen::Index, double m, double s) { return alpha * m + s; };
}

/// The system alpha M + S of `ops`'s matrices, pinned (pinNegligibleTexels); `owned`, if given,
/// holds `ops` and is consumed (A formed in M's storage).
SparseMatrixd pinnedScreenedSystem(const TexelOperators& ops, std::unique_ptr<TexelOperators> owned,
                                   double alpha) {
  const Eigen::VectorXd massDiagonal = ops.mass().diagonal();
  SparseMatrixd system = owned ? TexelOperators::combined(std::move(owned), screening(alpha))
                               : ops.combined(screening(alpha));
  pinNegligibleTexels(massDiagonal, alpha, system);
  return system;
}

/// The diffusion's right-hand side alpha M_h noise, and its system alpha M_h + S_h (pinned) in
/// `system`. Shared operators get M_h and S_h assembled next to theirs; handed-over ones
/// (`owned`, holding `ops`) are re-assembled for h in their own storage and consumed, so no
/// matrix of the immersion metric is held through the diffusion.
Eigen::MatrixXd diffusionSystem(const TexelOperators& ops, std::unique_ptr<TexelOperators> owned,
                                const std::vector<Eigen::Matrix2d>& metric,
                                const Eigen::MatrixXd& noise, double alpha, SparseMatrixd& system) {
  if (owned) {
    owned->setMetric(metric);
    owned->releasePieceIntegrals();
    Eigen::MatrixXd b = alpha * (owned->mass() * noise);
    const TexelOperators& h = *owned;
    // Swapped in: Eigen 3.4's SparseMatrix has no move assignment, so `=` would copy it.
    SparseMatrixd formed = pinnedScreenedSystem(h, std::move(owned), alpha);
    system.swap(formed);
    return b;
  }
  MassStiffness h = ops.assembledFor(metric);
  Eigen::MatrixXd b = alpha * (h.mass * noise);
  const Eigen::VectorXd massDiagonal = h.mass.diagonal();
  SparseMatrixd formed = screenedSystem(std::move(h), alpha);
  system.swap(formed);
  pinNegligibleTexels(massDiagonal, alpha, system);
  return b;
}

/// The one-shot LIC on the domain's operators, or on `owned` (handed over by the domain) if
/// given. The same operations as LineIntegralConvolution's set-up and convolve (so the same
/// bits), in an order that holds one system and one solver at a time: the diffusion's are freed
/// before the sharpening's are formed, and each system is formed in its mass matrix's storage.
/// Handed-over operators become the diffusion's system; the sharpening then rebuilds the
/// immersion metric's operators (deterministic: the same M and S, bit for bit) and consumes them.
LicResult licOnce(const TexelDomain& domain, std::unique_ptr<TexelOperators> owned,
                  const std::vector<Eigen::Vector2d>& fieldTexel, const LicOptions& options,
                  const ProgressCallback& progress) {
  options.validate();
  reportProgress(progress, "lic setup", 0.0);
  const auto start = std::chrono::steady_clock::now();
  const TexelGrid& grid = domain.grid();
  const TexelOperators& ops = owned ? *owned : domain.operators();
  OperatorOptions rebuild = ops.options();
  rebuild.keepPieceIntegrals = false;
  const bool handedOver = owned != nullptr;
  LicResult result;
  LicReport& report = result.report;
  const std::vector<Eigen::Matrix2d> metric =
      anisotropicMetric(domain.mesh(), grid, ops.metric(), fieldTexel, options.epsilon);
  report.zeroFieldFaces = zeroFieldFaces(domain, fieldTexel);
  // Contrast weights: the surface area of each texel's basis function under the immersion metric.
  const Eigen::VectorXd area = ops.mass() * Eigen::VectorXd::Ones(domain.unknowns());
  Eigen::MatrixXd x;
  {
    SparseMatrixd system;
    Eigen::MatrixXd b;
    {
      const Eigen::MatrixXd noise = licNoise(grid, options.channels, options.seed);
      b = diffusionSystem(ops, std::move(owned), metric, noise, options.alpha, system);
      // Start from the noise's mean (S_h kills constants): residual below that of 0 or noise.
      x = noise.colwise().mean().replicate(noise.rows(), 1);
    }
    const auto solverStart = std::chrono::steady_clock::now();
    SystemSolver diffusion(grid, options.solver);
    diffusion.initAndUpdate(std::move(system));
    report.solverSetupSeconds = secondsSince(solverStart);
    report.setupSeconds = secondsSince(start);
    reportProgress(progress, "lic setup", 1.0);
    report.diffusion = diffusion.solve(b, x, renameStage(progress, "lic solve"));
  }
  if (options.sharpenBeta != 1.0) {
    const auto sharpenStart = std::chrono::steady_clock::now();
    std::unique_ptr<TexelOperators> immersion;
    if (handedOver)
      immersion = std::make_unique<TexelOperators>(domain.mesh(), domain.atlas(), grid, rebuild);
    const TexelOperators& m = immersion ? *immersion : domain.operators();
    const Eigen::MatrixXd rhs =
        options.sharpenAlpha * (m.mass() * x) + options.sharpenBeta * (m.stiffness() * x);
    SparseMatrixd system = pinnedScreenedSystem(m, std::move(immersion), options.sharpenAlpha);
    SystemSolver sharpening(grid, options.solver);
    sharpening.initAndUpdate(std::move(system));
    const double sharpenSetup = secondsSince(sharpenStart);
    report.solverSetupSeconds += sharpenSetup;
    report.setupSeconds += sharpenSetup;
    Eigen::MatrixXd y = x;
    report.sharpening = sharpening.solve(rhs, y, renameStage(progress, "lic sharpen"));
    x = std::move(y);
  }
  result.values = std::move(x);
  result.image = Image(grid.imageWidth, grid.imageHeight, options.channels, PixelFormat::UInt8);
  scatterTexels(grid, licContrast(result.values, area, options.contrast), result.image);
  return result;
}

}  // namespace

LicResult lineIntegralConvolution(const TexelDomain& domain,
                                  const std::vector<Eigen::Vector2d>& fieldTexel,
                                  const LicOptions& options, const ProgressCallback& progress) {
  return licOnce(domain, nullptr, fieldTexel, options, progress);
}

LicResult lineIntegralConvolution(const TexelDomain& domain,
                                  std::unique_ptr<TexelOperators> operators,
                                  const std::vector<Eigen::Vector2d>& fieldTexel,
                                  const LicOptions& options, const ProgressCallback& progress) {
  if (!operators || operators->mass().rows() != domain.unknowns())
    throw InvalidInputError(
        "lineIntegralConvolution: the operators handed over are not the domain's "
        "(TexelDomain::releaseOperators)");
  return licOnce(domain, std::move(operators), fieldTexel, options, progress);
}

}  // namespace texgrad
