// Stitching (paper §7.2). The target gradient field is the sources' gradient, blended per lattice
// cell, so its divergence is sum_i sum_c beta_ic S_c x_i with the per-cell stiffness pieces S_c
// of paper §7.1 (exact for that field). The issue asks for per-pair targets d^T *1 g; the Whitney
// star *1 is |A| x |A| with ~11 |A| non-zeros and slow to assemble, and the lumped star
// diag(-S_st) is indefinite here (S has positive off-diagonals on distorted charts), so we keep
// a cell's gradient only where every texel whose basis function lives on it has the same source.
#include "texgrad/apps/stitch.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "texgrad/apps/barely_covered.h"
#include "texgrad/apps/gain_compensation.h"
#include "texgrad/apps/surface_normals.h"
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

/// Colour channels that gain compensation touches (not alpha).
int colourChannels(Eigen::Index channels) {
  return static_cast<int>(std::min<Eigen::Index>(channels, 3));
}

/// Solves (alpha W M W + S + lock) x = alpha W M W xbar + div + lock input into `x`; locked
/// texels end exactly at `input` (the uncompensated source values; may be empty without a lock
/// mask). `owned` (the domain's operators, handed over, or null to use the domain's) becomes A:
/// the system matrix is formed in M's own storage once the right-hand side and the barely
/// covered texels' neighbours are formed (in one copy of M's pattern with the domain's), and
/// xbar becomes the initial guess, so neither is held through the solver's set-up and cycles.
/// The solver is gone when this returns.
StitchResult solveStitch(const TexelDomain& domain, std::unique_ptr<TexelOperators> owned,
                         Eigen::MatrixXd xbar, const Eigen::MatrixXd& input, Eigen::VectorXd known,
                         Eigen::MatrixXd divergence, const StitchOptions& options,
                         const ProgressCallback& progress, Eigen::MatrixXd& x) {
  const TexelGrid& grid = domain.grid();
  const TexelOperators& ops = owned ? *owned : domain.operators();
  const auto n = static_cast<Eigen::Index>(grid.unknownCount());
  const SparseMatrixd& mass = ops.mass();
  const SparseViewd stiffness = ops.stiffness();
  if (!mass.isCompressed() || stiffness.nonZeros() != mass.nonZeros())
    throw InvalidInputError("solveStitch: M and S must share one compressed pattern");
  // rhs = alpha W M W xbar + div with W = diag(known), applied as scalings (no weighted copy
  // of M).
  Eigen::MatrixXd rhs = known.asDiagonal() * xbar;
  rhs = options.alpha * (known.asDiagonal() * (mass * rhs)) + divergence;
  divergence.resize(0, 0);
  StitchResult result;
  std::vector<uint8_t> locked(static_cast<size_t>(n), 0);
  Eigen::VectorXd lockValues;
  if (!options.lock.empty()) {
    checkSize(grid, options.lock, "the lock mask");
    lockValues = channelZero(grid, options.lock);
    for (Eigen::Index u = 0; u < n; ++u)
      if (lockValues[u] > 0.5) locked[static_cast<size_t>(u)] = 1;
  }
  BarelyCoveredNeighbours bound;
  if (!options.rawSolution) {
    std::vector<int32_t> barely = barelyCoveredUnknowns(domain);
    std::erase_if(barely, [&](int32_t u) { return locked[static_cast<size_t>(u)] != 0; });
    bound = barelyCoveredNeighbours(mass, std::move(barely));
  }
  // A = alpha W M W + 1e-6 alpha M + S; a little plain screening keeps components that no
  // source sees solvable. Formed in M's own storage when the operators are ours (`ops` and
  // `mass` are not used again).
  const EntryCombination entry = [&](Eigen::Index r, Eigen::Index c, double m, double s) {
    return options.alpha * (m * (known[r] * known[c])) + 1e-6 * options.alpha * m + s;
  };
  Eigen::SparseMatrix<double> a =
      owned ? TexelOperators::combined(std::move(owned), entry) : ops.combined(entry);
  known.resize(0);
  if (!options.lock.empty()) {
    double maxDiagonal = 0.0;
    for (Eigen::Index u = 0; u < n; ++u) maxDiagonal = std::max(maxDiagonal, a.coeff(u, u));
    const double weight = 1e8 * maxDiagonal;
    for (Eigen::Index u = 0; u < n; ++u) {
      if (!locked[static_cast<size_t>(u)]) continue;
      a.coeffRef(u, u) += weight;
      rhs.row(u) += weight * input.row(u);
      ++result.lockedTexels;
    }
  }
  const Eigen::MatrixXd boundInput = xbar(bound.unknowns, Eigen::all);
  x = std::move(xbar);
  {
    SystemSolver solver(grid, options.solver);
    solver.initAndUpdate(std::move(a), progress);
    result.report = solver.solve(rhs, x, progress);
  }
  rhs.resize(0, 0);
  boundBarelyCovered(bound, boundInput, x);
  for (Eigen::Index u = 0; u < n; ++u)
    if (locked[static_cast<size_t>(u)]) x.row(u) = input.row(u);  // exactly the input
  return result;
}

