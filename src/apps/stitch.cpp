// Stitching (paper §7.2): per-pair target differences g on the texel pairs A, divergence d^T *1 g
// (paper §5.3), screened by the sources' values where any source sees a texel.
#include "texgrad/apps/stitch.h"

#include <cmath>
#include <map>

#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"

namespace texgrad {
namespace {

void checkSize(const TexelGrid& grid, const Image& image, const std::string& what) {
  if (image.width != grid.imageWidth || image.height != grid.imageHeight)
    throw InvalidInputError(what + " is " + std::to_string(image.width) + "x" +
                            std::to_string(image.height) + " but the texture is " +
                            std::to_string(grid.imageWidth) + "x" +
                            std::to_string(grid.imageHeight) + "; all inputs must match");
}

/// Channel-0 value of `image` at each unknown (clamp-to-edge outside the image).
Eigen::VectorXd channelZero(const TexelGrid& grid, const Image& image) {
  return gatherTexels(grid, image).col(0);
}

/// Solves (alpha W M W + S + lock) x = alpha W M W xbar + div + lock xbar.
StitchResult solveStitch(const TexelDomain& domain, const Eigen::MatrixXd& xbar,
                         const Eigen::VectorXd& known, const Eigen::MatrixXd& pairTargets,
                         const Image& like, const StitchOptions& options) {
  const TexelGrid& grid = domain.grid();
  const TexelOperators& ops = domain.operators();
  const auto n = static_cast<Eigen::Index>(grid.unknownCount());
  Eigen::SparseMatrix<double> wmw = ops.mass();
  for (int k = 0; k < wmw.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(wmw, k); it; ++it)
      it.valueRef() *= known[it.row()] * known[it.col()];
  // A little plain screening keeps components that no source sees solvable.
  Eigen::SparseMatrix<double> a = options.alpha * wmw + 1e-6 * options.alpha * ops.mass() +
                                  ops.stiffness();
  Eigen::MatrixXd rhs = options.alpha * (wmw * xbar) +
                        ops.differential().transpose() * (ops.hodgeStar1() * pairTargets);
  StitchResult result;
  std::vector<uint8_t> locked(static_cast<size_t>(n), 0);
  if (!options.lock.empty()) {
    checkSize(grid, options.lock, "the lock mask");
    const Eigen::VectorXd lockValues = channelZero(grid, options.lock);
    double maxDiagonal = 0.0;
    for (Eigen::Index u = 0; u < n; ++u) maxDiagonal = std::max(maxDiagonal, a.coeff(u, u));
    const double weight = 1e8 * maxDiagonal;
    for (Eigen::Index u = 0; u < n; ++u) {
      if (!(lockValues[u] > 0.5)) continue;
      locked[static_cast<size_t>(u)] = 1;
      a.coeffRef(u, u) += weight;
      rhs.row(u) += weight * xbar.row(u);
      ++result.lockedTexels;
    }
  }
  SystemSolver solver(grid, options.solver);
  solver.init(a);
  solver.update(a);
  Eigen::MatrixXd x = xbar;
  result.report = solver.solve(rhs, x);
  for (Eigen::Index u = 0; u < n; ++u)
    if (locked[static_cast<size_t>(u)]) x.row(u) = xbar.row(u);  // exactly the input
  result.image = like;
  scatterTexels(grid, x, result.image);
  return result;
}

}  // namespace

void StitchOptions::validate() const {
  if (!(alpha > 0.0) || !std::isfinite(alpha))
    throw InvalidInputError("alpha must be a positive number, got " + std::to_string(alpha));
  solver.validate();
}

std::vector<int32_t> sourceLabels(const TexelGrid& grid, const Image& segments, int& sources) {
  const Eigen::MatrixXd colours = gatherTexels(grid, segments);
  std::map<std::vector<double>, int32_t> labelOf;
  std::vector<int32_t> labels(static_cast<size_t>(grid.unknownCount()), 0);
  const Eigen::Index channels = std::min<Eigen::Index>(colours.cols(), 3);
  for (Eigen::Index u = 0; u < colours.rows(); ++u) {
    std::vector<double> key;
    bool black = true;
    for (Eigen::Index c = 0; c < channels; ++c) {
      key.push_back(colours(u, c));
      black &= colours(u, c) == 0.0;
    }
    if (black) continue;
    auto [it, added] = labelOf.try_emplace(key, static_cast<int32_t>(labelOf.size()) + 1);
    labels[static_cast<size_t>(u)] = it->second;
  }
  sources = static_cast<int>(labelOf.size());
  return labels;
}

StitchResult stitchComposite(const TexelDomain& domain, const Image& composite,
                             const Image& segments, const StitchOptions& options) {
  options.validate();
  const TexelGrid& grid = domain.grid();
  checkSize(grid, composite, "the composite texture");
  checkSize(grid, segments, "the segment mask");
  int sources = 0;
  const std::vector<int32_t> labels = sourceLabels(grid, segments, sources);
  const Eigen::MatrixXd xbar = gatherTexels(grid, composite);
  Eigen::VectorXd known(xbar.rows());
  for (Eigen::Index u = 0; u < xbar.rows(); ++u) known[u] = labels[u] > 0 ? 1.0 : 0.0;
  const auto pairs = domain.operators().texelPairs();
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(pairs.size()), xbar.cols());
  for (size_t p = 0; p < pairs.size(); ++p) {
    const auto [s, t] = pairs[p];
    if (labels[s] > 0 && labels[s] == labels[t])
      g.row(static_cast<Eigen::Index>(p)) = xbar.row(t) - xbar.row(s);
  }
  StitchResult result = solveStitch(domain, xbar, known, g, composite, options);
  result.sources = sources;
  return result;
}

