// Screened-Poisson filtering: identity at beta = 1, multigrid matches direct, metric awareness,
// smoothing lowers seam jump and energy (procedural and every shared mesh, with a table), beta
// maps, normal maps stay unit length (every glTF model with one).
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app_fixtures.h"
#include "shared_meshes.h"
#include "test_paths.h"
#include "texgrad/apps/barely_covered.h"
#include "texgrad/apps/filter.h"
#include "texgrad/apps/normal_map.h"
#include "texgrad/apps/seams.h"
#include "texgrad/atlas/seam_jump.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/image_levels.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/procedural.h"
#include "texgrad/solver/grid_hierarchy.h"

namespace texgrad {
namespace {

FilterOptions withSolver(SolverKind kind, double beta) {
  FilterOptions o;
  o.beta = beta;
  o.solver.kind = kind;
  return o;
}

/// Largest seam jump of the seam-continuous function allowed (texture units: rounding only).
constexpr double kContinuityTolerance = 1e-6;
/// How far from beta the bilinear seam jump's scale may be (measured 1.98-2.10 at beta 2).
constexpr double kBetaScaleTolerance = 0.15;
/// The bilinear seam jump after beta = 0 is at most this fraction of the input's (measured 0-0.68).
constexpr double kSmoothedJumpRatio = 0.7;
/// RMS bilinear seam jump in 8-bit steps that `seams` brings sharpened textures under (measured
/// at most 1.02 on the shared meshes at 1024^2, whether run before or after filtering).
constexpr double kSeamsResidualSteps = 1.1;

/// Largest |f(p) - f(q)| over `samples` random seam-equivalent pairs p ~ q, where f is the function
/// sum_t x_t phi_t the texture's texel values define in the seam-continuous basis (every channel).
double finiteElementSeamJump(const TexelDomain& domain, const Image& image, int samples) {
  const fem::TexelBasis& basis = domain.operators().basis();
  const Eigen::MatrixXd x = gatherTexels(domain.grid(), image);
  std::mt19937_64 rng(11);
  double worst = 0.0;
  for (int k = 0; k < samples; ++k) {
    const auto [p, q] = basis.randomSeamPair(rng);
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      const Eigen::VectorXd column = x.col(c);
      worst = std::max(worst, std::abs(basis.evaluate(p, column) - basis.evaluate(q, column)));
    }
  }
  return worst;
}

TEST(Filter, BetaOneReturnsTheInput) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image input = test::randomTexture(128, 128, 3, 1);
  for (SolverKind kind : {SolverKind::Direct, SolverKind::Multigrid}) {
    const FilterResult r = filterTexture(domain, input, withSolver(kind, 1.0));
    EXPECT_LE(test::activeRms(domain, r.image, input), 1e-5 * test::activeRms(domain, input))
        << toString(kind);
  }
}

TEST(Filter, SmoothingLowersSeamJumpAndEnergySharpeningRaisesEnergy) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image input = test::randomTexture(128, 128, 1, 2);
  const Image smooth = filterTexture(domain, input, withSolver(SolverKind::Direct, 0.0)).image;
  const Image sharp = filterTexture(domain, input, withSolver(SolverKind::Direct, 3.0)).image;
  const double e0 = test::dirichletEnergy(domain, input);
  EXPECT_LT(test::dirichletEnergy(domain, smooth), 0.5 * e0);
  EXPECT_GT(test::dirichletEnergy(domain, sharp), 1.5 * e0);
  const SeamJump before = measureSeamJump(domain.mesh(), domain.atlas(), input);
  const SeamJump after = measureSeamJump(domain.mesh(), domain.atlas(), smooth);
  EXPECT_LT(after.rms, 0.5 * before.rms);
}

/// The statement of `filter --help` on a procedural atlas (fast; the shared meshes below): the
/// result's function in the seam-continuous basis is continuous across seams, and the bilinear
/// seam jump a renderer sees is scaled by about beta (texel-scale detail, like all fine detail).
TEST(Filter, SharpenedFunctionIsContinuousAndBilinearSeamJumpScalesWithBeta) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image input = test::randomTexture(128, 128, 3, 2);
  const Image sharp = filterTexture(domain, input, withSolver(SolverKind::Direct, 2.0)).image;
  const Image smooth = filterTexture(domain, input, withSolver(SolverKind::Direct, 0.0)).image;
  EXPECT_LE(finiteElementSeamJump(domain, sharp, 500), kContinuityTolerance);
  const auto jump = [&](const Image& image) {
    return measureSeamJump(domain.mesh(), domain.atlas(), image).rms;
  };
  EXPECT_NEAR(jump(sharp) / jump(input), 2.0, kBetaScaleTolerance);
  EXPECT_LE(jump(smooth), kSmoothedJumpRatio * jump(input));
}

