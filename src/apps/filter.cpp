// Screened Poisson filtering (paper §7.1): (alpha M + S) x* = (alpha M + S_beta) x, where S_beta
// is beta S, or sum_c beta_c S_c for a painted map. With the bilinear baseline basis the system
// also holds the soft seam energy alpha lambda E_C (paper §4.2, Fig. 5).
#include "texgrad/apps/filter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "texgrad/apps/normal_map.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_levels.h"
#include "texgrad/solver/conjugate_gradient.h"

namespace texgrad {
namespace {

void checkAlpha(double alpha) {
  if (!(alpha > 0.0) || !std::isfinite(alpha))
    throw InvalidInputError("alpha must be a positive number, got " + std::to_string(alpha));
}

void checkBetaMap(const TexelDomain& domain, const std::vector<double>& betaPerCell) {
  if (!betaPerCell.empty() && betaPerCell.size() != domain.grid().cellCoverage.size())
    throw InvalidInputError("beta map has " + std::to_string(betaPerCell.size()) +
                            " cells, the grid has " +
                            std::to_string(domain.grid().cellCoverage.size()));
}

/// The mass-matrix neighbours of the unknowns whose values image() bounds (none with
/// rawSolution).
BarelyCoveredNeighbours barelyBound(const TexelDomain& domain, const TexelOperators& ops,
                                    const FilterOptions& options) {
  if (options.rawSolution) return {};
  return barelyCoveredNeighbours(ops.mass(), barelyCoveredUnknowns(domain));
}

/// The values the one-shot filter reads x0 from, a channel at a time: a float image, or an 8-bit
/// texture held as its levels (exactByteLevels), each read as the float it decodes to. Either
/// way the values of gatherTexels(grid, image), bit for bit.
class TexelValues {
 public:
  /// `image` (and `levels`, if given: then image's pixels may be empty) must outlive this.
  TexelValues(const TexelGrid& grid, const Image& image, const std::vector<uint8_t>* levels)
      : grid_(grid), image_(image), levels_(levels) {
    requireGridImageSize(grid, image);
  }
  int channels() const { return image_.channels; }
  /// gatherTexels(grid, image)(u, c): the nearest image texel for active texels outside it.
  float operator()(int u, int c) const { return at(pixelOf(u), c); }
  /// Where unknown u's values start in the image's (or levels') interleaved values.
  size_t pixelOf(int u) const {
    const auto [i, j] = imageTexelOf(grid_, u);
    return image_.index(i, j);
  }
  /// Channel c of the values starting at `pixel` (pixelOf).
  float at(size_t pixel, int c) const {
    const size_t k = pixel + static_cast<size_t>(c);
    return levels_ ? levelValues_[(*levels_)[k]] : image_.pixels[k];
  }
  /// Channel c at every unknown: floats, as the values are (half the bytes of doubles).
  Eigen::VectorXf channel(int c) const {
    Eigen::VectorXf values(grid_.unknownCount());
    for (int u = 0; u < grid_.unknownCount(); ++u) values(u) = (*this)(u, c);
    return values;
  }
  /// Every channel at `unknowns` (row i for unknowns[i]).
  Eigen::MatrixXd rows(std::span<const int32_t> unknowns) const {
    Eigen::MatrixXd values(static_cast<Eigen::Index>(unknowns.size()), channels());
    for (size_t i = 0; i < unknowns.size(); ++i)
      for (int c = 0; c < channels(); ++c)
        values(static_cast<Eigen::Index>(i), c) = (*this)(unknowns[i], c);
    return values;
  }

