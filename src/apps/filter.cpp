// Screened Poisson filtering (paper §7.1): (alpha M + S) x* = (alpha M + S_beta) x, where S_beta
// is beta S, or sum_c beta_c S_c for a painted map. With the bilinear baseline basis the system
// also holds the soft seam energy alpha lambda E_C (paper §4.2, Fig. 5).
#include "texgrad/apps/filter.h"

#include <cmath>
#include <utility>

#include "texgrad/apps/barely_covered.h"
#include "texgrad/apps/normal_map.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/conjugate_gradient.h"

namespace texgrad {

void FilterOptions::validate() const {
  if (!(alpha > 0.0) || !std::isfinite(alpha))
    throw InvalidInputError("alpha must be a positive number, got " + std::to_string(alpha));
  if (!std::isfinite(beta)) throw InvalidInputError("beta must be a finite number");
  for (double b : betaPerCell)
    if (!std::isfinite(b)) throw InvalidInputError("the beta map holds a non-finite value");
  solver.validate();
}

InteractiveFilter::InteractiveFilter(const TexelDomain& domain, const Image& texture,
                                     const FilterOptions& options, const ProgressCallback& progress)
    : domain_(domain),
      input_(texture),
      // A colour texture is solved on input_ itself: no second whole-image copy (24 bytes per
      // active texel at spot's coverage).
      working_(options.normalMap ? decodeNormalMap(texture) : Image()),
      normalMap_(options.normalMap),
      solver_(domain.grid(), options.solver) {
  options.validate();
  x0_ = gatherTexels(domain.grid(), normalMap_ ? working_ : input_);
  x_ = x0_;
  symmetricProduct(domain.operators().mass(), x0_, massX0_);
  symmetricProduct(domain.operators().stiffness(), x0_, stiffnessX0_);
  if (!options.rawSolution) barely_ = barelyCoveredUnknowns(domain);
  applyParameters(options.alpha, options.beta, options.betaPerCell, progress);
}

void InteractiveFilter::setParameters(double alpha, double beta, std::vector<double> betaPerCell) {
  applyParameters(alpha, beta, std::move(betaPerCell), {});
}

void InteractiveFilter::applyParameters(double alpha, double beta, std::vector<double> betaPerCell,
                                        const ProgressCallback& progress) {
  if (!(alpha > 0.0) || !std::isfinite(alpha))
    throw InvalidInputError("alpha must be a positive number, got " + std::to_string(alpha));
  const TexelOperators& ops = domain_.operators();
  if (!betaPerCell.empty() && betaPerCell.size() != domain_.grid().cellCoverage.size())
    throw InvalidInputError("beta map has " + std::to_string(betaPerCell.size()) +
                            " cells, the grid has " +
                            std::to_string(domain_.grid().cellCoverage.size()));
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
  const TexelGrid& grid = domain_.grid();
  Eigen::MatrixXd bounded;
  if (!barely_.empty()) {
    bounded = x_;
    boundBarelyCovered(domain_, barely_, x0_, bounded);
  }
  const Eigen::MatrixXd& values = barely_.empty() ? x_ : bounded;
  // Only active texels inside the image change; everything else is the input bit for bit.
  Image out = input_;
  if (!normalMap_) {
    scatterTexels(grid, values, out);
    return out;
  }
  Image solved = working_;
  scatterTexels(grid, values, solved);
  renormalize(solved);
  solved = encodeNormalMap(solved, input_);
  for (int32_t t : grid.texelOfUnknown) {
    const int x = t % grid.nx, y = t / grid.nx;
    if (!grid.inImage(x, y)) continue;
    for (int c = 0; c < out.channels; ++c)
      out.at(x + grid.x0, y + grid.y0, c) = solved.at(x + grid.x0, y + grid.y0, c);
  }
  return out;
}

FilterResult filterTexture(const TexelDomain& domain, const Image& texture,
                           const FilterOptions& options, const ProgressCallback& progress) {
  InteractiveFilter filter(domain, texture, options, progress);
  FilterResult result;
  result.report = filter.solve(progress);
  result.image = filter.image();
  result.initSeconds = filter.initSeconds();
  result.updateSeconds = filter.updateSeconds();
  return result;
}

}  // namespace texgrad
