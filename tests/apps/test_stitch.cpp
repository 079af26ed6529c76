// Stitching: removes jumps between sources (multiview_bob with ground truth), keeps locked texels
// exactly, and leaves a single-source texture unchanged.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>

#include "app_fixtures.h"
#include "shared_meshes.h"
#include "texgrad/apps/gain_compensation.h"
#include "texgrad/apps/stitch.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

TEST(Stitch, SingleSourceTextureIsReproduced) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image texture = test::randomTexture(128, 128, 3, 21);
  Image segments(128, 128, 3);
  std::fill(segments.pixels.begin(), segments.pixels.end(), 1.0f);
  StitchOptions o;
  o.solver.kind = SolverKind::Direct;
  const StitchResult r = stitchComposite(domain, texture, segments, o);
  EXPECT_EQ(r.sources, 1);
  EXPECT_LE(test::activeRms(domain, r.image, texture), 1e-6);
}

TEST(Stitch, RemovesAnOffsetBetweenTwoSources) {
  // Left half of the image from source 1, right half from source 2 = source 1 + 0.3.
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image base = test::randomTexture(128, 128, 1, 22, 0.2f, 0.4f);
  Image composite = base, segments(128, 128, 1);
  for (int j = 0; j < 128; ++j)
    for (int i = 0; i < 128; ++i) {
      const bool right = i >= 64;
      segments.at(i, j) = right ? 1.0f : 0.5f;
      if (right) composite.at(i, j) += 0.3f;
    }
  StitchOptions o;
  o.solver.kind = SolverKind::Direct;
  o.alpha = 1e-2;  // weak screening: the offset spreads over the whole (connected) sphere
  o.compensateGains = false;  // the paper's stitch: an additive offset, no gain model
  const StitchResult r = stitchComposite(domain, composite, segments, o);
  EXPECT_EQ(r.sources, 2);
  // The result equals base + constant up to small error: its difference to base is flat.
  const Eigen::MatrixXd diff =
      gatherTexels(domain.grid(), r.image) - gatherTexels(domain.grid(), base);
  const double mean = diff.mean();
  const double spread = std::sqrt((diff.array() - mean).square().mean());
  const Eigen::MatrixXd input =
      gatherTexels(domain.grid(), composite) - gatherTexels(domain.grid(), base);
  const double inputSpread = std::sqrt((input.array() - input.mean()).square().mean());
  EXPECT_LT(spread, 0.2 * inputSpread) << spread << " vs " << inputSpread;
}

TEST(GainCompensation, RecoversLogGainsUpToTheWeightedMean) {
  // Sources 0 - 1 - 2 in a chain with exact log ratios; source 3 meets nobody.
  const Eigen::RowVector2d l0(0.2, -0.1), l1(-0.3, 0.4), l2(0.5, 0.0);
  std::vector<GainLink> links(2);
  links[0] = {0, 1, l0 - l1, 50.0};
  links[1] = {1, 2, l1 - l2, 20.0};
  const Eigen::Vector4d texels(100.0, 300.0, 50.0, 10.0);
  const Eigen::MatrixXd l = solveLogGains(4, 2, links, texels);
  for (int c = 0; c < 2; ++c) {
    EXPECT_NEAR(l(0, c) - l(1, c), l0[c] - l1[c], 1e-4);
    EXPECT_NEAR(l(1, c) - l(2, c), l1[c] - l2[c], 1e-4);
    EXPECT_NEAR(texels.head(3).dot(l.col(c).head(3)), 0.0, 1e-3);  // brightness kept
    EXPECT_NEAR(l(3, c), 0.0, 1e-9);
  }
}