TEST(Filter, SoftSeamBaselineNeedsLambdaWhereTheContinuousBasisDoesNot) {
  // Paper §4.2 / Fig. 5: plain bilinear texels leave charts uncoupled (lambda = 0); the soft seam
  // energy alpha lambda E_C pulls the sides together as lambda grows.
  const Image input = test::randomTexture(128, 128, 1, 3);
  const auto smoothedJump = [&](fem::BasisKind basis, double lambda) {
    OperatorOptions ops;
    ops.basis = basis;
    ops.seamContinuityWeight = lambda;
    const TexelDomain domain(procedural::cubeSphere(8), 128, 128, ops);
    const Image smooth = filterTexture(domain, input, withSolver(SolverKind::Direct, 0.0)).image;
    return measureSeamJump(domain.mesh(), domain.atlas(), smooth).rms;
  };
  const double continuous = smoothedJump(fem::BasisKind::SeamContinuous, 0.0);
  const double uncoupled = smoothedJump(fem::BasisKind::Bilinear, 0.0);
  const double soft = smoothedJump(fem::BasisKind::Bilinear, 1e-2);
  const double stiff = smoothedJump(fem::BasisKind::Bilinear, 1e2);
  std::cout << "[ filter ] seam jump after smoothing: continuous basis " << continuous
            << ", bilinear lambda 0: " << uncoupled << ", 1e-2: " << soft << ", 1e2: " << stiff
            << "\n";
  EXPECT_LT(continuous, 0.5 * uncoupled);
  EXPECT_LT(soft, uncoupled);
  EXPECT_LT(stiff, soft);
}

TEST(Filter, SmoothingIsIsotropicOnTheSurfaceForAnisotropicUvs) {
  // The unit square with UVs squeezed 4x in v: an impulse must blur into a circle on the surface
  // (an ellipse in UV), so surface second moments agree in x and y.
  const int w = 256, h = 256;
  const TexelDomain domain(procedural::square(1.0, 0.25, 0.0, 0.3), w, h);
  Image impulse(w, h, 1);
  const int ci = w / 2, cj = static_cast<int>(0.425 * h);
  impulse.at(ci, cj) = 1.0f;
  FilterOptions o = withSolver(SolverKind::Direct, 0.0);
  o.alpha = 100.0;
  const Image blob = filterTexture(domain, impulse, o).image;
  double sum = 0, mx = 0, my = 0, sxx = 0, syy = 0;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double value = blob.at(i, j);
      const double x = (i + 0.5) / w, y = ((j + 0.5) / h - 0.3) / 0.25;
      sum += value;
      mx += value * x;
      my += value * y;
      sxx += value * x * x;
      syy += value * y * y;
    }
  mx /= sum;
  my /= sum;
  const double varX = sxx / sum - mx * mx, varY = syy / sum - my * my;
  EXPECT_NEAR(varX / varY, 1.0, 0.05) << "var x " << varX << " var y " << varY;
}