StitchResult stitchPartials(const TexelDomain& domain, const std::vector<Image>& partials,
                            const std::vector<Image>& confidences, const StitchOptions& options) {
  options.validate();
  if (partials.empty()) throw InvalidInputError("stitching needs at least one partial texture");
  if (partials.size() != confidences.size())
    throw InvalidInputError(std::to_string(partials.size()) + " partial textures but " +
                            std::to_string(confidences.size()) +
                            " confidence maps; give one confidence map per partial");
  const TexelGrid& grid = domain.grid();
  const auto pairs = domain.operators().texelPairs();
  const auto n = static_cast<Eigen::Index>(grid.unknownCount());
  const Eigen::Index channels = partials[0].channels;
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, channels);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(pairs.size()), channels);
  Eigen::VectorXd pairWeight = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(pairs.size()));
  for (size_t i = 0; i < partials.size(); ++i) {
    const std::string name = "partial " + std::to_string(i);
    checkSize(grid, partials[i], name);
    checkSize(grid, confidences[i], "confidence " + std::to_string(i));
    if (partials[i].channels != channels)
      throw InvalidInputError(name + " has " + std::to_string(partials[i].channels) +
                              " channels, partial 0 has " + std::to_string(channels));
    const Eigen::MatrixXd x = gatherTexels(grid, partials[i]);
    const Eigen::VectorXd w = channelZero(grid, confidences[i]).cwiseMax(0.0).cwiseMin(1.0);
    for (Eigen::Index u = 0; u < n; ++u) {
      sum.row(u) += w[u] * x.row(u);
      weight[u] += w[u];
    }
    for (size_t p = 0; p < pairs.size(); ++p) {
      const auto [s, t] = pairs[p];
      const double wp = std::min(w[s], w[t]);
      if (wp <= 0.0) continue;
      const auto row = static_cast<Eigen::Index>(p);
      g.row(row) += wp * (x.row(t) - x.row(s));
      pairWeight[row] += wp;
    }
  }
  Eigen::VectorXd known(n);
  Eigen::MatrixXd xbar(n, channels);
  for (Eigen::Index u = 0; u < n; ++u) {
    known[u] = weight[u] > 0.0 ? 1.0 : 0.0;
    xbar.row(u) = weight[u] > 0.0 ? Eigen::RowVectorXd(sum.row(u) / weight[u])
                                  : Eigen::RowVectorXd::Zero(channels);
  }
  for (Eigen::Index p = 0; p < g.rows(); ++p)
    if (pairWeight[p] > 0.0) g.row(p) /= pairWeight[p];
  Image like = partials[0];
  StitchResult result = solveStitch(domain, xbar, known, g, like, options);
  result.sources = static_cast<int>(partials.size());
  return result;
}

}  // namespace texgrad
