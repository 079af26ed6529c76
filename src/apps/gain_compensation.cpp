// Gain compensation between stitching sources; see the header for the model and reference.
#include "texgrad/apps/gain_compensation.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include <Eigen/Cholesky>

namespace texgrad {
namespace {

/// Values darker than this (on a [0, 1] scale) say little about a gain and are skipped.
constexpr double kDarkest = 2.0 / 255.0;

/// Log-ratio samples per ordered source pair and channel.
class RatioSamples {
 public:
  explicit RatioSamples(int channels) : channels_(channels) {}

  /// Records log(xa / xb) per channel for one texel pair seen by sources a < b.
  void add(int a, int b, const Eigen::Ref<const Eigen::RowVectorXd>& xa,
           const Eigen::Ref<const Eigen::RowVectorXd>& xb) {
    for (int c = 0; c < channels_; ++c)
      if (!(xa[c] > kDarkest && xb[c] > kDarkest)) return;
    auto& lists = samples_[{a, b}];
    lists.resize(static_cast<size_t>(channels_));
    for (int c = 0; c < channels_; ++c)
      lists[static_cast<size_t>(c)].push_back(static_cast<float>(std::log(xa[c] / xb[c])));
  }

  /// One link per pair that has samples, holding the per-channel medians.
  std::vector<GainLink> links() {
    std::vector<GainLink> result;
    for (auto& [pair, lists] : samples_) {
      GainLink link;
      link.a = pair.first;
      link.b = pair.second;
      link.logRatio.resize(channels_);
      for (int c = 0; c < channels_; ++c) link.logRatio[c] = median(lists[static_cast<size_t>(c)]);
      link.weight = static_cast<double>(lists[0].size());
      result.push_back(std::move(link));
    }
    return result;
  }

 private:
  static double median(std::vector<float>& v) {
    const auto middle = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), middle, v.end());
    return *middle;
  }

  int channels_;
  std::map<std::pair<int, int>, std::vector<std::vector<float>>> samples_;
};

}  // namespace

Eigen::MatrixXd solveLogGains(int sources, int channels, const std::vector<GainLink>& links,
                              const Eigen::VectorXd& texelsPerSource) {
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(sources, sources);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(sources, channels);
  double linkWeight = 0.0;
  for (const GainLink& link : links) {
    normal(link.a, link.a) += link.weight;
    normal(link.b, link.b) += link.weight;
    normal(link.a, link.b) -= link.weight;
    normal(link.b, link.a) -= link.weight;
    rhs.row(link.a) += link.weight * link.logRatio;
    rhs.row(link.b) -= link.weight * link.logRatio;
    linkWeight += link.weight;
  }
  const double texels = std::max(1.0, texelsPerSource.sum());
  const double mu = 1e-6 * std::max(1.0, linkWeight) / texels;
  for (int a = 0; a < sources; ++a) normal(a, a) += mu * std::max(1.0, texelsPerSource[a]);
  return normal.ldlt().solve(rhs);
}

std::vector<GainLink> compositeGainLinks(const Eigen::SparseMatrix<double>& coupling,
                                         const std::vector<int32_t>& labels,
                                         const Eigen::MatrixXd& values, int channels) {
  RatioSamples samples(channels);
  for (int u = 0; u < coupling.outerSize(); ++u)
    for (Eigen::SparseMatrix<double>::InnerIterator it(coupling, u); it; ++it) {
      const auto v = static_cast<int>(it.row());
      const int32_t la = labels[static_cast<size_t>(u)], lb = labels[static_cast<size_t>(v)];
      if (v <= u || la == 0 || lb == 0 || la == lb) continue;
      if (la < lb)
        samples.add(la - 1, lb - 1, values.row(u).head(channels), values.row(v).head(channels));
      else
        samples.add(lb - 1, la - 1, values.row(v).head(channels), values.row(u).head(channels));
    }
  return samples.links();
}

std::vector<GainLink> partialGainLinks(const std::vector<Eigen::MatrixXd>& values,
                                       const std::vector<Eigen::VectorXd>& confidence,
                                       int channels) {
  RatioSamples samples(channels);
  for (size_t a = 0; a < values.size(); ++a)
    for (size_t b = a + 1; b < values.size(); ++b)
      for (Eigen::Index u = 0; u < values[a].rows(); ++u)
        if (confidence[a][u] > 0.0 && confidence[b][u] > 0.0)
          samples.add(static_cast<int>(a), static_cast<int>(b), values[a].row(u).head(channels),
                      values[b].row(u).head(channels));
  return samples.links();
}

}  // namespace texgrad
