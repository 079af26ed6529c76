// Filter and geodesic on a cube whose UVs lie on texel centres (chart edges on lattice lines) and
// on the same cube moved up to 1e-4 texel off the lattice (issue 31): constants stay constant,
// both meshes give the same result, and no value leaves the input's range.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "app_fixtures.h"
#include "texgrad/apps/filter.h"
#include "texgrad/apps/geodesic.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

constexpr int kSize = procedural::kAlignedCubeResolution;
/// UV offset of the jittered cube, in texels (below kLatticeSnapTexels).
constexpr double kJitterTexels = 1e-4;
/// How far a smoothing filter (beta <= 1) or a distance may leave the input's range, as a
/// fraction of it. The consistent mass matrix has no discrete maximum principle, so a screened
/// Poisson solution may overshoot by a rounding-level amount; on this atlas it does not at all
/// (measured 0 for the noise texture), and before the lattice snap the jittered cube reached
/// -375 .. 71219 for an input in [0, 1].
constexpr double kRangeMargin = 1e-3;

/// Values of the active in-image texels by image texel (y * width + x), NaN elsewhere.
std::vector<double> byImageTexel(const TexelGrid& grid, const Eigen::VectorXd& values) {
  std::vector<double> out(static_cast<size_t>(kSize * kSize), std::nan(""));
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const int t = grid.texelOfUnknown[static_cast<size_t>(u)];
    const int x = t % grid.nx, y = t / grid.nx;
    if (grid.inImage(x, y))
      out[static_cast<size_t>((y + grid.y0) * kSize + x + grid.x0)] = values[u];
  }
  return out;
}

/// Largest difference over texels active in both, relative to the range of `a`.
double relativeDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double lo = INFINITY, hi = -INFINITY, worst = 0.0;
  for (size_t k = 0; k < a.size(); ++k) {
    if (std::isnan(a[k]) || std::isnan(b[k])) continue;
    lo = std::min(lo, a[k]);
    hi = std::max(hi, a[k]);
    worst = std::max(worst, std::abs(a[k] - b[k]));
  }
  return worst / (hi - lo);
}

Image constantTexture(float value) {
  Image image(kSize, kSize, 1, PixelFormat::Float);
  std::fill(image.pixels.begin(), image.pixels.end(), value);
  return image;
}

FilterOptions filterOptions(double beta, SolverKind kind) {
  FilterOptions o;
  o.beta = beta;
  o.solver.kind = kind;
  return o;
}

TEST(TexelAlignment, ConstantTextureStaysConstant) {
  const float value = 200.0f / 255.0f;
  for (double jitter : {0.0, kJitterTexels}) {
    const TexelDomain domain(procedural::alignedCube(4, jitter), kSize, kSize);
    for (SolverKind kind : {SolverKind::MultigridCg, SolverKind::Direct})
      for (double beta : {0.0, 1.0, 3.0}) {
        const Image out =
            filterTexture(domain, constantTexture(value), filterOptions(beta, kind)).image;
        const Eigen::MatrixXd x = gatherTexels(domain.grid(), out);
        EXPECT_LE((x.array() - value).abs().maxCoeff(), 1e-6)
            << "jitter " << jitter << " beta " << beta << " " << toString(kind);
      }
  }
}

TEST(TexelAlignment, FilterAgreesWithTheJitteredCubeAndStaysInRange) {
  const TexelDomain aligned(procedural::alignedCube(), kSize, kSize);
  const TexelDomain jittered(procedural::alignedCube(4, kJitterTexels), kSize, kSize);
  const Image noise = test::randomTexture(kSize, kSize, 1, 31);
  for (double beta : {0.0, 3.0}) {
    const FilterOptions o = filterOptions(beta, SolverKind::MultigridCg);
    const Eigen::VectorXd a = gatherTexels(aligned.grid(), filterTexture(aligned, noise, o).image);
    const Eigen::VectorXd j =
        gatherTexels(jittered.grid(), filterTexture(jittered, noise, o).image);
    EXPECT_LE(relativeDifference(byImageTexel(aligned.grid(), a), byImageTexel(jittered.grid(), j)),
              1e-3)
        << "beta " << beta;
    if (beta > 1.0) continue;  // sharpening leaves the range by design
    for (const Eigen::VectorXd* x : {&a, &j}) {
      EXPECT_GE(x->minCoeff(), -kRangeMargin) << "beta " << beta;
      EXPECT_LE(x->maxCoeff(), 1.0 + kRangeMargin) << "beta " << beta;
    }
  }
}

TEST(TexelAlignment, GeodesicAgreesWithTheJitteredCubeAndStaysInRange) {
  const TexelDomain aligned(procedural::alignedCube(), kSize, kSize);
  const TexelDomain jittered(procedural::alignedCube(4, kJitterTexels), kSize, kSize);
  const GeodesicSource source = GeodesicSource::atVertex(0);  // a corner of the cube
  const GeodesicResult a = geodesicDistance(aligned, std::span(&source, 1));
  const GeodesicResult j = geodesicDistance(jittered, std::span(&source, 1));
  EXPECT_LE(relativeDifference(byImageTexel(aligned.grid(), a.distances),
                               byImageTexel(jittered.grid(), j.distances)),
            1e-3);
  // From a corner of the unit cube the farthest point, the opposite corner, is sqrt(5) away.
  for (const GeodesicResult* r : {&a, &j}) {
    EXPECT_NEAR(r->maxDistance, std::sqrt(5.0), 0.05 * std::sqrt(5.0));
    EXPECT_GE(r->distances.minCoeff(), -kRangeMargin * r->maxDistance);
    EXPECT_LE(r->distances.maxCoeff(), (1.0 + kRangeMargin) * r->maxDistance);
  }
}

}  // namespace
}  // namespace texgrad