TEST(GainCompensation, StitchingRemovesAPerChannelGainBetweenSources) {
  // Right half of the image from a camera with per-channel gains g; left half from the truth.
  // One chart, so that the image-space test texture is continuous on the surface.
  const TexelDomain domain(procedural::square(), 128, 128);
  Image base(128, 128, 3);  // smooth, like a photograph at texel scale
  for (int j = 0; j < 128; ++j)
    for (int i = 0; i < 128; ++i)
      for (int c = 0; c < 3; ++c)
        base.at(i, j, c) =
            0.4f + 0.15f * std::sin(0.11f * static_cast<float>(i) + static_cast<float>(c)) *
                       std::cos(0.07f * static_cast<float>(j) - static_cast<float>(c));
  const std::array<float, 3> g{1.6f, 1.3f, 0.8f};
  Image composite = base, segments(128, 128, 1);
  for (int j = 0; j < 128; ++j)
    for (int i = 64; i < 128; ++i) {
      segments.at(i, j) = 1.0f;
      for (int c = 0; c < 3; ++c) composite.at(i, j, c) *= g[c];
    }
  for (int j = 0; j < 128; ++j)
    for (int i = 0; i < 64; ++i) segments.at(i, j) = 0.5f;
  StitchOptions o;
  o.solver.kind = SolverKind::Direct;
  const StitchResult r = stitchComposite(domain, composite, segments, o);
  ASSERT_EQ(r.sourceGains.rows(), 2);
  // Which label is the right half depends on scan order; the ratio does not.
  const int right = r.sourceGains(0, 0) > r.sourceGains(1, 0) ? 0 : 1;
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(r.sourceGains(right, c) / r.sourceGains(1 - right, c), g[c], 0.02 * g[c]);
  // The result is the truth times one gain per channel: the ratio result / truth is flat.
  const Eigen::MatrixXd x = gatherTexels(domain.grid(), r.image);
  const Eigen::MatrixXd t = gatherTexels(domain.grid(), base);
  for (int c = 0; c < 3; ++c) {
    const Eigen::ArrayXd ratio = x.col(c).array() / t.col(c).array();
    const double spread = std::sqrt((ratio - ratio.mean()).square().mean()) / ratio.mean();
    EXPECT_LT(spread, 0.02) << "channel " << c;
  }
  o.compensateGains = false;  // without it the gain stays away from the source boundary
  const StitchResult plain = stitchComposite(domain, composite, segments, o);
  const Eigen::ArrayXd ratio =
      gatherTexels(domain.grid(), plain.image).col(0).array() / t.col(0).array();
  EXPECT_GT(std::sqrt((ratio - ratio.mean()).square().mean()) / ratio.mean(), 0.1);
}

TEST(GainCompensation, PartialsSeeingTheSameTexelsGiveTheirGainRatio) {
  const Eigen::MatrixXd truth = (Eigen::MatrixXd::Random(400, 3).array() * 0.3 + 0.5).matrix();
  std::vector<Eigen::MatrixXd> values{truth * 0.9, truth * 1.5};
  std::vector<Eigen::VectorXd> confidence{Eigen::VectorXd::Ones(400), Eigen::VectorXd::Zero(400)};
  confidence[1].tail(200).setOnes();  // the second sees half the texels
  const std::vector<GainLink> links = partialGainLinks(
      {compactPartial(values[0], confidence[0]), compactPartial(values[1], confidence[1])}, 3);
  ASSERT_EQ(links.size(), 1u);
  EXPECT_EQ(links[0].weight, 200.0);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(links[0].logRatio[c], std::log(0.9 / 1.5), 1e-6);
}

TEST(GainCompensation, PartialShadingSamplesAreEvenlyThinnedWithoutStoringThemAll) {
  // Two views share unknowns 0 .. n-1; the normal's x component names the unknown, so each
  // kept sample says which shared texel it came from. Thinning keeps every stride-th of them.
  const int n = 450001;  // stride ceil(n / 200000) = 3
  PartialView a, b;
  a.channels = b.channels = 3;
  Eigen::MatrixX3d normals = Eigen::MatrixX3d::Zero(n, 3);
  for (int u = 0; u < n; ++u) {
    for (PartialView* v : {&a, &b}) {
      v->unknowns.push_back(u);
      v->confidence.push_back(1.0f);
      for (int c = 0; c < 3; ++c) v->values.push_back(v == &a ? 0.5f : 0.25f);
    }
    normals(u, 0) = u;
  }
  const std::vector<ShadingSample> samples = partialShadingSamples({a, b}, normals, 3);
  ASSERT_EQ(samples.size(), static_cast<size_t>((n + 2) / 3));
  for (size_t k = 0; k < samples.size(); ++k) {
    ASSERT_EQ(samples[k].na.x(), static_cast<float>(3 * k)) << k;
    ASSERT_NEAR(samples[k].logRatio[0], std::log(2.0), 1e-6);
  }
}

