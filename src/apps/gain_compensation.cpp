// Gain compensation between stitching sources; see the header for the model and reference.
#include "texgrad/apps/gain_compensation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include <Eigen/Cholesky>

namespace texgrad {
namespace {

/// Reweighting rounds of the robust illumination fit.
constexpr int kHuberIterations = 5;
/// Samples kept for the illumination fit (evenly thinned beyond this).
constexpr size_t kMaxShadingSamples = 200000;

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

Eigen::MatrixXd solveLogIllumination(int sources, int channels,
                                     const std::vector<ShadingSample>& samples,
                                     const Eigen::VectorXd& texelsPerSource) {
  const int unknowns = 4 * sources;
  Eigen::MatrixXd result = Eigen::MatrixXd::Zero(unknowns, channels);
  const double texels = std::max(1.0, texelsPerSource.sum());
  const double mu = 1e-4 * static_cast<double>(std::max<size_t>(1, samples.size())) / texels;
  // Row of the linear model for a sample: +[1, na] on source a, -[1, nb] on source b.
  auto rowOf = [](const ShadingSample& s) {
    Eigen::Matrix<double, 8, 1> row;
    row << 1.0, s.na.cast<double>(), -1.0, -s.nb.cast<double>();
    return row;
  };
  std::vector<double> residuals(samples.size()), sorted;
  for (int c = 0; c < channels; ++c) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(unknowns);
    double huber = std::numeric_limits<double>::infinity();
    for (int iteration = 0; iteration < kHuberIterations; ++iteration) {
      if (iteration > 0 && !samples.empty()) {
        // Huber threshold 1.345 sigma, sigma from the median absolute residual of the last fit.
        for (size_t i = 0; i < samples.size(); ++i) {
          const ShadingSample& s = samples[i];
          const Eigen::Matrix<double, 8, 1> row = rowOf(s);
          residuals[i] = std::abs(static_cast<double>(s.logRatio[c]) -
                                  row.head<4>().dot(x.segment<4>(4 * s.a)) -
                                  row.tail<4>().dot(x.segment<4>(4 * s.b)));
        }
        sorted = residuals;
        const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
        std::nth_element(sorted.begin(), middle, sorted.end());
        huber = std::max(1e-6, 1.345 * 1.4826 * *middle);
      }
      Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(unknowns, unknowns);
      Eigen::VectorXd rhs = Eigen::VectorXd::Zero(unknowns);
      for (size_t i = 0; i < samples.size(); ++i) {
        const ShadingSample& s = samples[i];
        const Eigen::Matrix<double, 8, 1> row = rowOf(s);
        const double w = iteration == 0 || residuals[i] <= huber ? 1.0 : huber / residuals[i];
        const double r = static_cast<double>(s.logRatio[c]);
        const Eigen::Matrix<double, 8, 8> outer = w * row * row.transpose();
        rhs.segment<4>(4 * s.a) += w * r * row.head<4>();
        rhs.segment<4>(4 * s.b) += w * r * row.tail<4>();
        normal.block<4, 4>(4 * s.a, 4 * s.a) += outer.topLeftCorner<4, 4>();
        normal.block<4, 4>(4 * s.a, 4 * s.b) += outer.topRightCorner<4, 4>();
        normal.block<4, 4>(4 * s.b, 4 * s.a) += outer.bottomLeftCorner<4, 4>();
        normal.block<4, 4>(4 * s.b, 4 * s.b) += outer.bottomRightCorner<4, 4>();
      }
      for (int k = 0; k < sources; ++k)
        normal.diagonal().segment(4 * k, 4).array() += mu * std::max(1.0, texelsPerSource[k]);
      x = normal.ldlt().solve(rhs);
    }
    result.col(c) = x;
  }
  return result;
}

std::vector<GainLink> compositeGainLinks(
    const Eigen::Ref<const Eigen::SparseMatrix<double>>& coupling,
    const std::vector<int32_t>& labels, const Eigen::MatrixXd& values, int channels) {
  RatioSamples samples(channels);
  for (int u = 0; u < coupling.outerSize(); ++u)
    for (Eigen::Ref<const Eigen::SparseMatrix<double>>::InnerIterator it(coupling, u); it; ++it) {
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

namespace {

/// Calls f(i, j) for every pair of positions with a.unknowns[i] == b.unknowns[j], in ascending
/// unknown order (both lists are ascending).
template <typename F>
void forEachShared(const PartialView& a, const PartialView& b, F&& f) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (a.unknowns[i] < b.unknowns[j]) {
      ++i;
    } else if (b.unknowns[j] < a.unknowns[i]) {
      ++j;
    } else {
      f(i, j);
      ++i;
      ++j;
    }
  }
}

/// Entry i of `view` as a row of doubles.
Eigen::RowVectorXd rowOf(const PartialView& view, size_t i) {
  Eigen::RowVectorXd row(view.channels);
  for (int c = 0; c < view.channels; ++c)
    row[c] = view.values[i * static_cast<size_t>(view.channels) + static_cast<size_t>(c)];
  return row;
}

}  // namespace

std::vector<GainLink> partialGainLinks(const std::vector<PartialView>& views, int channels) {
  RatioSamples samples(channels);
  for (size_t a = 0; a < views.size(); ++a)
    for (size_t b = a + 1; b < views.size(); ++b)
      forEachShared(views[a], views[b], [&](size_t i, size_t j) {
        samples.add(static_cast<int>(a), static_cast<int>(b), rowOf(views[a], i).head(channels),
                    rowOf(views[b], j).head(channels));
      });
  return samples.links();
}

namespace {

/// Keeps every k-th sample so that at most kMaxShadingSamples remain (deterministic).
std::vector<ShadingSample> thinned(std::vector<ShadingSample> samples) {
  if (samples.size() <= kMaxShadingSamples) return samples;
  const size_t stride = (samples.size() + kMaxShadingSamples - 1) / kMaxShadingSamples;
  size_t kept = 0;
  for (size_t i = 0; i < samples.size(); i += stride) samples[kept++] = samples[i];
  samples.resize(kept);
  return samples;
}

/// A sample of sources a, b from their values and normals, if every channel is bright enough.
bool makeSample(int a, int b, const Eigen::Ref<const Eigen::RowVectorXd>& xa,
                const Eigen::Ref<const Eigen::RowVectorXd>& xb,
                const Eigen::Ref<const Eigen::RowVector3d>& na,
                const Eigen::Ref<const Eigen::RowVector3d>& nb, int channels, ShadingSample& s) {
  s.a = a;
  s.b = b;
  s.logRatio.setZero();
  for (int c = 0; c < channels; ++c) {
    if (!(xa[c] > kDarkest && xb[c] > kDarkest)) return false;
    s.logRatio[c] = static_cast<float>(std::log(xa[c] / xb[c]));
  }
  s.na = na.transpose().cast<float>();
  s.nb = nb.transpose().cast<float>();
  return true;
}

}  // namespace

std::vector<ShadingSample> compositeShadingSamples(
    const Eigen::Ref<const Eigen::SparseMatrix<double>>& coupling,
    const std::vector<int32_t>& labels, const Eigen::MatrixXd& values,
    const Eigen::MatrixX3d& normals, int channels) {
  std::vector<ShadingSample> samples;
  ShadingSample s;
  for (int u = 0; u < coupling.outerSize(); ++u)
    for (Eigen::Ref<const Eigen::SparseMatrix<double>>::InnerIterator it(coupling, u); it; ++it) {
      const auto v = static_cast<int>(it.row());
      const int32_t la = labels[static_cast<size_t>(u)], lb = labels[static_cast<size_t>(v)];
      if (v <= u || la == 0 || lb == 0 || la == lb) continue;
      if (makeSample(la - 1, lb - 1, values.row(u), values.row(v), normals.row(u), normals.row(v),
                     channels, s))
        samples.push_back(s);
    }
  return thinned(std::move(samples));
}

std::vector<ShadingSample> partialShadingSamples(const std::vector<PartialView>& views,
                                                 const Eigen::MatrixX3d& normals, int channels) {
  // Two passes over the shared texels: count the samples, then keep every stride-th one, the
  // samples thinned() would keep of the whole list (which at 10 views of 2048^2 holds ~25M
  // samples, 1.1 GB).
  ShadingSample s;
  const auto visit = [&](auto&& take) {
    for (size_t a = 0; a < views.size(); ++a)
      for (size_t b = a + 1; b < views.size(); ++b)
        forEachShared(views[a], views[b], [&](size_t i, size_t j) {
          const Eigen::Index u = views[a].unknowns[i];
          if (makeSample(static_cast<int>(a), static_cast<int>(b), rowOf(views[a], i),
                         rowOf(views[b], j), normals.row(u), normals.row(u), channels, s))
            take(s);
        });
  };
  size_t total = 0;
  visit([&](const ShadingSample&) { ++total; });
  const size_t stride = std::max<size_t>(1, (total + kMaxShadingSamples - 1) / kMaxShadingSamples);
  std::vector<ShadingSample> samples;
  samples.reserve((total + stride - 1) / stride);
  size_t index = 0;
  visit([&](const ShadingSample& sample) {
    if (index++ % stride == 0) samples.push_back(sample);
  });
  return samples;
}

double logIllumination(const Eigen::MatrixXd& illumination, int source,
                       const Eigen::MatrixX3d& normals, Eigen::Index row, int channel) {
  const auto k = static_cast<Eigen::Index>(4 * source);
  return illumination(k, channel) +
         normals.row(row).dot(illumination.col(channel).segment<3>(k + 1).transpose());
}

Eigen::RowVectorXd removeIllumination(const Eigen::MatrixXd& illumination, int source,
                                      const Eigen::MatrixX3d& normals,
                                      const std::vector<Eigen::Index>& rows, int channels,
                                      Eigen::MatrixXd& values) {
  Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(channels);
  for (Eigen::Index u : rows)
    for (int c = 0; c < channels; ++c) {
      const double log = logIllumination(illumination, source, normals, u, c);
      values(u, c) /= std::exp(log);
      mean[c] += log;
    }
  return rows.empty() ? mean : Eigen::RowVectorXd(mean / static_cast<double>(rows.size()));
}

}  // namespace texgrad