/// Unknowns whose basis functions can be non-zero on each covered cell: the four corners, plus
/// (on cells a chart boundary crosses, where seams couple the two sides) every unknown that
/// shares a stiffness entry with a corner. Calls f(cell, list).
template <typename F>
void forEachCoveredCell(const TexelGrid& g, const SparseRefd& s, F&& f) {
  std::vector<int32_t> texels;
  for (int b = -1; b < g.ny; ++b)
    for (int a = -1; a < g.nx; ++a) {
      const int cell = g.cellIndex(a, b);
      if (g.cellCoverage[cell] == CellCoverage::Empty) continue;
      texels.clear();
      for (int y = b; y <= b + 1; ++y)
        for (int x = a; x <= a + 1; ++x) {
          const int32_t u = (x >= 0 && y >= 0 && x < g.nx && y < g.ny)
                                ? g.unknownOfTexel[g.texelIndex(x, y)]
                                : -1;
          texels.push_back(u);
          if (u < 0 || g.cellCoverage[cell] == CellCoverage::Full) continue;
          for (SparseRefd::InnerIterator it(s, u); it; ++it)
            texels.push_back(static_cast<int32_t>(it.row()));
        }
      f(cell, texels);
    }
}

/// Throws InvalidInputError unless every view has `channels` channels, consistent array sizes
/// and strictly ascending unknowns below n.
void checkViews(const std::vector<PartialView>& views, int channels, Eigen::Index n) {
  for (size_t i = 0; i < views.size(); ++i) {
    const PartialView& v = views[i];
    const std::string name = "partial " + std::to_string(i);
    if (v.channels != channels)
      throw InvalidInputError(name + " has " + std::to_string(v.channels) +
                              " channels, partial 0 has " + std::to_string(channels));
    if (v.values.size() != v.size() * static_cast<size_t>(channels) ||
        v.confidence.size() != v.size())
      throw InvalidInputError(name + ": values, confidence and unknowns differ in length");
    for (size_t e = 0; e < v.size(); ++e)
      if (v.unknowns[e] < 0 || v.unknowns[e] >= n || (e > 0 && v.unknowns[e] <= v.unknowns[e - 1]))
        throw InvalidInputError(name + ": unknowns must be ascending indices below " +
                                std::to_string(n));
  }
}

/// Per-view colour compensation of partials mode: none, one gain per channel, or the
/// illumination model (gain_compensation.h); applied to a view's values as they are read, so
/// the compact views stay as projected.
struct Compensation {
  Eigen::MatrixXd gains;         ///< sources x colour channels (ones when off)
  Eigen::MatrixXd illumination;  ///< solveLogIllumination's result, or empty
  Eigen::MatrixX3d normals;      ///< unit normal per unknown while illumination is used
  bool gainsOnly = false;        ///< divide by gains (true) or by the illumination (if any)
  int colour = 0;                ///< colour channels it touches

  /// Entry e of view i (unknown u), compensated, into `row`.
  void read(const PartialView& view, size_t i, size_t e, Eigen::RowVectorXd& row) const {
    const auto u = static_cast<Eigen::Index>(view.unknowns[e]);
    for (int c = 0; c < view.channels; ++c)
      row[c] = view.values[e * static_cast<size_t>(view.channels) + static_cast<size_t>(c)];
    const auto k = static_cast<int>(i);
    for (int c = 0; c < colour; ++c) {
      if (gainsOnly)
        row[c] /= gains(k, c);
      else if (illumination.size() > 0)
        row[c] /= std::exp(logIllumination(illumination, k, normals, u, c));
    }
  }
};