TEST(GainCompensation, IlluminationFitRecoversGainAndShadingDespiteOutliers) {
  // Three sources with log illumination a_k + b_k . n; pairs observe nearby points; one sample
  // in ten sits on a texture edge (a log-ratio off by 0.7), which the robust fit must ignore.
  const std::array<double, 3> a{0.1, -0.2, 0.3};
  const std::array<Eigen::Vector3d, 3> b{Eigen::Vector3d(0.1, 0.0, -0.1),
                                         Eigen::Vector3d(-0.2, 0.15, 0.0),
                                         Eigen::Vector3d(0.0, 0.1, 0.2)};
  auto light = [&](int k, const Eigen::Vector3d& n) { return a[k] + b[k].dot(n); };
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto unit = [&] { return Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized(); };
  std::vector<ShadingSample> samples;
  for (int i = 0; i < 3000; ++i) {
    ShadingSample s;
    s.a = i % 3;
    s.b = (i + 1 + i / 3 % 2) % 3;
    if (s.a == s.b) continue;
    const Eigen::Vector3d na = unit(), nb = (na + 0.05 * unit()).normalized();
    s.na = na.cast<float>();
    s.nb = nb.cast<float>();
    const double edge = i % 10 == 0 ? 0.7 : 0.0;  // one-sided: least squares would be biased
    const double r = light(s.a, na) - light(s.b, nb) + edge + 0.002 * gauss(rng);
    s.logRatio = Eigen::Vector3f::Constant(static_cast<float>(r));
    samples.push_back(s);
  }
  const Eigen::MatrixXd fit = solveLogIllumination(3, 2, samples, Eigen::Vector3d(1e3, 1e3, 1e3));
  ASSERT_EQ(fit.rows(), 12);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d n = unit();
    for (int k = 1; k < 3; ++k) {
      auto fitted = [&](int j, int c) {
        return fit(4 * j, c) + n.dot(fit.col(c).segment<3>(4 * j + 1));
      };
      for (int c = 0; c < 2; ++c)
        EXPECT_NEAR(fitted(k, c) - fitted(0, c), light(k, n) - light(0, n), 0.01);
    }
  }
}

TEST(Stitch, LockedTexelsAreBitIdentical) {
  const TexelDomain domain(procedural::cube(3), 96, 64);
  Image composite = test::randomTexture(96, 64, 3, 23), segments(96, 64, 1), lock(96, 64, 1);
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 96; ++i) {
      segments.at(i, j) = i < 48 ? 0.25f : 0.75f;
      lock.at(i, j) = (i + j) % 7 == 0 ? 1.0f : 0.0f;
    }
  StitchOptions o;
  o.lock = lock;
  const StitchResult r = stitchComposite(domain, composite, segments, o);
  EXPECT_GT(r.lockedTexels, 0);
  const TexelGrid& g = domain.grid();
  for (int32_t t : g.texelOfUnknown) {
    const int x = t % g.nx, y = t / g.nx;
    if (!g.inImage(x, y)) continue;
    const int i = x + g.x0, j = y + g.y0;
    if (lock.at(i, j) <= 0.5f) continue;
    for (int c = 0; c < 3; ++c) ASSERT_EQ(r.image.at(i, j, c), composite.at(i, j, c));
  }
}

