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

#include "texgrad/apps/partial_view.h"

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

/// Two sources' observations of (nearly) the same surface point, for the illumination model:
/// log(x_a / x_b) per colour channel, and the surface normal where each was taken.
struct ShadingSample {
  int a = 0, b = 0;          ///< source indices, 0-based
  Eigen::Vector3f na, nb;    ///< unit surface normals at the two observations
  Eigen::Vector3f logRatio;  ///< per channel (first `channels` entries), log(x_a) - log(x_b)
};

/// Illumination per source beyond one gain: log x_k(p) = log t(p) + a_k + b_k . n(p), the
/// first-order spherical-harmonic approximation of how a view's lighting scales a diffuse
/// surface (Ramamoorthi & Hanrahan, "An Efficient Representation for Irradiance Environment
/// Maps", SIGGRAPH 2001). Fitted by Huber-weighted least squares (robust to texture edges) with
/// a small ridge that fixes the unobservable common part. Returns (4 sources) x channels:
/// rows 4k .. 4k + 3 hold a_k, b_k for source k.
Eigen::MatrixXd solveLogIllumination(int sources, int channels,
                                     const std::vector<ShadingSample>& samples,
                                     const Eigen::VectorXd& texelsPerSource);

/// Links from a composite: pairs of coupled unknowns (non-zeros of `coupling`, e.g. the
/// stiffness) whose source labels differ (labels 1..sources, 0 = none).
std::vector<GainLink> compositeGainLinks(
    const Eigen::Ref<const Eigen::SparseMatrix<double>>& coupling,
    const std::vector<int32_t>& labels, const Eigen::MatrixXd& values, int channels);

/// Links from partial textures: texels that two partials both see.
std::vector<GainLink> partialGainLinks(const std::vector<PartialView>& views, int channels);

/// Illumination samples from a composite: coupled unknowns with different source labels, as in
/// compositeGainLinks; `normals` holds one unit normal per unknown. At most ~200k, evenly spread.
std::vector<ShadingSample> compositeShadingSamples(
    const Eigen::Ref<const Eigen::SparseMatrix<double>>& coupling,
    const std::vector<int32_t>& labels, const Eigen::MatrixXd& values,
    const Eigen::MatrixX3d& normals, int channels);

/// Illumination samples from partial textures: texels two partials both see, thinned as
/// compositeShadingSamples (counted first, so the samples dropped are never stored).
std::vector<ShadingSample> partialShadingSamples(const std::vector<PartialView>& views,
                                                 const Eigen::MatrixX3d& normals, int channels);

/// Log of source `source`'s illumination a_k + b_k . n in channel `channel` at the unit normal
/// normals.row(row) (illumination as solveLogIllumination returns it).
double logIllumination(const Eigen::MatrixXd& illumination, int source,
                       const Eigen::MatrixX3d& normals, Eigen::Index row, int channel);

/// Divides out source k's illumination exp(a_k + b_k . n) (from solveLogIllumination) from the
/// first `channels` channels of rows `rows` of values; returns the mean log illumination over
/// those rows per channel (the log of the source's geometric-mean gain).
Eigen::RowVectorXd removeIllumination(const Eigen::MatrixXd& illumination, int source,
                                      const Eigen::MatrixX3d& normals,
                                      const std::vector<Eigen::Index>& rows, int channels,
                                      Eigen::MatrixXd& values);

}  // namespace texgrad