/// Estimates the compensation of partials mode from the views' overlaps.
Compensation estimateCompensation(const TexelDomain& domain, const TexelOperators& ops,
                                  const std::vector<PartialView>& views, int channels,
                                  const StitchOptions& options) {
  Compensation comp;
  comp.colour = colourChannels(channels);
  const int sources = static_cast<int>(views.size());
  comp.gains = Eigen::MatrixXd::Ones(sources, comp.colour);
  if (!options.compensateGains || sources < 2) return comp;
  Eigen::VectorXd texelsPerSource(sources);
  for (int i = 0; i < sources; ++i)
    texelsPerSource[i] = static_cast<double>(views[static_cast<size_t>(i)].size());
  if (!options.compensateIllumination) {
    comp.gains =
        solveLogGains(sources, comp.colour, partialGainLinks(views, comp.colour), texelsPerSource)
            .array()
            .exp();
    comp.gainsOnly = true;
    return comp;
  }
  comp.normals = texelNormals(domain, ops);
  comp.illumination = solveLogIllumination(sources, comp.colour,
                                           partialShadingSamples(views, comp.normals, comp.colour),
                                           texelsPerSource);
  // Each source's gain is its geometric-mean illumination over the texels it sees.
  for (int i = 0; i < sources; ++i) {
    const PartialView& view = views[static_cast<size_t>(i)];
    Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(comp.colour);
    for (int32_t u : view.unknowns)
      for (int c = 0; c < comp.colour; ++c)
        mean[c] += logIllumination(comp.illumination, i, comp.normals, u, c);
    if (view.size() > 0) mean /= static_cast<double>(view.size());
    comp.gains.row(i) = mean.array().exp();
  }
  return comp;
}

/// Confidence-weighted mean of the views' values (compensated by `comp`, if given) per unknown;
/// zero where no view sees it. `weight` receives the summed confidence.
Eigen::MatrixXd blendViews(const std::vector<PartialView>& views, Eigen::Index n, int channels,
                           const Compensation* comp, Eigen::VectorXd& weight) {
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, channels);
  weight = Eigen::VectorXd::Zero(n);
  Eigen::RowVectorXd row(channels);
  for (size_t i = 0; i < views.size(); ++i)
    for (size_t e = 0; e < views[i].size(); ++e) {
      const int32_t u = views[i].unknowns[e];
      const double c = views[i].confidence[e];
      if (comp) {
        comp->read(views[i], i, e, row);
      } else {
        for (int ch = 0; ch < channels; ++ch)
          row[ch] = views[i].values[e * static_cast<size_t>(channels) + static_cast<size_t>(ch)];
      }
      sum.row(u) += c * row;
      weight[u] += c;
    }
  for (Eigen::Index u = 0; u < n; ++u)
    if (weight[u] > 0.0) sum.row(u) /= weight[u];
  return sum;
}

/// Per covered cell, the smallest confidence of `view` over the texels whose basis functions
/// live on the cell (0 if one is unseen or outside the domain); calls f(cell, least).
template <typename F>
void forEachCellLeast(const TexelGrid& grid, const SparseRefd& stiffness, const PartialView& view,
                      F&& f) {
  std::vector<float> dense(static_cast<size_t>(grid.unknownCount()), 0.0f);
  for (size_t e = 0; e < view.size(); ++e)
    dense[static_cast<size_t>(view.unknowns[e])] = view.confidence[e];
  forEachCoveredCell(grid, stiffness, [&](int cell, const std::vector<int32_t>& texels) {
    double least = 1.0;
    for (int32_t u : texels)
      least = u >= 0 ? std::min(least, static_cast<double>(dense[static_cast<size_t>(u)])) : 0.0;
    f(cell, least);
  });
}

/// out += S X for X zero but at rows `seen` (ascending), where it is `values` (seen.size() x k):
/// Eigen's column-major sparse times dense product (per column of X, the columns of S in
/// ascending order) restricted to the columns that can add anything, without forming X.
void addSeenProduct(const SparseMatrixd& s, const std::vector<int32_t>& seen,
                    const Eigen::MatrixXd& values, Eigen::MatrixXd& out) {
  for (Eigen::Index c = 0; c < values.cols(); ++c)
    for (size_t e = 0; e < seen.size(); ++e) {
      const double v = values(static_cast<Eigen::Index>(e), c);
      for (SparseMatrixd::InnerIterator it(s, seen[e]); it; ++it)
        out(it.index(), c) += it.value() * v;
    }
}

