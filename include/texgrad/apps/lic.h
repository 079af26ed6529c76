// Line integral convolution inside the atlas (`texgrad lic`, paper §7.4): diffuse a random texture
// under an anisotropic metric that shrinks lengths along a vector field, then sharpen it.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/core/progress.h"
#include "texgrad/io/image.h"
#include "texgrad/solver/solve_report.h"

namespace texgrad {

/// Solver settings LIC starts from: multigrid-preconditioned CG (plain V-cycles stall on the
/// anisotropic metric, paper §8), up to 600 iterations, relative residual 1e-8 (30 V-cycles if
/// the kind is changed to Multigrid).
SolverSettings defaultLicSolver();

/// Parameters of line integral convolution. Lengths refer to the unit-area surface (paper §7).
struct LicOptions {
  /// Isotropic part of the metric h = g(., u⊥) g(., u⊥) + epsilon g, relative to the field's
  /// area-weighted RMS length (normalised to 1). Where |u| = 1, streaks are about
  /// sqrt((1 + epsilon) / epsilon) times longer than wide: smaller is more streaky (and makes the
  /// system harder to solve); where u = 0 diffusion is isotropic.
  double epsilon = 1e-4;
  /// Screening weight of the diffusion (alpha M_h + S_h) x = alpha M_h x0, with h scaled to unit
  /// area: streak length along u ~ epsilon^(-1/4) / sqrt(alpha). Smaller gives longer streaks.
  double alpha = 1e4;
  /// Screening weight of the sharpening (alpha_s M + S) y = alpha_s M x + beta S x, with the
  /// immersion metric: detail finer than ~1 / sqrt(alpha_s) is boosted.
  double sharpenAlpha = 1e4;
  /// Gradient gain beta of the sharpening step: 1 skips it, larger restores more contrast
  /// across the streaks (the reference implementation uses 100).
  double sharpenBeta = 100.0;
  /// Output contrast: each channel is mapped to mean 0.5 and this (surface-area weighted)
  /// standard deviation before clamping to [0, 1] (diffusion along long streaks averages the noise
  /// to a flat grey, and sharpening changes its scale with resolution). 0 keeps the raw values
  /// (clamped).
  double contrast = 0.2;
  /// Noise channels: 1 = grey values uniform in [0, 1], 3 = random fully saturated hues.
  int channels = 1;
  /// Seed of the noise; the same seed and inputs give the same texture.
  uint64_t seed = 1;
  /// Solver of both systems (Direct for ground truth).
  SolverSettings solver = defaultLicSolver();
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// The anisotropic metric of paper §7.4 per face, in texel coordinates, for `fieldTexel`
/// (texel-coordinate vectors per face, fieldInTexelCoordinates) and the immersion metric `g`
/// (TexelOperators::metric of the unit-area surface). The field is first scaled to unit
/// area-weighted RMS g-length, then h = (g u⊥)(g u⊥)^T + epsilon g with u⊥ the g-rotation of u by
/// 90 degrees (same g-length), and h is scaled so the surface has unit area under h. Faces with
/// zero UV area keep g. Throws InvalidInputError if the field is zero on every face or sizes
/// differ.
std::vector<Eigen::Matrix2d> anisotropicMetric(const TexturedMesh& mesh, const TexelGrid& grid,
                                               const std::vector<Eigen::Matrix2d>& g,
                                               const std::vector<Eigen::Vector2d>& fieldTexel,
                                               double epsilon);

/// Seeded white noise on the grid's unknowns (unknownCount x channels): a value per texel that
/// depends only on the seed and the texel's image coordinates (not on threads or ordering).
Eigen::MatrixXd licNoise(const TexelGrid& grid, int channels, uint64_t seed);

/// What one LIC run did.
struct LicReport {
  SolveReport diffusion;      ///< anisotropic diffusion solve
  SolveReport sharpening;     ///< sharpening solve (empty when sharpenBeta == 1)
  double setupSeconds = 0.0;  ///< metric, assembly, solver init and update of both systems
  /// The part of setupSeconds spent in init and update of the two solvers (for Direct: the
  /// CHOLMOD factorisations; for MultigridCg: the hierarchies and coarse factorisations).
  double solverSetupSeconds = 0.0;
  int zeroFieldFaces = 0;  ///< faces with positive UV area where the field vanishes
};

/// Stateful LIC for one domain and field: both systems are assembled and their solvers set up
/// once; convolve() can then run for any noise. M_h and S_h are assembled from the domain's
/// operators (TexelOperators::assembledFor), which stay unchanged. `domain` must outlive the
/// object.
class LineIntegralConvolution {
 public:
  /// Builds h (anisotropicMetric), M_h, S_h and the two solvers; throws InvalidInputError on
  /// bad options or a field of the wrong size or zero everywhere.
  LineIntegralConvolution(const TexelDomain& domain, const std::vector<Eigen::Vector2d>& fieldTexel,
                          const LicOptions& options);
  ~LineIntegralConvolution();
  LineIntegralConvolution(const LineIntegralConvolution&) = delete;
  LineIntegralConvolution& operator=(const LineIntegralConvolution&) = delete;

