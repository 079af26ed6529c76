// Seamless stitching of textures from several sources (`texgrad stitch`, paper §7.2): keep the
// gradients inside each source, drop them across sources, and solve for one consistent texture.
#pragma once

#include <memory>
#include <vector>

#include "texgrad/apps/partial_view.h"
#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/image.h"
#include "texgrad/solver/solve_report.h"

namespace texgrad {

/// Parameters of the stitching solve (alpha W M W + S) x = alpha W M W xbar + div(g), W = 1 on
/// texels some source sees, g the target gradient field, blended per lattice cell.
struct StitchOptions {
  /// Screening weight on the unit-area surface (paper default 1e2): how strongly the result keeps
  /// the sources' absolute colours; gradients inside each source are always kept.
  double alpha = 1e2;
  /// Optional lock mask (image of the texture's size): texels where channel 0 > 0.5 keep the
  /// composite value exactly.
  Image lock;
  /// Divide each source by its estimated gain per colour channel before stitching (beyond the
  /// paper: cameras differ by exposure and colour cast, which the screening would otherwise keep
  /// away from source boundaries). See gain_compensation.h.
  bool compensateGains = true;
  /// With compensateGains: let each source's gain vary with the surface normal,
  /// exp(a_k + b_k . n), the first-order model of a view's lighting on a diffuse surface, so that
  /// smooth shading differences inside sources go too (solveLogIllumination).
  bool compensateIllumination = true;
  /// Keep the solver's values at barely covered texels; by default those not locked are
  /// clamped into the range the surface shows around them (boundBarelyCovered).
  bool rawSolution = false;
  SolverSettings solver;
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// Stitched texture and what the solve did.
struct StitchResult {
  Image image;
  SolveReport report;
  int sources = 0;           ///< distinct source labels / partial textures used
  int64_t lockedTexels = 0;  ///< texels held at their input value
  /// Gain divided out of each source per colour channel (sources x channels; ones when off).
  Eigen::MatrixXd sourceGains;
  /// With compensateIllumination: rows 4k .. 4k + 3 = a_k, b_k per colour channel (else empty).
  Eigen::MatrixXd sourceIllumination;
};

/// Composite mode: `composite` holds each texel from one source, `segments` a distinct colour
/// per source (black = no source). The target gradient is the composite's on cells whose texels
/// all share one source, zero on cells that straddle sources or touch unknown texels. Reports
/// stages "solver setup" and "solve" to `progress`, which may cancel (Cancelled).
StitchResult stitchComposite(const TexelDomain& domain, const Image& composite,
                             const Image& segments, const StitchOptions& options,
                             const ProgressCallback& progress = {});

/// As above, for a caller done with the operators: `operators` (the domain's, handed over by
/// TexelDomain::releaseOperators, or null) are freed once the system is formed, before the
/// solver's set-up. Same result, bit for bit.
StitchResult stitchComposite(const TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                             const Image& composite, const Image& segments,
                             const StitchOptions& options, const ProgressCallback& progress = {});

/// Partials mode: N partial textures with confidence maps (channel 0 in [0, 1]). The target
/// gradient on a cell is the confidence-weighted mean of the partials' gradients (a partial's
/// weight on a cell = its smallest confidence over the cell's texels); zero where none sees it.
/// The result holds partials[0] at the texels that are not unknowns. Reports and cancels as
/// stitchComposite.
StitchResult stitchPartials(const TexelDomain& domain, const std::vector<Image>& partials,
                            const std::vector<Image>& confidences, const StitchOptions& options,
                            const ProgressCallback& progress = {});

/// Partials mode on compact views (compactPartial), the same solve as above. The views are
/// taken over and freed once the system is formed, before the solver is set up, so they never
/// share memory with the solver. The result is an image of the grid's size in `format`, zero at
/// the texels that are not unknowns.
StitchResult stitchPartials(const TexelDomain& domain, std::vector<PartialView> views,
                            PixelFormat format, const StitchOptions& options,
                            const ProgressCallback& progress = {});

/// As above, for a caller done with the operators (a one-shot run): `operators`, the domain's
/// handed over by TexelDomain::releaseOperators (or null to use the domain's), are freed once
/// the system is formed, before the solver's set-up, so M, S and the piece integrals are not
/// held through set-up and solve. Same result, bit for bit.
StitchResult stitchPartials(const TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                            std::vector<PartialView> views, PixelFormat format,
                            const StitchOptions& options, const ProgressCallback& progress = {});

/// Distinct source label per unknown from a segment image (0 = none, 1.. = sources in order of
/// first appearance), and the number of sources.
std::vector<int32_t> sourceLabels(const TexelGrid& grid, const Image& segments, int& sources);

}  // namespace texgrad