 private:
  const TexelGrid& grid_;
  const Image& image_;
  const std::vector<uint8_t>* levels_;
  const std::array<float, kByteLevels>& levelValues_ = byteLevelValues();
};

/// The filter's right-hand side as it is solved for: rounded to float. Both filters solve with
/// it, so they solve the same system; the one-shot filter holds its channels through the
/// solver's set-up at half the bytes (the float cycles read the rhs at float precision anyway,
/// and the rounding, 6e-8 relative, is far below the solver's tolerance).
Eigen::MatrixXd roundedRightHandSide(const Eigen::MatrixXd& rhs) {
  return rhs.cast<float>().cast<double>();
}

/// alpha M x0 + S_beta x0, one n x 1 float block per channel (roundedRightHandSide), with one
/// channel of x0 and one product held at a time. The same operations per value, in the same
/// order, as InteractiveFilter's from its stored M x0 and S x0, so the same bits; with beta 0
/// and no map S x0 is not formed (InteractiveFilter adds 0 S x0, which changes no value but the
/// sign of a zero).
std::vector<Eigen::MatrixXf> screenedRightHandSide(const TexelOperators& ops, const TexelValues& x0,
                                                   const FilterOptions& options) {
  std::vector<Eigen::MatrixXf> rhs(static_cast<size_t>(x0.channels()));
  const bool mapped = !options.betaPerCell.empty();
  const Eigen::SparseMatrix<double> modulated =
      mapped ? ops.modulatedStiffness(options.betaPerCell) : Eigen::SparseMatrix<double>();
  Eigen::MatrixXd b, product;
  for (int c = 0; c < x0.channels(); ++c) {
    const Eigen::VectorXf x0c = x0.channel(c);
    Eigen::MatrixXf& out = rhs[static_cast<size_t>(c)];
    if (!mapped && options.beta == 0.0) {  // straight into floats: no n x 1 double
      symmetricProduct(ops.mass(), x0c, options.alpha, out);
      continue;
    }
    if (mapped) {
      symmetricProduct(modulated, x0c, b);
      symmetricProduct(ops.mass(), x0c, product);
      b += options.alpha * product;
    } else {
      symmetricProduct(ops.mass(), x0c, b);
      symmetricProduct(ops.stiffness(), x0c, product);
      b = options.alpha * b + options.beta * product;
    }
    out = b.col(0).cast<float>();
  }
  return rhs;
}

/// What the one-shot filter solves: A = alpha M + S (+ alpha lambda C), one right-hand side per
/// channel, and the bound on barely covered texels, which reads M.
struct ScreenedProblem {
  Eigen::SparseMatrix<double> system;
  FloatSystem floatSystem;           ///< A instead of `system`, for a solver that takes it
  std::vector<Eigen::MatrixXf> rhs;  ///< n x 1 each
  BarelyCoveredNeighbours barely;
};

/// ScreenedProblem from operators handed over, without a beta map, gathered from each column of
/// M and S while TexelOperators::screenedSystem combines them: M and S are never held beside A,
/// nor S whole if their assembly was deferred (docs/memory.md). Per value the operations of
/// screenedRightHandSide and barelyCoveredNeighbours, in the same order: the same bits.
/// `barely` are the barely covered unknowns (barelyCoveredUnknowns: ascending) to bound.
void screenColumnByColumn(std::unique_ptr<TexelOperators> operators, std::vector<int32_t> barely,
                          const TexelValues& x0, const FilterOptions& options,
                          const ProgressCallback& progress, ScreenedProblem& out) {
  const int channels = x0.channels();
  const auto unknowns = static_cast<Eigen::Index>(operators->basis().grid().unknownCount());
  out.rhs.assign(static_cast<size_t>(channels), Eigen::MatrixXf(unknowns, 1));
  std::vector<std::vector<int32_t>> neighbours(barely.size());
  const ColumnVisitor visit = [&](const OperatorColumn& column) {
    const int u = column.column;
    // Up to four channels per pass over the column's rows, each row's texel looked up once; per
    // channel the sums run in row order as one channel's would.
    for (int c0 = 0; c0 < channels; c0 += 4) {
      const int group = std::min(4, channels - c0);
      std::array<double, 4> mass{}, stiffness{};
      for (size_t k = 0; k < column.rows.size(); ++k) {
        const size_t pixel = x0.pixelOf(column.rows[k]);
        for (int c = 0; c < group; ++c) {
          const auto x = static_cast<double>(x0.at(pixel, c0 + c));
          mass[c] += column.mass[k] * x;
          if (options.beta != 0.0) stiffness[c] += column.stiffness[k] * x;
        }
      }
      for (int c = 0; c < group; ++c)
        out.rhs[static_cast<size_t>(c0 + c)](u, 0) =
            options.beta == 0.0
                ? static_cast<float>(options.alpha * mass[c])
                : static_cast<float>(options.alpha * mass[c] + options.beta * stiffness[c]);
    }
    const auto at = std::lower_bound(barely.begin(), barely.end(), u);
    if (at == barely.end() || *at != u) return;
    std::vector<int32_t>& around = neighbours[static_cast<size_t>(at - barely.begin())];
    for (size_t k = 0; k < column.rows.size(); ++k)
      if (column.rows[k] != u && column.mass[k] > 0.0) around.push_back(column.rows[k]);
  };
  // In float where the solver takes A so (float cycles keeping no copy): 8 bytes per entry,
  // not 12, with the same stencils and row sums (docs/memory.md).
  if (SystemSolver::takesFloatSystem(options.solver) &&
      operators->options().seamContinuityWeight == 0.0) {
    out.floatSystem =
        TexelOperators::screenedSystemInFloat(std::move(operators), options.alpha, visit, progress);
  } else {
    Eigen::SparseMatrix<double> system =
        TexelOperators::screenedSystem(std::move(operators), options.alpha, visit, progress);
    out.system.swap(system);
  }
  out.barely.start.assign(1, 0);
  for (const std::vector<int32_t>& around : neighbours) {
    out.barely.neighbours.insert(out.barely.neighbours.end(), around.begin(), around.end());
    out.barely.start.push_back(static_cast<int64_t>(out.barely.neighbours.size()));
  }
  out.barely.unknowns = std::move(barely);
}

/// The report of k single-channel solves run in turn, as one solve: iterations summed (the
/// V-cycles or CG iterations, each on one channel); residuals[i] the largest relative residual
/// ||b_c - A x_c|| / ||b_c|| over the channels after i iterations of each (a channel that
/// stopped earlier counts with its last), so residuals.back() is the worst channel's final one;
/// rmsChange[i] over all channels' i-th iterations (a finished channel counts as no change);
/// converged if every channel converged, diverged if one diverged; phase times summed.
SolveReport combinedReport(const std::vector<SolveReport>& reports) {
  SolveReport all;
  all.converged = !reports.empty();
  size_t length = 0;
  for (const SolveReport& r : reports) {
    all.iterations += r.iterations;
    all.converged = all.converged && r.converged;
    all.diverged = all.diverged || r.diverged;
    all.times.relaxation += r.times.relaxation;
    all.times.boundary += r.times.boundary;
    all.times.coarse += r.times.coarse;
    all.times.transfer += r.times.transfer;
    all.times.matvec += r.times.matvec;
    all.times.preconditioner += r.times.preconditioner;
    all.times.other += r.times.other;
    length = std::max(length, r.residuals.size());
  }
  all.residuals.assign(length, 0.0);
  all.rmsChange.assign(length > 0 ? length - 1 : 0, 0.0);
  for (const SolveReport& r : reports) {
    for (size_t i = 0; i < length && !r.residuals.empty(); ++i)
      all.residuals[i] =
          std::max(all.residuals[i], r.residuals[std::min(i, r.residuals.size() - 1)]);
    for (size_t i = 0; i < r.rmsChange.size() && i < all.rmsChange.size(); ++i)
      all.rmsChange[i] += r.rmsChange[i] * r.rmsChange[i] / static_cast<double>(reports.size());
  }
  for (double& change : all.rmsChange) change = std::sqrt(change);
  return all;
}

/// Runs `solveChannel(c, progress)` for each of `channels` in turn and combines the reports
/// (combinedReport). `progress` sees one "solve" stage across them: fraction (c + f) / channels
/// and the iterations done in all channels so far, of channels times each solve's most.
template <typename SolveChannel>
SolveReport solveEachChannel(int channels, const ProgressCallback& progress,
                             SolveChannel&& solveChannel) {
  std::vector<SolveReport> reports;
  int done = 0;
  for (int c = 0; c < channels; ++c) {
    ProgressCallback channelProgress;
    if (progress)
      channelProgress = [&progress, c, channels, done](const Progress& p) {
        return progress(
            Progress{p.stage, (c + p.fraction) / channels, done + p.step, channels * p.steps});
      };
    reports.push_back(solveChannel(c, channelProgress));
    done += reports.back().iterations;
  }
  return combinedReport(reports);
}

/// The solution `values` (unknowns x channels, already bounded) in `input`'s storage: active
/// in-image texels replaced, everything else the input bit for bit. A normal map's values are
/// vectors: scattered into `decoded` (its decoded input), renormalised and encoded first.
Image filteredImage(const TexelGrid& grid, Image input, Image decoded, bool normalMap,
                    const Eigen::MatrixXd& values) {
  if (!normalMap) {
    scatterTexels(grid, values, input);
    return input;
  }
  scatterTexels(grid, values, decoded);
  renormalize(decoded);
  const Image solved = encodeNormalMap(decoded, input);
  for (int32_t t : grid.texelOfUnknown) {
    const int x = t % grid.nx, y = t / grid.nx;
    if (!grid.inImage(x, y)) continue;
    for (int c = 0; c < input.channels; ++c)
      input.at(x + grid.x0, y + grid.y0, c) = solved.at(x + grid.x0, y + grid.y0, c);
  }
  return input;
}

/// The one-shot filter on `ops`; `owned`, if given, holds `ops` and is freed before set-up;
/// `mapsOwner`, if given, is `domain`, whose grid maps are freed once nothing reads them.
/// Solves one channel at a time (solveEachChannel): the multigrid's level vectors and CG's work
/// vectors hold one channel, not all; x0 exists a channel at a time, for the right-hand side
/// and again as each channel's initial guess, so only the k right-hand sides (n x 1 floats each)
/// live through the set-up.
FilterResult filterOnce(const TexelDomain& domain, const TexelOperators& ops,
                        std::unique_ptr<TexelOperators> owned, TexelDomain* mapsOwner,
                        Image texture, std::optional<std::vector<uint8_t>> levels,
                        const FilterOptions& options, const ProgressCallback& progress) {
  options.validate();
  checkBetaMap(domain, options.betaPerCell);
  if (levels && options.normalMap) texture.pixels = valuesOfByteLevels(*levels);
  Image decoded = options.normalMap ? decodeNormalMap(texture) : Image();
  // Until the result is written, an 8-bit texture is held as its levels: 1 byte per value
  // instead of a float (38 MB less from here to the write-back at spot 2048²).
  if (!levels) levels = exactByteLevels(texture);
  if (levels) texture.pixels = std::vector<float>();
  const TexelValues x0 = options.normalMap
                             ? TexelValues(domain.grid(), decoded, nullptr)
                             : TexelValues(domain.grid(), texture, levels ? &*levels : nullptr);
  // The grid's maps go once nothing reads them: all but the texels' class and chart once the
  // barely covered texels are found, or once A is formed if a deferred assembly or a beta map
  // (modulatedStiffness integrates the pieces of every cell again) reads them; those once the
  // solver's hierarchy is built.
  const bool mapped = !options.betaPerCell.empty();
  bool mapsKept = mapsOwner != nullptr;
  ScreenedProblem problem;
  if (owned && !mapped) {
    std::vector<int32_t> barelyUnknowns =
        options.rawSolution ? std::vector<int32_t>() : barelyCoveredUnknowns(domain);
    if (mapsKept && !owned->assemblyDeferred()) {
      mapsOwner->releaseImageMaps(TexelDomain::KeptMaps::ClassAndChart);
      mapsKept = false;
    }
    screenColumnByColumn(std::move(owned), std::move(barelyUnknowns), x0, options, progress,
                         problem);
  } else {
    problem.barely = barelyBound(domain, ops, options);
    problem.rhs = screenedRightHandSide(ops, x0, options);
    // From here on only A is needed: formed in M's storage when the operators are ours, which
    // frees S with them (`ops` is not used again); rounded as screenColumnByColumn forms it
    // where the solver takes that, so every filter solves one system.
    const bool rounded =
        SystemSolver::takesFloatSystem(options.solver) && ops.options().seamContinuityWeight == 0.0;
    const std::vector<uint8_t> exact = rounded ? ops.exactUnknowns() : std::vector<uint8_t>();
    Eigen::SparseMatrix<double> system =
        owned ? TexelOperators::screenedSystem(std::move(owned), options.alpha)
              : ops.screenedSystem(options.alpha);
    if (rounded)
      problem.floatSystem = roundedSystem(std::move(system), exact);
    else
      problem.system.swap(system);
  }
  if (mapsKept) mapsOwner->releaseImageMaps(TexelDomain::KeptMaps::ClassAndChart);
  const BarelyCoveredNeighbours& barely = problem.barely;
  const Eigen::MatrixXd barelyX0 = x0.rows(barely.unknowns);
  std::vector<Eigen::MatrixXf>& rhs = problem.rhs;
  // Built once S is freed (the hierarchy is larger than the class and chart maps it reads, its
  // only read of the grid), then those maps go too.
  std::optional<SystemSolver> solver(std::in_place, domain.grid(), options.solver);
  if (mapsOwner) mapsOwner->releaseImageMaps();
  if (problem.floatSystem.rows() > 0)
    solver->initAndUpdate(std::move(problem.floatSystem), progress);
  else
    solver->initAndUpdate(std::move(problem.system), progress);
  FilterResult result;
  // Each channel is solved on float b and x (SystemSolver::floatIterates: CG keeps its iterate
  // and residual in float too, by default, the residual in b's storage), and its solution kept
  // as floats, the image's own type, until all are solved.
  std::vector<Eigen::MatrixXf> solved(rhs.size());
  result.report = solveEachChannel(
      x0.channels(), progress, [&](int c, const ProgressCallback& channelProgress) {
        const auto k = static_cast<size_t>(c);
        Eigen::MatrixXf channel = x0.channel(c);  // the initial guess
        const SolveReport report = solver->solve(std::move(rhs[k]), channel, channelProgress);
        solved[k] = std::move(channel);
        return report;
      });
  result.initSeconds = solver->initSeconds();
  result.updateSeconds = solver->updateSeconds();
  result.solverStorageBytes = solver->storageBytes();
  solver.reset();
  if (levels) {
    texture.pixels = valuesOfByteLevels(*levels);
    levels.reset();
  }
  if (!options.normalMap) {
    // A channel at a time into the texture: the bound treats channels apart, so this is the
    // whole-block result's bits without a double copy of every channel (8 bytes per value).
    for (size_t k = 0; k < solved.size(); ++k) {
      Eigen::MatrixXd channel = solved[k].cast<double>();
      solved[k] = Eigen::MatrixXf();
      boundBarelyCovered(barely, barelyX0.col(static_cast<Eigen::Index>(k)), channel);
      scatterTexelChannel(domain.grid(), channel.col(0), static_cast<int>(k), texture);
    }
    result.image = std::move(texture);
    return result;
  }
  Eigen::MatrixXd x(domain.unknowns(), x0.channels());
  for (size_t k = 0; k < solved.size(); ++k) {
    x.col(static_cast<Eigen::Index>(k)) = solved[k].cast<double>();
    solved[k] = Eigen::MatrixXf();
  }
  boundBarelyCovered(barely, barelyX0, x);
  result.image = filteredImage(domain.grid(), std::move(texture), std::move(decoded), true, x);
  return result;
}

}  // namespace

void FilterOptions::validate() const {
  checkAlpha(alpha);
  if (!std::isfinite(beta)) throw InvalidInputError("beta must be a finite number");
  for (double b : betaPerCell)
    if (!std::isfinite(b)) throw InvalidInputError("the beta map holds a non-finite value");
  solver.validate();
}

InteractiveFilter::InteractiveFilter(const TexelDomain& domain, Image texture,
                                     const FilterOptions& options, const ProgressCallback& progress)
    : domain_(domain),
      input_(std::move(texture)),
      // A colour texture is solved on input_ itself: no second whole-image copy (24 bytes per
      // active texel at spot's coverage).
      working_(options.normalMap ? decodeNormalMap(input_) : Image()),
      normalMap_(options.normalMap),
      solver_(domain.grid(), options.solver) {
  options.validate();
  x0_ = gatherTexels(domain.grid(), normalMap_ ? working_ : input_);
  x_ = x0_;
  symmetricProduct(domain.operators().mass(), x0_, massX0_);
  symmetricProduct(domain.operators().stiffness(), x0_, stiffnessX0_);
  barely_ = barelyBound(domain, domain.operators(), options);
  applyParameters(options.alpha, options.beta, options.betaPerCell, progress);
}

void InteractiveFilter::setParameters(double alpha, double beta, std::vector<double> betaPerCell) {
  applyParameters(alpha, beta, std::move(betaPerCell), {});
}

void InteractiveFilter::applyParameters(double alpha, double beta, std::vector<double> betaPerCell,
                                        const ProgressCallback& progress) {
  checkAlpha(alpha);
  checkBetaMap(domain_, betaPerCell);
  const TexelOperators& ops = domain_.operators();
  // alpha M x0 + S_beta x0 from the stored products (no scaled copy of S, hundreds of MB at
  // 2048²); a painted map needs its own S_beta.
  if (betaPerCell.empty()) {
    rhs_ = alpha * massX0_ + beta * stiffnessX0_;
  } else {
    symmetricProduct(ops.modulatedStiffness(betaPerCell), x0_, rhs_);
    rhs_ += alpha * massX0_;
  }
  rhs_ = roundedRightHandSide(rhs_);
  // The system matrix depends on alpha only: painting beta changes just the right-hand side.
  if (alpha == alpha_) return;
  const bool first = alpha_ == 0.0;
  alpha_ = alpha;
  // alpha M + S (+ alpha lambda C, paper §4.2); the pattern is the same for every alpha.
  // As the one-shot filter hands it over: rounded to float where the solver takes that, so
  // both solve the same system (roundedSystem gives screenedSystemInFloat's values and sums).
  if (solver_.takesFloatSystem() && ops.options().seamContinuityWeight == 0.0) {
    if (exactUnknowns_.empty()) exactUnknowns_ = ops.exactUnknowns();
    if (first)
      solver_.initAndUpdate(roundedSystem(ops.screenedSystem(alpha), exactUnknowns_), progress);
    else
      solver_.update(roundedSystem(ops.screenedSystem(alpha), exactUnknowns_), progress);
  } else if (first) {
    solver_.initAndUpdate(ops.screenedSystem(alpha), progress);
  } else {
    solver_.update(ops.screenedSystem(alpha), progress);
  }
}

SolveReport InteractiveFilter::step(const ProgressCallback& progress) {
  return solver_.step(rhs_, x_, progress);
}

SolveReport InteractiveFilter::solve(const ProgressCallback& progress) {
  // Every channel at once (unlike the one-shot filter): a cancelled solve leaves all channels
  // advanced alike, which is what an interactive preview shows.
  return solver_.solve(rhs_, x_, progress);
}

Image InteractiveFilter::image() const {
  Eigen::MatrixXd bounded;
  if (!barely_.unknowns.empty()) {
    bounded = x_;
    boundBarelyCovered(barely_, x0_(barely_.unknowns, Eigen::all), bounded);
  }
  return filteredImage(domain_.grid(), input_, working_, normalMap_,
                       barely_.unknowns.empty() ? x_ : bounded);
}

FilterResult filterTexture(const TexelDomain& domain, Image texture, const FilterOptions& options,
                           const ProgressCallback& progress) {
  return filterOnce(domain, domain.operators(), nullptr, nullptr, std::move(texture), std::nullopt,
                    options, progress);
}

namespace {

/// The one-shot filter on operators handed over by the caller (both consuming overloads): checks
/// they are the domain's, and frees the grid's maps too when the domain holds no operators.
FilterResult filterHandedOver(TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                              Image texture, std::optional<std::vector<uint8_t>> levels,
                              const FilterOptions& options, const ProgressCallback& progress) {
  if (!operators || &operators->basis().grid() != &domain.grid())
    throw InvalidInputError(
        "filterTexture: the operators handed over are not the domain's "
        "(TexelDomain::releaseOperators)");
  const TexelOperators& ops = *operators;
  TexelDomain* mapsOwner = domain.hasOperators() ? nullptr : &domain;
  return filterOnce(domain, ops, std::move(operators), mapsOwner, std::move(texture),
                    std::move(levels), options, progress);
}

}  // namespace

FilterResult filterTexture(TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                           Image texture, const FilterOptions& options,
                           const ProgressCallback& progress) {
  return filterHandedOver(domain, std::move(operators), std::move(texture), std::nullopt, options,
                          progress);
}

FilterResult filterTexture(TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                           Image texture, std::vector<uint8_t> levels, const FilterOptions& options,
                           const ProgressCallback& progress) {
  const size_t values = static_cast<size_t>(texture.width) * static_cast<size_t>(texture.height) *
                        static_cast<size_t>(texture.channels);
  if (texture.format != PixelFormat::UInt8 || levels.size() != values)
    throw InvalidInputError("filterTexture: the levels handed over are not those of an 8-bit " +
                            std::to_string(texture.width) + "x" + std::to_string(texture.height) +
                            "x" + std::to_string(texture.channels) + " texture (exactByteLevels)");
  texture.pixels = std::vector<float>();
  return filterHandedOver(domain, std::move(operators), std::move(texture), std::move(levels),
                          options, progress);
}

}  // namespace texgrad