TEST(Filter, ConstantBetaMapMatchesGlobalBetaAndHalfMapsActLocally) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image input = test::randomTexture(128, 128, 1, 3);
  FilterOptions global = withSolver(SolverKind::Direct, 0.3);
  FilterOptions mapped = global;
  mapped.betaPerCell.assign(domain.grid().cellCoverage.size(), 0.3);
  const Image a = filterTexture(domain, input, global).image;
  const Image b = filterTexture(domain, input, mapped).image;
  EXPECT_LE(test::activeRms(domain, a, b), 1e-12);

  // Left half smooths (beta 0), right half sharpens (beta 3): energy per half moves accordingly.
  Image map(128, 128, 1);
  for (int j = 0; j < 128; ++j)
    for (int i = 64; i < 128; ++i) map.at(i, j) = 1.0f;
  FilterOptions half = withSolver(SolverKind::Direct, 1.0);
  half.betaPerCell = cellValuesFromMap(domain.grid(), map, 0.0, 3.0);
  const Image out = filterTexture(domain, input, half).image;
  double changeLeft = 0, changeRight = 0, varLeftIn = 0, varLeftOut = 0, varRightIn = 0,
         varRightOut = 0;
  const TexelGrid& g = domain.grid();
  for (int32_t t : g.texelOfUnknown) {
    if (g.texelClass[t] != TexelClass::Interior) continue;
    const int i = t % g.nx + g.x0, j = t / g.nx + g.y0;
    const double in = input.at(i, j) - 0.5, o2 = out.at(i, j) - 0.5;
    if (i < 60) {
      varLeftIn += in * in;
      varLeftOut += o2 * o2;
      changeLeft += std::abs(in - o2);
    } else if (i >= 68) {
      varRightIn += in * in;
      varRightOut += o2 * o2;
      changeRight += std::abs(in - o2);
    }
  }
  EXPECT_LT(varLeftOut, 0.5 * varLeftIn);    // smoothed: contrast falls
  EXPECT_GT(varRightOut, 1.2 * varRightIn);  // sharpened: contrast grows
  EXPECT_GT(changeLeft, 0.0);
  EXPECT_GT(changeRight, 0.0);
}

TEST(Filter, ReportsSetupAndSolveStagesAndSolvesAgainAfterACancel) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image texture = test::randomTexture(128, 128, 3, 11);
  FilterOptions options = withSolver(SolverKind::MultigridCg, 0.2);
  options.solver.tolerance = 1e-8;  // enough iterations to cancel in the middle
  std::vector<std::string> stages;
  int lastStep = -1;
  const auto record = [&](const Progress& p) {
    if (stages.empty() || stages.back() != p.stage) stages.emplace_back(p.stage);
    lastStep = p.step;
    return true;
  };
  const FilterResult reference = filterTexture(domain, texture, options, record);
  EXPECT_EQ(stages, (std::vector<std::string>{"solver setup", "solve"}));
  EXPECT_EQ(lastStep, reference.report.iterations);
  ASSERT_GT(reference.report.iterations, 3);

  InteractiveFilter filter(domain, texture, options);
  int cancelledAt = -1;
  EXPECT_THROW(filter.solve([&](const Progress& p) {
    cancelledAt = p.step;
    return p.step < 3;
  }),
               Cancelled);
  EXPECT_EQ(cancelledAt, 3) << "polled before every iteration";
  filter.solve();
  // CG restarted from the third iterate reaches the same tolerance: equal to far below 8 bits.
  EXPECT_LT(test::activeRms(domain, filter.image(), reference.image), 1e-6);
}

/// Number of stored values (texel and channel) in which two images of one size differ.
int64_t differingValues(const Image& a, const Image& b) {
  if (a.pixels.size() != b.pixels.size()) return static_cast<int64_t>(a.pixels.size());
  int64_t count = 0;
  for (size_t k = 0; k < a.pixels.size(); ++k) count += a.pixels[k] != b.pixels[k] ? 1 : 0;
  return count;
}

