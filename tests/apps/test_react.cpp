// Gray–Scott reaction-diffusion: pure diffusion conserves mass, uniform steady states stay
// uniform, patterns are seam-continuous, and runs are reproducible from the seed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "texgrad/apps/reaction_diffusion.h"
#include "texgrad/atlas/seam_jump.h"
#include "texgrad/core/error.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

double totalMass(const TexelDomain& domain, const Eigen::VectorXd& x) {
  return Eigen::VectorXd::Ones(x.size()).dot(domain.operators().mass() * x);
}

/// A smooth non-uniform field on the unknowns (from texel coordinates; seams do not matter here).
Eigen::VectorXd wavy(const TexelGrid& grid) {
  Eigen::VectorXd x(grid.unknownCount());
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const int t = grid.texelOfUnknown[u];
    x(u) = 1.0 + 0.5 * std::sin(0.3 * (t % grid.nx)) * std::cos(0.2 * (t / grid.nx));
  }
  return x;
}

TEST(React, PureDiffusionConservesMass) {
  TexelDomain domain(procedural::cubeSphere(8), 96, 64);
  const int n = domain.unknowns();
  struct Case {
    const char* name;
    SolverSettings solver;
    double tolerance;  ///< on |1'M u1 - 1'M u0| / 1'M u0
  };
  SolverSettings direct;
  direct.kind = SolverKind::Direct;
  SolverSettings converged;  // double V-cycles run to convergence: the scheme's own property
  converged.singlePrecision = false;
  converged.cycles = 40;
  converged.tolerance = 1e-13;
  const Case cases[] = {{"direct", direct, 1e-13},
                        {"multigrid double, converged", converged, 1e-11},
                        {"multigrid default (2 float cycles)", defaultReactionSolver(), 1e-5}};
  for (const Case& c : cases) {
    ReactionDiffusionOptions options;
    options.feed = 0.0;  // F = k = 0 and v = 0 make the reaction term R vanish
    options.kill = 0.0;
    options.timeStep = 50.0;  // large steps: strong diffusion per step
    options.solver = c.solver;
    ReactionDiffusion model(domain, options);
    model.setState(wavy(domain.grid()), Eigen::VectorXd::Zero(n));
    const Eigen::VectorXd u0 = model.u();
    const double before = totalMass(domain, u0);
    model.step();
    const double after = totalMass(domain, model.u());
    std::printf("%s: 1'Mu %.15f -> %.15f (relative %.2e), max |u1 - u0| = %.3f\n", c.name, before,
                after, std::abs(after - before) / before,
                (model.u() - u0).lpNorm<Eigen::Infinity>());
    EXPECT_GT((model.u() - u0).lpNorm<Eigen::Infinity>(), 0.05) << "the step must diffuse";
    EXPECT_LE(std::abs(after - before) / before, c.tolerance) << c.name;
  }
}

TEST(React, UniformSteadyStatesStayUniform) {
  TexelDomain domain(procedural::cubeSphere(8), 96, 64);
  const int n = domain.unknowns();
  // Trivial state u = 1, v = 0 with the stripes rates, and the non-trivial homogeneous state of
  // F = 0.04, k = 0.01: (F + k) v^2 - F v + F (F + k) = 0, u = (F + k) / v.
  struct Case {
    double feed, kill, u, v;
  };
  const double f = 0.04, k = 0.01;
  const double vStar = (f + std::sqrt(f * f - 4.0 * f * (f + k) * (f + k))) / (2.0 * (f + k));
  const Case cases[] = {{0.050, 0.065, 1.0, 0.0}, {f, k, (f + k) / vStar, vStar}};
  // Double V-cycles keep the state uniform to rounding; the default float cycles to float
  // precision (their matrices are rounded to float, so S 1 = 0 only holds to ~1e-7).
  for (bool single : {false, true}) {
    const double bound = single ? 1e-5 : 1e-10;
    for (const Case& c : cases) {
      ReactionDiffusionOptions options;
      options.feed = c.feed;
      options.kill = c.kill;
      options.solver.singlePrecision = single;
      ReactionDiffusion model(domain, options);
      model.setState(Eigen::VectorXd::Constant(n, c.u), Eigen::VectorXd::Constant(n, c.v));
      model.run(200);
      const double spreadU = model.u().maxCoeff() - model.u().minCoeff();
      const double spreadV = model.v().maxCoeff() - model.v().minCoeff();
      const double driftU = (model.u().array() - c.u).abs().maxCoeff();
      const double driftV = (model.v().array() - c.v).abs().maxCoeff();
      std::printf("%s F %.3f k %.3f (u, v) = (%.4f, %.4f): spread %.1e %.1e, drift %.1e %.1e\n",
                  single ? "float " : "double", c.feed, c.kill, c.u, c.v, spreadU, spreadV, driftU,
                  driftV);
      EXPECT_LT(spreadU, bound);
      EXPECT_LT(spreadV, bound);
      EXPECT_LT(driftU, 10 * bound);
      EXPECT_LT(driftV, 10 * bound);
    }
  }
}

