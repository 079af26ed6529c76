// Screened Poisson filtering (paper §7.1): (alpha M + S) x* = (alpha M + S_beta) x, where S_beta
// is beta S, or sum_c beta_c S_c for a painted map. With the bilinear baseline basis the system
// also holds the soft seam energy alpha lambda E_C (paper §4.2, Fig. 5).
#include "texgrad/apps/filter.h"

#include <cmath>
#include <optional>
#include <utility>

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

/// alpha M x0 + S_beta x0 with one product held at a time. The same operations, in the same
/// order, as InteractiveFilter's from its stored M x0 and S x0, so the same bits.
Eigen::MatrixXd screenedRightHandSide(const TexelOperators& ops, const Eigen::MatrixXd& x0,
                                      const FilterOptions& options) {
  Eigen::MatrixXd rhs, product;
  if (options.betaPerCell.empty()) {
    symmetricProduct(ops.mass(), x0, rhs);
    symmetricProduct(ops.stiffness(), x0, product);
    rhs = options.alpha * rhs + options.beta * product;
  } else {
    symmetricProduct(ops.modulatedStiffness(options.betaPerCell), x0, rhs);
    symmetricProduct(ops.mass(), x0, product);
    rhs += options.alpha * product;
  }
  return rhs;
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

/// The one-shot filter on `ops`; `owned`, if given, holds `ops` and is freed before set-up.
FilterResult filterOnce(const TexelDomain& domain, const TexelOperators& ops,
                        std::unique_ptr<TexelOperators> owned, Image texture,
                        const FilterOptions& options, const ProgressCallback& progress) {
  options.validate();
  checkBetaMap(domain, options.betaPerCell);
  SystemSolver solver(domain.grid(), options.solver);
  Image decoded = options.normalMap ? decodeNormalMap(texture) : Image();
  // x0, then the initial guess and the solution in the same storage.
  Eigen::MatrixXd x = gatherTexels(domain.grid(), options.normalMap ? decoded : texture);
  // Until the result is written, an 8-bit texture is held as its levels: 1 byte per value
  // instead of a float (38 MB less from here to the write-back at spot 2048²).
  std::optional<std::vector<uint8_t>> levels = exactByteLevels(texture);
  if (levels) texture.pixels = std::vector<float>();
  const BarelyCoveredNeighbours barely = barelyBound(domain, ops, options);
  const Eigen::MatrixXd barelyX0 = x(barely.unknowns, Eigen::all);
  const Eigen::MatrixXd rhs = screenedRightHandSide(ops, x, options);
  // From here on only A is needed: formed in M's storage when the operators are ours, which
  // frees S with them (`ops` is not used again).
  Eigen::SparseMatrix<double> system =
      owned ? TexelOperators::screenedSystem(std::move(owned), options.alpha)
            : ops.screenedSystem(options.alpha);
  solver.initAndUpdate(std::move(system), progress);
  FilterResult result;
  result.report = solver.solve(rhs, x, progress);
  boundBarelyCovered(barely, barelyX0, x);
  if (levels) {
    texture.pixels = valuesOfByteLevels(*levels);
    levels.reset();
  }
  result.image =
      filteredImage(domain.grid(), std::move(texture), std::move(decoded), options.normalMap, x);
  result.initSeconds = solver.initSeconds();
  result.updateSeconds = solver.updateSeconds();
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
  // The system matrix depends on alpha only: painting beta changes just the right-hand side.
  if (alpha == alpha_) return;
  const bool first = alpha_ == 0.0;
  alpha_ = alpha;
  // alpha M + S (+ alpha lambda C, paper §4.2); the pattern is the same for every alpha.
  if (first)
    solver_.initAndUpdate(ops.screenedSystem(alpha), progress);
  else
    solver_.update(ops.screenedSystem(alpha), progress);
}

SolveReport InteractiveFilter::step(const ProgressCallback& progress) {
  return solver_.step(rhs_, x_, progress);
}

SolveReport InteractiveFilter::solve(const ProgressCallback& progress) {
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
  return filterOnce(domain, domain.operators(), nullptr, std::move(texture), options, progress);
}

FilterResult filterTexture(const TexelDomain& domain, std::unique_ptr<TexelOperators> operators,
                           Image texture, const FilterOptions& options,
                           const ProgressCallback& progress) {
  if (!operators || operators->mass().rows() != domain.unknowns())
    throw InvalidInputError(
        "filterTexture: the operators handed over are not the domain's "
        "(TexelDomain::releaseOperators)");
  const TexelOperators& ops = *operators;
  return filterOnce(domain, ops, std::move(operators), std::move(texture), options, progress);
}

}  // namespace texgrad