TEST(Filter, OneShotRunsGiveTheInteractiveFiltersImageBitForBit) {
  // The jittered cube has barely covered texels, so the bound (which reads M's neighbours) is
  // exercised; filterTexture forms its right-hand side without InteractiveFilter's stored
  // products, and the consuming overload frees M and S before the solver's set-up (without a
  // beta map it forms the right-hand side and the bound column by column as A is formed, also
  // from operators whose assembly was deferred to then).
  constexpr int kSize = procedural::kAlignedCubeResolution;
  constexpr double kJitter = 0.01;
  const TexturedMesh mesh = procedural::alignedCube(4, kJitter);
  const TexelDomain shared(mesh, kSize, kSize);
  ASSERT_FALSE(barelyCoveredUnknowns(shared).empty());
  const Image texture = test::randomTexture(kSize, kSize, 3, 5);
  // A fixed number of V-cycles: each channel's iterates are the same bits whether the channels
  // are solved together (InteractiveFilter) or in turn (the one-shot filter); CG's stopping
  // iteration may differ per channel (ChannelByChannelSolveMeetsTheTolerance... covers it).
  FilterOptions uniform = withSolver(SolverKind::Multigrid, 0.3);
  FilterOptions mapped = uniform;
  mapped.betaPerCell.assign(shared.grid().cellCoverage.size(), 0.0);
  for (size_t c = 0; c < mapped.betaPerCell.size(); c += 2) mapped.betaPerCell[c] = 2.0;
  FilterOptions normals = uniform;
  normals.normalMap = true;
  FilterOptions smoothing = uniform;  // beta 0: the one-shot filter forms no S x0
  smoothing.beta = 0.0;
  // An 8-bit texture (as read from a file) is held as its levels through the one-shot solve.
  const Image levels = [&] {
    const auto dir = test::tempDir("filter_levels");
    Image eightBit = texture;
    eightBit.format = PixelFormat::UInt8;
    writeImage(dir / "texture.png", eightBit);
    Image read = readImage(dir / "texture.png");
    std::filesystem::remove_all(dir);
    return read;
  }();
  ASSERT_TRUE(exactByteLevels(levels).has_value());
  for (const auto& [options, input] :
       {std::pair{uniform, texture}, std::pair{mapped, texture}, std::pair{normals, texture},
        std::pair{uniform, levels}, std::pair{smoothing, levels}, std::pair{normals, levels}}) {
    InteractiveFilter interactive(shared, input, options);
    interactive.solve();
    const Image expected = interactive.image();
    const std::string what = "beta " + std::to_string(options.beta) + ", beta map " +
                             std::to_string(!options.betaPerCell.empty()) + ", normal map " +
                             std::to_string(options.normalMap) + ", 8-bit " +
                             std::to_string(input.format == PixelFormat::UInt8);
    EXPECT_EQ(differingValues(filterTexture(shared, input, options).image, expected), 0) << what;
    TexelDomain consumed(mesh, kSize, kSize);
    const FilterResult result =
        filterTexture(consumed, consumed.releaseOperators(), input, options);
    EXPECT_EQ(differingValues(result.image, expected), 0) << what;
    EXPECT_FALSE(consumed.hasOperators());
    EXPECT_FALSE(consumed.hasImageMaps()) << what;
    EXPECT_EQ(consumed.grid().texelOfUnknown, shared.grid().texelOfUnknown) << "it stays";
    if (options.betaPerCell.empty()) {  // as texgrad filter builds them without a beta map
      OperatorOptions deferral = OperatorOptions::assembledOnce();
      deferral.deferAssembly = true;
      TexelDomain deferred(mesh, kSize, kSize, deferral);
      EXPECT_TRUE(deferred.operators().assemblyDeferred());
      const FilterResult d = filterTexture(deferred, deferred.releaseOperators(), input, options);
      EXPECT_EQ(differingValues(d.image, expected), 0) << what << ", assembly deferred";
      EXPECT_FALSE(deferred.hasImageMaps()) << what;
    }
    if (std::optional<std::vector<uint8_t>> held = exactByteLevels(input)) {
      TexelDomain byLevels(mesh, kSize, kSize);
      Image withoutPixels = input;
      withoutPixels.pixels = std::vector<float>();
      const FilterResult r = filterTexture(byLevels, byLevels.releaseOperators(),
                                           std::move(withoutPixels), std::move(*held), options);
      EXPECT_EQ(differingValues(r.image, expected), 0) << what << ", handed over as levels";
    }
  }
}

TEST(Filter, LevelsHandedOverMustBeThoseOfAn8BitTexture) {
  Image texture(96, 64, 3, PixelFormat::UInt8);
  const auto refused = [&](const Image& image, size_t values) {
    TexelDomain domain(procedural::cube(3), 96, 64);
    try {
      filterTexture(domain, domain.releaseOperators(), image, std::vector<uint8_t>(values),
                    withSolver(SolverKind::Direct, 0.0));
    } catch (const InvalidInputError& e) {
      return std::string(e.what()).find("levels handed over") != std::string::npos;
    }
    return false;
  };
  EXPECT_TRUE(refused(texture, texture.pixels.size() - 1));
  texture.format = PixelFormat::Float;
  EXPECT_TRUE(refused(texture, texture.pixels.size()));
}

/// How much larger the channel-by-channel solve's error to the direct solution may be than the
/// all-channel solve's (both stop at a relative residual of 1e-4; measured equal to 5 digits).
constexpr double kNoWorse = 1.05;
/// Slack on the solver's relative residual for the solution's rounding to the float image.
constexpr double kFloatImageSlack = 1e-6;