/// Partials mode on compact views: compensation, blend, target divergence, then the views are
/// freed and the system solved into `x`.
StitchResult stitchViews(const TexelDomain& domain, std::unique_ptr<TexelOperators> owned,
                         std::vector<PartialView> views, const StitchOptions& options,
                         const ProgressCallback& progress, Eigen::MatrixXd& x) {
  const TexelOperators& ops = owned ? *owned : domain.operators();
  const TexelGrid& grid = domain.grid();
  const auto n = static_cast<Eigen::Index>(grid.unknownCount());
  const int channels = views[0].channels;
  checkViews(views, channels, n);
  Eigen::VectorXd weight;
  // The lock keeps the confidence-weighted mean of the partials as given.
  const Eigen::MatrixXd input =
      options.lock.empty() ? Eigen::MatrixXd() : blendViews(views, n, channels, nullptr, weight);
  Compensation comp = estimateCompensation(domain, ops, views, channels, options);
  Eigen::MatrixXd xbar = blendViews(views, n, channels, &comp, weight);
  Eigen::VectorXd known(n);
  for (Eigen::Index u = 0; u < n; ++u) known[u] = weight[u] > 0.0 ? 1.0 : 0.0;
  weight.resize(0);
  // A partial's weight on a cell = its smallest confidence over the cell's texels; the target
  // gradient is the weighted mean of the partials' gradients, zero where none sees the cell.
  // One view at a time: the per-cell sums first, then each view's normalised weights.
  const SparseViewd stiffness = ops.stiffness();
  std::vector<double> total(grid.cellCoverage.size(), 0.0), beta(total.size());
  for (const PartialView& view : views)
    forEachCellLeast(grid, stiffness, view, [&](int cell, double least) { total[cell] += least; });
  Eigen::MatrixXd divergence = Eigen::MatrixXd::Zero(n, channels), values;
  Eigen::RowVectorXd row(channels);
  for (size_t i = 0; i < views.size(); ++i) {
    std::fill(beta.begin(), beta.end(), 0.0);
    forEachCellLeast(grid, stiffness, views[i], [&](int cell, double least) {
      beta[cell] = total[cell] > 0.0 ? least / total[cell] : 0.0;
    });
    values.resize(static_cast<Eigen::Index>(views[i].size()), channels);
    for (size_t e = 0; e < views[i].size(); ++e) {
      comp.read(views[i], i, e, row);
      values.row(static_cast<Eigen::Index>(e)) = row;
    }
    addSeenProduct(ops.modulatedStiffness(beta), views[i].unknowns, values, divergence);
  }
  StitchResult result;
  result.sources = static_cast<int>(views.size());
  result.sourceGains = comp.gains;
  result.sourceIllumination = comp.illumination;
  // Nothing of the views is needed past this point: free them before the solver is set up.
  std::vector<PartialView>().swap(views);
  comp = Compensation{};
  values.resize(0, 0);
  std::vector<double>().swap(total);
  std::vector<double>().swap(beta);
  const StitchResult solved =
      solveStitch(domain, std::move(owned), std::move(xbar), input, std::move(known),
                  std::move(divergence), options, progress, x);
  result.report = solved.report;
  result.lockedTexels = solved.lockedTexels;
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
                             const Image& segments, const StitchOptions& options,
                             const ProgressCallback& progress) {
  return stitchComposite(domain, nullptr, composite, segments, options, progress);
}