TEST(Stitch, CompactViewsWithHandedOverOperatorsMatchTheImagePartialsBitForBit) {
  // Three partials with different gains, shading-free, each seeing an overlapping band of
  // columns with a confidence ramp; the compact path (operators handed over and freed before
  // the solve, as `texgrad texture` runs it) must give the image path's values exactly.
  TexelDomain domain(procedural::cubeSphere(8), 96, 96);
  const Image base = test::randomTexture(96, 96, 3, 23, 0.2f, 0.8f);
  std::vector<Image> partials, confidences;
  for (int k = 0; k < 3; ++k) {
    Image p(96, 96, 3), c(96, 96, 1);
    for (int j = 0; j < 96; ++j)
      for (int i = 0; i < 96; ++i) {
        const int from = 28 * k, to = from + 40;
        if (i < from || i >= to) continue;
        c.at(i, j) = 0.25f + 0.75f * static_cast<float>(i - from) / 40.0f;
        for (int ch = 0; ch < 3; ++ch)
          p.at(i, j, ch) = (0.8f + 0.2f * static_cast<float>(k)) * base.at(i, j, ch);
      }
    partials.push_back(p);
    confidences.push_back(c);
  }
  StitchOptions o;
  const StitchResult images = stitchPartials(domain, partials, confidences, o);
  std::vector<PartialView> views;
  for (size_t k = 0; k < partials.size(); ++k)
    views.push_back(compactPartial(domain.grid(), partials[k], confidences[k]));
  const StitchResult compact =
      stitchPartials(domain, domain.releaseOperators(), std::move(views), partials[0].format, o);
  EXPECT_FALSE(domain.hasOperators());
  EXPECT_EQ(compact.sources, 3);
  ASSERT_EQ(compact.sourceGains.rows(), 3);
  EXPECT_EQ(compact.sourceGains, images.sourceGains);
  const Eigen::MatrixXd x = gatherTexels(domain.grid(), compact.image);
  EXPECT_EQ(x, gatherTexels(domain.grid(), images.image));
  EXPECT_GT(x.maxCoeff(), 0.1);  // a solution, not an empty image
}

TEST(Stitch, CompositeWithHandedOverOperatorsMatchesTheDomainsOperatorsBitForBit) {
  // Two sources with different gains; the hand-over frees the operators before the solve (as
  // `texgrad texture --select best` runs it) and must not change a bit of the result.
  TexelDomain domain(procedural::cubeSphere(8), 96, 96);
  Image composite = test::randomTexture(96, 96, 3, 24, 0.2f, 0.8f), segments(96, 96, 1);
  for (int j = 0; j < 96; ++j)
    for (int i = 0; i < 96; ++i) {
      segments.at(i, j) = i < 48 ? 0.5f : 1.0f;
      if (i >= 48)
        for (int c = 0; c < 3; ++c) composite.at(i, j, c) *= 1.3f;
    }
  const StitchOptions o;
  const StitchResult kept = stitchComposite(domain, composite, segments, o);
  const StitchResult freed =
      stitchComposite(domain, domain.releaseOperators(), composite, segments, o);
  EXPECT_FALSE(domain.hasOperators());
  EXPECT_EQ(freed.sources, 2);
  EXPECT_EQ(freed.sourceGains, kept.sourceGains);
  EXPECT_EQ(freed.image.pixels, kept.image.pixels);
}

TEST(Stitch, PartialsNeedOneConfidencePerTexture) {
  const TexelDomain domain(procedural::cube(2), 48, 32);
  const std::vector<Image> partials(2, Image(48, 32, 3));
  const std::vector<Image> confidences(1, Image(48, 32, 1));
  EXPECT_THROW(stitchPartials(domain, partials, confidences, {}), InvalidInputError);
}

/// Error measures against multiview_bob's truth.
struct Quality {
  double rmsAfterFit = 0.0;  ///< RMS to truth after a per-channel gain/offset fit
  /// Systematic step across source boundaries: per pair of sources and channel, the mean over
  /// their neighbouring texel pairs of the step the result has and the truth does not; RMS over
  /// those means weighted by pair count (what shows as a lighting seam).
  double boundaryJump = 0.0;
};