TEST(Filter, ChannelByChannelSolveMeetsTheToleranceInEachChannelAndMatchesTheAllChannelSolve) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const TexelOperators& ops = domain.operators();
  const Image texture = test::randomTexture(128, 128, 3, 17);
  FilterOptions options = withSolver(SolverKind::MultigridCg, 0.3);
  options.rawSolution = true;  // x itself, not bounded
  const FilterResult oneShot = filterTexture(domain, texture, options);
  const Eigen::MatrixXd x = gatherTexels(domain.grid(), oneShot.image);
  // The same system, solved for all channels at once and directly.
  const Eigen::MatrixXd x0 = gatherTexels(domain.grid(), texture);
  const Eigen::MatrixXd b =
      options.alpha * (ops.mass() * x0) + options.beta * (ops.stiffness() * x0);
  const Eigen::SparseMatrix<double> a = ops.screenedSystem(options.alpha);
  SystemSolver all(domain.grid(), options.solver);
  all.initAndUpdate(a);
  Eigen::MatrixXd xAll = x0;
  ASSERT_TRUE(all.solve(b, xAll).converged);
  SystemSolver direct(domain.grid(), withSolver(SolverKind::Direct, 0.3).solver);
  direct.initAndUpdate(a);
  Eigen::MatrixXd xDirect;
  direct.solve(b, xDirect);

  const double tolerance = options.solver.tolerance;
  ASSERT_EQ(oneShot.report.residuals.size(), oneShot.report.rmsChange.size() + 1);
  EXPECT_TRUE(oneShot.report.converged);
  EXPECT_LE(oneShot.report.residuals.back(), tolerance) << "the worst channel's residual";
  for (Eigen::Index c = 0; c < x.cols(); ++c) {
    const double residual = (b.col(c) - a * x.col(c)).norm() / b.col(c).norm();
    EXPECT_LE(residual, tolerance + kFloatImageSlack) << "channel " << c;
  }
  // Each channel converged on its own is as close to the exact solution as all channels
  // converged together (measured: max 0.0178 of an 8-bit step both, 7.6e-6 steps apart).
  const auto rms = [](const Eigen::MatrixXd& e) {
    return std::sqrt(e.squaredNorm() / static_cast<double>(e.size()));
  };
  EXPECT_LE(rms(x - xDirect), kNoWorse * rms(xAll - xDirect));
  EXPECT_LE((x - xDirect).cwiseAbs().maxCoeff(), kNoWorse * (xAll - xDirect).cwiseAbs().maxCoeff());
}

TEST(Filter, OneSolveStageAcrossTheChannelsAndACancelInTheSecondChannel) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image texture = test::randomTexture(128, 128, 3, 19);
  const FilterOptions options = withSolver(SolverKind::MultigridCg, 0.2);
  std::vector<Progress> solve;
  const FilterResult result = filterTexture(domain, texture, options, [&](const Progress& p) {
    if (p.stage == "solve") solve.push_back(p);
    return true;
  });
  ASSERT_FALSE(solve.empty());
  for (size_t k = 1; k < solve.size(); ++k) {
    EXPECT_GE(solve[k].fraction, solve[k - 1].fraction) << "report " << k;
    EXPECT_GE(solve[k].step, solve[k - 1].step) << "report " << k;
  }
  for (const Progress& p : solve) EXPECT_EQ(p.steps, 3 * options.solver.maxIterations);
  EXPECT_EQ(solve.back().fraction, 1.0);
  EXPECT_EQ(solve.back().step, result.report.iterations);
  // Past half the stage the second channel is solving: a cancel there still stops the filter.
  bool cancelled = false;
  EXPECT_THROW(filterTexture(domain, texture, options,
                             [&](const Progress& p) {
                               cancelled = p.stage == "solve" && p.fraction > 0.5;
                               return !cancelled;
                             }),
               Cancelled);
  EXPECT_TRUE(cancelled);
}