StitchResult stitchComposite(const TexelDomain& domain, std::unique_ptr<TexelOperators> owned,
                             const Image& composite, const Image& segments,
                             const StitchOptions& options, const ProgressCallback& progress) {
  options.validate();
  const TexelOperators& ops = owned ? *owned : domain.operators();
  const TexelGrid& grid = domain.grid();
  checkSize(grid, composite, "the composite texture");
  checkSize(grid, segments, "the segment mask");
  int sources = 0;
  const std::vector<int32_t> labels = sourceLabels(grid, segments, sources);
  Eigen::MatrixXd xbar = gatherTexels(grid, composite);
  // The lock keeps the composite as given (before compensation).
  const Eigen::MatrixXd input = options.lock.empty() ? Eigen::MatrixXd() : xbar;
  const int channels = colourChannels(xbar.cols());
  Eigen::MatrixXd gains = Eigen::MatrixXd::Ones(sources, channels), illumination;
  if (options.compensateGains && sources > 1) {
    Eigen::VectorXd texelsPerSource = Eigen::VectorXd::Zero(sources);
    for (int32_t label : labels)
      if (label > 0) texelsPerSource[label - 1] += 1.0;
    const SparseViewd coupling = ops.stiffness();
    if (options.compensateIllumination) {
      const Eigen::MatrixX3d normals = texelNormals(domain, ops);
      illumination = solveLogIllumination(
          sources, channels, compositeShadingSamples(coupling, labels, xbar, normals, channels),
          texelsPerSource);
      std::vector<std::vector<Eigen::Index>> rows(static_cast<size_t>(sources));
      for (Eigen::Index u = 0; u < xbar.rows(); ++u)
        if (labels[u] > 0) rows[static_cast<size_t>(labels[u] - 1)].push_back(u);
      for (int k = 0; k < sources; ++k) {
        gains.row(k) = removeIllumination(illumination, k, normals, rows[static_cast<size_t>(k)],
                                          channels, xbar)
                           .array()
                           .exp();
      }
    } else {
      const auto links = compositeGainLinks(coupling, labels, xbar, channels);
      gains = solveLogGains(sources, channels, links, texelsPerSource).array().exp();
      for (Eigen::Index u = 0; u < xbar.rows(); ++u)
        if (labels[u] > 0) xbar.row(u).head(channels).array() /= gains.row(labels[u] - 1).array();
    }
  }
  Eigen::VectorXd known(xbar.rows());
  for (Eigen::Index u = 0; u < xbar.rows(); ++u) known[u] = labels[u] > 0 ? 1.0 : 0.0;
  // Keep the gradient on cells whose texels all come from one source; zero elsewhere.
  std::vector<double> beta(grid.cellCoverage.size(), 0.0);
  forEachCoveredCell(grid, ops.stiffness(), [&](int cell, const std::vector<int32_t>& texels) {
    bool same = true;
    for (int32_t u : texels) same &= u >= 0 && labels[u] > 0 && labels[u] == labels[texels[0]];
    beta[cell] = same ? 1.0 : 0.0;
  });
  Eigen::MatrixXd divergence = ops.modulatedStiffness(beta) * xbar;
  std::vector<double>().swap(beta);
  Eigen::MatrixXd x;
  StitchResult result = solveStitch(domain, std::move(owned), std::move(xbar), input,
                                    std::move(known), std::move(divergence), options, progress, x);
  result.image = composite;
  scatterTexels(grid, x, result.image);
  result.sources = sources;
  result.sourceGains = gains;
  result.sourceIllumination = illumination;
  return result;
}

StitchResult stitchPartials(const TexelDomain& domain, const std::vector<Image>& partials,
                            const std::vector<Image>& confidences, const StitchOptions& options,
                            const ProgressCallback& progress) {
  options.validate();
  if (partials.empty()) throw InvalidInputError("stitching needs at least one partial texture");
  if (partials.size() != confidences.size())
    throw InvalidInputError(std::to_string(partials.size()) + " partial textures but " +
                            std::to_string(confidences.size()) +
                            " confidence maps; give one confidence map per partial");
  const TexelGrid& grid = domain.grid();
  std::vector<PartialView> views;
  for (size_t i = 0; i < partials.size(); ++i) {
    const std::string name = "partial " + std::to_string(i);
    checkSize(grid, partials[i], name);
    checkSize(grid, confidences[i], "confidence " + std::to_string(i));
    if (partials[i].channels != partials[0].channels)
      throw InvalidInputError(name + " has " + std::to_string(partials[i].channels) +
                              " channels, partial 0 has " + std::to_string(partials[0].channels));
    views.push_back(compactPartial(grid, partials[i], confidences[i]));
  }
  Eigen::MatrixXd x;
  StitchResult result = stitchViews(domain, nullptr, std::move(views), options, progress, x);
  result.image = partials[0];
  scatterTexels(grid, x, result.image);
  return result;
}

StitchResult stitchPartials(const TexelDomain& domain, std::vector<PartialView> views,
                            PixelFormat format, const StitchOptions& options,
                            const ProgressCallback& progress) {
  return stitchPartials(domain, nullptr, std::move(views), format, options, progress);
}

StitchResult stitchPartials(const TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                            std::vector<PartialView> views, PixelFormat format,
                            const StitchOptions& options, const ProgressCallback& progress) {
  options.validate();
  if (views.empty()) throw InvalidInputError("stitching needs at least one partial texture");
  const int channels = views[0].channels;
  Eigen::MatrixXd x;
  StitchResult result =
      stitchViews(domain, std::move(operators), std::move(views), options, progress, x);
  const TexelGrid& grid = domain.grid();
  result.image = Image(grid.imageWidth, grid.imageHeight, channels, format);
  scatterTexels(grid, x, result.image);
  return result;
}

}  // namespace texgrad