TEST(React, PatternIsSeamContinuous) {
  TexelDomain domain(procedural::cubeSphere(16), 144, 96);
  ReactionDiffusionOptions options;
  const GrayScottRates rates = presetRates(ReactionPreset::Dots);
  options.feed = rates.feed;
  options.kill = rates.kill;
  const ReactionResult result = reactionDiffusion(domain, options, 800);
  // Texture contrast over the active texels in the image.
  double sum = 0.0, sum2 = 0.0;
  int count = 0;
  const TexelGrid& grid = domain.grid();
  for (int32_t t : grid.texelOfUnknown) {
    const int x = t % grid.nx, y = t / grid.nx;
    if (!grid.inImage(x, y)) continue;
    const double value = result.image.at(x + grid.x0, y + grid.y0);
    sum += value;
    sum2 += value * value;
    ++count;
  }
  const double mean = sum / count;
  const double contrast = std::sqrt(std::max(0.0, sum2 / count - mean * mean));
  const SeamJump jump = measureSeamJump(domain.mesh(), domain.atlas(), result.image);
  std::printf(
      "cube sphere, 800 steps in %.1f s: texture std %.3f, seam jump RMS %.4f (max %.4f),"
      " ratio %.3f\n",
      result.seconds, contrast, jump.rms, jump.maxAbs, jump.rms / contrast);
  EXPECT_GT(contrast, 0.1) << "a pattern must have formed";
  EXPECT_LT(jump.rms, 0.1 * contrast);
}

TEST(React, SameSeedSameOutput) {
  TexelDomain domain(procedural::cubeSphere(8), 96, 64);
  ReactionDiffusionOptions options;
  const ReactionResult a = reactionDiffusion(domain, options, 100);
  const ReactionResult b = reactionDiffusion(domain, options, 100);
  EXPECT_EQ(a.u, b.u);
  EXPECT_EQ(a.v, b.v);
  EXPECT_EQ(a.image.pixels, b.image.pixels);
  options.seed = 7;
  const ReactionResult c = reactionDiffusion(domain, options, 100);
  EXPECT_GT((c.v - a.v).lpNorm<Eigen::Infinity>(), 1e-3) << "another seed moves the spots";
}

TEST(React, HandingTheOperatorsOverGivesTheSameResult) {
  // The one-shot path keeps only M once both systems are formed; states and image must not move.
  TexelDomain shared(procedural::cubeSphere(8), 96, 64);
  TexelDomain handed(procedural::cubeSphere(8), 96, 64);
  ReactionDiffusionOptions options;
  options.timeStep = 5.0;  // a pattern forms within the steps, so any change to M or A shows
  const ReactionResult a = reactionDiffusion(shared, options, 60);
  const ReactionResult b = reactionDiffusion(handed, handed.releaseOperators(), options, 60);
  EXPECT_GT(a.v.maxCoeff(), 0.05) << "the spots must still be there";
  EXPECT_EQ(a.u, b.u);
  EXPECT_EQ(a.v, b.v);
  EXPECT_EQ(a.image.pixels, b.image.pixels);
  EXPECT_FALSE(handed.hasOperators());

  TexelDomain other(procedural::cubeSphere(8), 96, 64);
  ReactionDiffusion model(other, other.releaseOperators(), options);
  EXPECT_THROW(model.reseed(2), InvalidInputError) << "seeding needs the operators";
  EXPECT_THROW(ReactionDiffusion bad(shared, nullptr, options), InvalidInputError);
}

TEST(React, PresetsAndOptions) {
  EXPECT_EQ(parseReactionPreset("stripes"), ReactionPreset::Stripes);
  EXPECT_EQ(parseReactionPreset("dots"), ReactionPreset::Dots);
  EXPECT_THROW(parseReactionPreset("zebra"), InvalidInputError);
  ReactionDiffusionOptions options;
  options.timeStep = 0.0;
  EXPECT_THROW(options.validate(), InvalidInputError);
}

}  // namespace
}  // namespace texgrad