TEST(Filter, OperatorsHandedOverOnceAndOnlyTheDomainsAreAccepted) {
  TexelDomain domain(procedural::cube(3), 96, 64);
  TexelDomain other(procedural::cylinder(), 96, 64);
  const Image input = test::randomTexture(96, 64, 3, 4);
  ASSERT_NE(other.unknowns(), domain.unknowns());
  const FilterOptions options = withSolver(SolverKind::Direct, 0.0);
  const auto refused = [&](std::unique_ptr<TexelOperators> operators, TexelDomain& to) {
    try {
      filterTexture(to, std::move(operators), input, options);
    } catch (const InvalidInputError& e) {
      return std::string(e.what()).find("not the domain's") != std::string::npos;
    }
    return false;
  };
  EXPECT_TRUE(refused(nullptr, domain));
  EXPECT_THROW(domain.releaseImageMaps(), InvalidInputError);  // the operators still hold them
  EXPECT_TRUE(domain.hasImageMaps());
  std::unique_ptr<TexelOperators> operators = domain.releaseOperators();
  ASSERT_NE(operators, nullptr);
  EXPECT_FALSE(domain.hasOperators());
  EXPECT_THROW(static_cast<void>(domain.operators()), InvalidInputError);
  EXPECT_THROW(static_cast<void>(domain.releaseOperators()), InvalidInputError);
  EXPECT_TRUE(refused(std::move(operators), other));
}

TEST(Filter, DomainGridHasNoCellChartsAndMapsKeptForTheHierarchySuffice) {
  // The consuming filter builds its solver's hierarchy after freeing all maps but the class,
  // the charts and the numbering.
  TexelDomain domain(procedural::cube(3), 96, 64);
  const TexelGrid full = domain.grid();
  // The domain's grid is the atlas's, but for the cells' charts, freed at once.
  const TexelGrid built = buildTexelGrid(domain.mesh(), domain.atlas(), 96, 64);
  EXPECT_TRUE(full.cellChart.empty());
  EXPECT_FALSE(built.cellChart.empty());
  EXPECT_EQ(full.cellCoverage, built.cellCoverage);
  EXPECT_EQ(full.chartOfUnknown, built.chartOfUnknown);
  EXPECT_EQ(full.unknownOfTexel, built.unknownOfTexel);
  domain.releaseOperators();
  domain.releaseImageMaps(TexelDomain::KeptMaps::ClassAndChart);
  const TexelGrid& kept = domain.grid();
  EXPECT_TRUE(domain.hasImageMaps());
  EXPECT_EQ(kept.texelClass, full.texelClass);
  EXPECT_EQ(kept.chartOfUnknown, full.chartOfUnknown);
  EXPECT_EQ(kept.unknownOfTexel, full.unknownOfTexel) << "chartOfTexel reads it";
  EXPECT_EQ(kept.texelOfUnknown, full.texelOfUnknown);
  EXPECT_TRUE(kept.cellCoverage.empty());
  EXPECT_TRUE(kept.cellChart.empty());
  const GridHierarchy expected = GridHierarchy::build(full, 8, 16);
  const GridHierarchy fromKept = GridHierarchy::build(kept, 8, 16);
  ASSERT_EQ(fromKept.levelCount(), expected.levelCount());
  for (int l = 0; l < fromKept.levelCount(); ++l) {
    EXPECT_EQ(fromKept.level(l).slotOfUnknown, expected.level(l).slotOfUnknown) << "level " << l;
    EXPECT_EQ(fromKept.level(l).footprintInterior, expected.level(l).footprintInterior) << l;
  }
  domain.releaseImageMaps();
  EXPECT_FALSE(domain.hasImageMaps());
  EXPECT_TRUE(domain.grid().chartOfUnknown.empty());
  EXPECT_TRUE(domain.grid().unknownOfTexel.empty());
  EXPECT_EQ(domain.grid().texelOfUnknown, full.texelOfUnknown);
}

TEST(Filter, InactiveTexelsAreUntouched) {
  const TexelDomain domain(procedural::cube(3), 96, 64);
  const Image input = test::randomTexture(96, 64, 3, 4);
  const Image out = filterTexture(domain, input, withSolver(SolverKind::Multigrid, 0.0)).image;
  const TexelGrid& g = domain.grid();
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 96; ++i) {
      const int x = i - g.x0, y = j - g.y0;
      const bool active = x >= 0 && y >= 0 && x < g.nx && y < g.ny &&
                          g.texelClass[g.texelIndex(x, y)] != TexelClass::Inactive;
      if (active) continue;
      for (int c = 0; c < 3; ++c) ASSERT_EQ(out.at(i, j, c), input.at(i, j, c));
    }
}

/// A glTF model of ../shared/data with a tangent-space normal map.
struct NormalMapped {
  std::string name, gltf, normals;  ///< model name; paths relative to sharedData()
};

class SharedNormalMapsSlow : public ::testing::TestWithParam<NormalMapped> {};