  /// Diffuses `noise` (unknowns x k) along the field and sharpens the result; values are the
  /// unknowns' (not clamped). Solve reports go to `report` if given.
  /// Reports stage "solve" (then "sharpen solve" if sharpening) with the iteration counts to
  /// `progress`, which may cancel (Cancelled).
  Eigen::MatrixXd convolve(const Eigen::MatrixXd& noise, LicReport* report = nullptr,
                           const ProgressCallback& progress = {});
  /// The per-face metric h in use.
  const std::vector<Eigen::Matrix2d>& metric() const;
  /// Setup diagnostics (setupSeconds, zeroFieldFaces).
  const LicReport& setupReport() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Output of lineIntegralConvolution.
struct LicResult {
  /// Domain's image size, options.channels channels (written as 8-bit by default); active
  /// texels hold the convolved noise after the contrast mapping, inactive texels 0.
  Image image;
  Eigen::MatrixXd values;  ///< raw convolved values per unknown (unknowns x channels)
  LicReport report;
};

/// Maps each column to mean 0.5 and standard deviation `contrast`, then clamps to [0, 1];
/// contrast 0 only clamps; constant columns become 0.5. Mean and deviation are weighted by
/// `weights` (per unknown, e.g. the surface area of each texel's basis function, M 1), so texels
/// that barely touch the surface cannot skew them.
Eigen::MatrixXd licContrast(const Eigen::MatrixXd& values, const Eigen::VectorXd& weights,
                            double contrast);

/// One-shot LIC: noise from options.seed, diffusion, sharpening, contrast, image; the same
/// values as LineIntegralConvolution::convolve, bit for bit, with one system and one solver
/// alive at a time. Reports the stages "lic setup" (0, and 1 once the diffusion's solver is set
/// up), "lic solve" and, if sharpening, "lic sharpen" (with the iteration counts) to `progress`,
/// which may cancel.
LicResult lineIntegralConvolution(const TexelDomain& domain,
                                  const std::vector<Eigen::Vector2d>& fieldTexel,
                                  const LicOptions& options, const ProgressCallback& progress = {});

/// As above, for a caller done with the operators: `operators` (the domain's, handed over by
/// TexelDomain::releaseOperators) are re-assembled for h in their own storage and consumed by
/// the diffusion's system, so no matrix of the immersion metric is held through the diffusion;
/// the sharpening rebuilds the immersion metric's operators (bit for bit the same; one more
/// operator build) and consumes them likewise (docs/memory.md). Same result, bit for bit.
LicResult lineIntegralConvolution(const TexelDomain& domain,
                                  std::unique_ptr<TexelOperators> operators,
                                  const std::vector<Eigen::Vector2d>& fieldTexel,
                                  const LicOptions& options, const ProgressCallback& progress = {});

}  // namespace texgrad
