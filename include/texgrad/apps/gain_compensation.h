// Exposure (gain) compensation between texture sources before stitching: cameras differ by a
// multiplicative gain and colour cast, which gradient-domain stitching alone only removes near
// source boundaries (the screening term keeps each source's level elsewhere). We estimate one
// gain per source and channel from where sources meet, in the spirit of Brown & Lowe,
// "Automatic Panoramic Image Stitching using Invariant Features" (IJCV 2007, §5), using medians
// of log ratios so that texture edges along a boundary do not bias the estimate.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace texgrad {

/// What two sources say about their relative gain: per channel, the median over their meeting
/// texels of log(x_a / x_b), with the number of texels it came from as weight.
struct GainLink {
  int a = 0, b = 0;             ///< source indices, 0-based
  Eigen::RowVectorXd logRatio;  ///< per channel, median of log(x_a) - log(x_b)
  double weight = 0.0;          ///< number of observations
};

/// Per-source, per-channel log gains l (sources x channels) minimising
/// sum_links w (l_a - l_b - r)^2 + mu sum_a n_a l_a^2 with a tiny mu, so the gains are fixed up to
/// the texel-weighted mean (which is pulled to zero: overall brightness is kept) and sources that
/// meet no other source keep a gain of one.
Eigen::MatrixXd solveLogGains(int sources, int channels, const std::vector<GainLink>& links,
                              const Eigen::VectorXd& texelsPerSource);

/// Links from a composite: pairs of coupled unknowns (non-zeros of `coupling`, e.g. the
/// stiffness) whose source labels differ (labels 1..sources, 0 = none).
std::vector<GainLink> compositeGainLinks(const Eigen::SparseMatrix<double>& coupling,
                                         const std::vector<int32_t>& labels,
                                         const Eigen::MatrixXd& values, int channels);

/// Links from partial textures: texels that two partials both see (confidence > 0).
std::vector<GainLink> partialGainLinks(const std::vector<Eigen::MatrixXd>& values,
                                       const std::vector<Eigen::VectorXd>& confidence,
                                       int channels);

}  // namespace texgrad