TEST_P(SharedNormalMapsSlow, SmoothedNormalsStayUnitLength) {
  const NormalMapped& m = GetParam();
  const TexturedMesh mesh = readMesh(test::sharedData() / m.gltf);
  // Every k-th texel of the map, at most 512 across: keeps the test quick.
  const Image full = readImage(test::sharedData() / m.normals);
  const int k = std::max(1, full.width / 512);
  Image normals(full.width / k, full.height / k, full.channels, full.format);
  for (int j = 0; j < normals.height; ++j)
    for (int i = 0; i < normals.width; ++i)
      for (int c = 0; c < full.channels; ++c) normals.at(i, j, c) = full.at(k * i, k * j, c);
  const TexelDomain domain(mesh, normals.width, normals.height);
  FilterOptions o = withSolver(SolverKind::Multigrid, 0.0);
  o.normalMap = true;
  const Image out = filterTexture(domain, normals, o).image;
  const Image decoded = decodeNormalMap(out);
  const TexelGrid& g = domain.grid();
  double worst = 0.0;
  for (int32_t t : g.texelOfUnknown) {
    const int x = t % g.nx, y = t / g.nx;
    if (!g.inImage(x, y)) continue;
    Eigen::Vector3d n;
    for (int c = 0; c < 3; ++c) n[c] = decoded.at(x + g.x0, y + g.y0, c);
    worst = std::max(worst, std::abs(n.norm() - 1.0));
  }
  std::cout << "[ normals ] " << m.name << " worst | |n| - 1 | = " << worst << "\n";
  // 8-bit quantisation of a unit vector moves its length by at most ~sqrt(3)/255.
  EXPECT_LE(worst, 1e-3 + std::sqrt(3.0) / 255.0);
}

INSTANTIATE_TEST_SUITE_P(
    GltfModels, SharedNormalMapsSlow,
    ::testing::Values(
        NormalMapped{"Avocado", "Avocado/glTF/Avocado.gltf", "Avocado/glTF/Avocado_normal.png"},
        NormalMapped{"BoomBox", "BoomBox/glTF/BoomBox.gltf", "BoomBox/glTF/BoomBox_normal.png"},
        NormalMapped{"Lantern", "Lantern/glTF/Lantern.gltf", "Lantern/glTF/Lantern_normal.png"},
        NormalMapped{"WaterBottle", "WaterBottle/glTF/WaterBottle.gltf",
                     "WaterBottle/glTF/WaterBottle_normal.png"}),
    [](const ::testing::TestParamInfo<NormalMapped>& p) { return p.param.name; });

/// Smoothing and sharpening each shared mesh's own texture (at most 512 across).
class SharedFilterJumpSlow : public ::testing::TestWithParam<test::SharedMesh> {};

TEST_P(SharedFilterJumpSlow, SmoothingLowersSeamJumpAndEnergy) {
  const test::SharedMesh& s = GetParam();
  const Image texture = test::textureAtMost(readImage(test::sharedData() / s.texture), 512);
  const TexelDomain domain(readMesh(test::sharedData() / s.obj), texture.width, texture.height);
  const Image smooth = filterTexture(domain, texture, withSolver(SolverKind::Multigrid, 0.0)).image;
  const Image sharp = filterTexture(domain, texture, withSolver(SolverKind::Multigrid, 3.0)).image;
  const auto jump = [&](const Image& image) {
    return measureSeamJump(domain.mesh(), domain.atlas(), image).rms;
  };
  const double e0 = test::dirichletEnergy(domain, texture);
  const double e1 = test::dirichletEnergy(domain, smooth),
               e3 = test::dirichletEnergy(domain, sharp);
  std::cout << "[ filter ] " << s.name << " " << texture.width << "x" << texture.height
            << " seam jump " << jump(texture) << " -> beta 0: " << jump(smooth)
            << ", beta 3: " << jump(sharp) << "; energy " << e0 << " -> " << e1 << ", " << e3
            << "\n";
  EXPECT_LT(e1, e0);
  EXPECT_GT(e3, e0);
  if (domain.atlas().seams.empty()) {  // Suzanne: no seam to measure
    EXPECT_EQ(jump(smooth), 0.0);
    return;
  }
  EXPECT_LT(jump(smooth), jump(texture));
}

INSTANTIATE_TEST_SUITE_P(AllMeshes, SharedFilterJumpSlow, ::testing::ValuesIn(test::sharedMeshes()),
                         test::sharedMeshName);