Quality quality(const TexelGrid& g, Image result, const Image& truth,
                const std::vector<int32_t>& labels) {
  for (float& v : result.pixels) v = std::clamp(v, 0.0f, 1.0f);  // what an 8-bit file holds
  const Eigen::MatrixXd x = gatherTexels(g, result).leftCols(3),
                        t = gatherTexels(g, truth).leftCols(3);
  Quality q;
  std::vector<uint8_t> known(labels.size());
  for (size_t k = 0; k < labels.size(); ++k) known[k] = labels[k] > 0;
  Eigen::MatrixXd fitted = x;
  for (Eigen::Index c = 0; c < 3; ++c) {
    double n = 0, sx = 0, st = 0, sxx = 0, sxt = 0;
    for (Eigen::Index u = 0; u < x.rows(); ++u) {
      if (!known[u]) continue;
      n += 1, sx += x(u, c), st += t(u, c), sxx += x(u, c) * x(u, c), sxt += x(u, c) * t(u, c);
    }
    const double gain = (n * sxt - sx * st) / (n * sxx - sx * sx), offset = (st - gain * sx) / n;
    fitted.col(c) = gain * x.col(c).array() + offset;
  }
  double err = 0, count = 0, jump = 0, pairs = 0;
  for (Eigen::Index u = 0; u < x.rows(); ++u)
    if (known[u]) err += (fitted.row(u) - t.row(u)).squaredNorm(), count += 3;
  q.rmsAfterFit = std::sqrt(err / count);
  // Horizontal and vertical neighbours with different source labels, oriented low -> high label.
  std::map<std::pair<int, int>, std::pair<Eigen::Vector3d, double>> steps;
  for (int32_t tex : g.texelOfUnknown) {
    const int x0 = tex % g.nx, y0 = tex / g.nx, u = g.unknownOfTexel[tex];
    for (const auto& [dx, dy] : {std::pair{1, 0}, {0, 1}}) {
      if (x0 + dx >= g.nx || y0 + dy >= g.ny) continue;
      int v = g.unknownOfTexel[g.texelIndex(x0 + dx, y0 + dy)], w = u;
      if (v < 0 || labels[w] == 0 || labels[v] == 0 || labels[w] == labels[v]) continue;
      if (labels[w] > labels[v]) std::swap(w, v);
      auto& entry = steps[{labels[w], labels[v]}];
      if (entry.second == 0.0) entry.first.setZero();
      entry.first += ((fitted.row(v) - fitted.row(w)) - (t.row(v) - t.row(w))).transpose();
      entry.second += 1;
    }
  }
  for (const auto& [key, entry] : steps) {
    jump += entry.first.squaredNorm() / entry.second;  // n * |mean|^2
    pairs += 3 * entry.second;
  }
  q.boundaryJump = std::sqrt(jump / std::max(1.0, pairs));
  return q;
}

TEST(StitchSlow, MultiviewBobHalvesTheErrorAndCutsSourceJumpsFiveFold) {
  const std::filesystem::path dir = test::sharedData() / "multiview_bob";
  const Image composite = readImage(dir / "texels.png"), segments = readImage(dir / "mask.png");
  const Image truth = readImage(dir / "truth.png");
  const TexelDomain domain(readMesh(test::sharedData() / "bob" / "bob_tri.obj"), composite.width,
                           composite.height);
  int sources = 0;
  const std::vector<int32_t> labels = sourceLabels(domain.grid(), segments, sources);
  EXPECT_EQ(sources, 6);
  const Quality before = quality(domain.grid(), composite, truth, labels);

  const StitchOptions options;  // paper defaults (alpha = 1e2)
  const StitchResult a = stitchComposite(domain, composite, segments, options);
  const Quality composited = quality(domain.grid(), a.image, truth, labels);
  std::cout << "[ stitch ] composite mode: RMS " << before.rmsAfterFit << " -> "
            << composited.rmsAfterFit << ", source jump " << before.boundaryJump << " -> "
            << composited.boundaryJump << "\n";
  // Issue 5 asks for half the composite's RMS. The views differ by gain, colour cast and a
  // smooth shading term: one gain per source and channel left the shading inside each region
  // (0.106 -> 0.057, 0.54x); the per-source illumination model exp(a + b . n) removes most of it.
  EXPECT_LE(composited.rmsAfterFit, 0.5 * before.rmsAfterFit);
  EXPECT_LE(composited.boundaryJump, 0.2 * before.boundaryJump);

  std::vector<Image> partials, confidences;
  for (int k = 0; k < 6; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "texels-%02d.png", k);
    partials.push_back(readImage(dir / name));
    std::snprintf(name, sizeof name, "mask-%02d.png", k);
    confidences.push_back(readImage(dir / name));
  }
  const StitchResult b = stitchPartials(domain, partials, confidences, options);
  const Quality blended = quality(domain.grid(), b.image, truth, labels);
  std::cout << "[ stitch ] partials mode: RMS " << before.rmsAfterFit << " -> "
            << blended.rmsAfterFit << ", source jump " << before.boundaryJump << " -> "
            << blended.boundaryJump << "\n";
  EXPECT_LE(blended.rmsAfterFit, 0.5 * before.rmsAfterFit);
  EXPECT_LE(blended.boundaryJump, 0.2 * before.boundaryJump);
}

}  // namespace
}  // namespace texgrad