/// What `texgrad filter --help` says about seams, measured on every shared mesh's texture (at
/// most 1024 across, default filter settings): the filtered function is continuous across seams,
/// while the bilinear lookups a renderer makes on the two sides of a seam differ by the RMS jump
/// of measureSeamJump, which smoothing lowers, sharpening raises, and `seams` removes.
class SharedFilterSeamContinuitySlow : public ::testing::TestWithParam<test::SharedMesh> {};

TEST_P(SharedFilterSeamContinuitySlow, FunctionIsContinuousAndBilinearJumpIsAsDocumented) {
  const test::SharedMesh& s = GetParam();
  const Image texture = test::textureAtMost(readImage(test::sharedData() / s.texture), 1024);
  const TexelDomain domain(readMesh(test::sharedData() / s.obj), texture.width, texture.height);
  FilterOptions smoothing, sharpening;
  smoothing.beta = 0.0;
  sharpening.beta = 2.0;
  if (domain.atlas().seams.empty()) {  // Suzanne has no seam: nothing may jump
    const Image sharp = filterTexture(domain, texture, sharpening).image;
    EXPECT_EQ(measureSeamJump(domain.mesh(), domain.atlas(), sharp).rms, 0.0);
    return;
  }
  const Image smooth = filterTexture(domain, texture, smoothing).image;
  const Image sharp = filterTexture(domain, texture, sharpening).image;
  const Image seamless = smoothSeams(domain, texture).image;
  const auto jump = [&](const Image& image) {
    return 255.0 * measureSeamJump(domain.mesh(), domain.atlas(), image).rms;
  };
  const double input = jump(texture), beta0 = jump(smooth), beta2 = jump(sharp);
  const double beta2Seams = jump(smoothSeams(domain, sharp).image);
  const double seamsBeta2 = jump(filterTexture(domain, seamless, sharpening).image);
  const double fe2 = 255.0 * finiteElementSeamJump(domain, sharp, 2000);
  std::printf(
      "[ seam continuity ] %-12s %4dx%-4d RMS bilinear jump (8-bit): input %.2f, beta 0 "
      "%.2f, beta 2 %.2f (x%.2f), seams(input) %.2f, seams(beta 2) %.2f, beta 2 of "
      "seams(input) %.2f; max FE jump at beta 2 %.1e\n",
      s.name.c_str(), texture.width, texture.height, input, beta0, beta2, beta2 / input,
      jump(seamless), beta2Seams, seamsBeta2, fe2);
  EXPECT_LE(fe2 / 255.0, kContinuityTolerance);
  EXPECT_NEAR(beta2 / input, 2.0, kBetaScaleTolerance);
  EXPECT_LE(beta0, kSmoothedJumpRatio * input);
  EXPECT_LE(beta2Seams, kSeamsResidualSteps);
  EXPECT_LE(seamsBeta2, kSeamsResidualSteps);
}

INSTANTIATE_TEST_SUITE_P(AllMeshes, SharedFilterSeamContinuitySlow,
                         ::testing::ValuesIn(test::sharedMeshes()), test::sharedMeshName);

/// Multigrid (default settings) against the direct solution on every shared mesh at 1024².
class SharedFilterSlow : public ::testing::TestWithParam<test::SharedMesh> {};

TEST_P(SharedFilterSlow, MultigridWithinATenthOfAnEightBitStepOfDirect) {
  const test::SharedMesh& s = GetParam();
  const TexelDomain domain(readMesh(test::sharedData() / s.obj), 1024, 1024);
  const Image texture = test::randomTexture(1024, 1024, 3, 5);
  FilterOptions o;
  o.beta = 0.0;
  const Image mg = filterTexture(domain, texture, o).image;
  o.solver.kind = SolverKind::Direct;
  const Image direct = filterTexture(domain, texture, o).image;
  const double rms = test::activeRms(domain, mg, direct);
  std::cout << "[ filter ] " << s.name << " multigrid vs direct RMS " << rms * 255.0
            << " 8-bit steps\n";
  EXPECT_LE(rms, 0.1 / 255.0);
}

INSTANTIATE_TEST_SUITE_P(AllMeshes, SharedFilterSlow, ::testing::ValuesIn(test::sharedMeshes()),
                         test::sharedMeshName);

}  // namespace
}  // namespace texgrad
