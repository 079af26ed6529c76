// Function-space guarantees (paper Sec. 4) on every mesh of ../shared/data at 256^2 and
// 1024^2: partition of unity at random points and continuity at random seam-equivalent pairs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <tuple>

#include "fem_fixtures.h"
#include "shared_meshes.h"
#include "texgrad/fem/texel_basis.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad::fem {
namespace {

constexpr double kTight = 1e-12;
constexpr int kSamples = 1000;
/// Bound on |d/ds (sum x_t phi_t)| per texel of arc along a seam side, per unit |x|_inf, for
/// s the arc length on the denser side: bilinear data are 2 sqrt(2)-Lipschitz per texel and
/// quadratic interpolation of Lipschitz data is at most 4 times steeper (Lagrange end-point
/// derivative), rounded up.
constexpr double kSlopeBound = 12.0;

using Param = std::tuple<test::SharedMesh, int>;

class SharedMeshBasis : public ::testing::TestWithParam<Param> {};

/// Length (texels) of the face edge a point lies on (the one nearest to it).
double edgeLength(const TexelBasis& basis, const SurfacePoint& point) {
  const auto& c = basis.faceCorners(point.face);
  double best = std::numeric_limits<double>::infinity(), length = 0.0;
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector2d a = c[e], d = c[(e + 1) % 3] - a, r = point.grid - a;
    const double distance = std::abs(d.x() * r.y() - d.y() * r.x()) / d.norm();
    if (distance < best) {
      best = distance;
      length = d.norm();
    }
  }
  return length;
}

/// Rounding bound for comparing f at p and q = the seam-equivalent point of p. Both points are
/// computed as a + u (b - a) on their own UV edge, so each carries a position error of about
/// eps |p|_inf texels, i.e. an error of eps |p|_inf / L_p in the seam parameter u (L_p = edge
/// length in texels). Along the seam, f varies with u at most kSlopeBound |x|_inf L_max per unit
/// u (L_max = the denser side's length). Two points on different sides cannot agree better.
/// At 1024^2 with L_p ~ L_q this is ~1e-12; on lpshead some seams have sides 100x apart in
/// texel length and pairs differ by up to ~5e-12, all within 0.7 of this bound. A genuine
/// discontinuity is orders larger (a point-location bug once gave jumps of 0.2 there).
double roundingBound(const TexelBasis& basis, const SurfacePoint& p, const SurfacePoint& q,
                     double xMax) {
  const double lp = edgeLength(basis, p), lq = edgeLength(basis, q);
  const double eps = std::numeric_limits<double>::epsilon();
  const double du = eps * (p.grid.cwiseAbs().maxCoeff() / lp + q.grid.cwiseAbs().maxCoeff() / lq);
  return kSlopeBound * xMax * std::max(lp, lq) * du;
}

TEST_P(SharedMeshBasis, PartitionOfUnityAndSeamContinuity) {
  const auto& [shared, resolution] = GetParam();
  const TexturedMesh mesh = readMesh(test::sharedData() / shared.obj);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, resolution, resolution);
  const TexelBasis basis(mesh, atlas, grid);
  std::mt19937_64 rng(7);

  double worstUnity = 0.0, worstBilinear = 0.0;
  int bilinearChecks = 0;
  for (int k = 0; k < kSamples; ++k) {
    const SurfacePoint p = basis.randomPoint(rng);
    const auto weights = basis.evaluate(p);
    double sum = 0.0;
    for (const auto& w : weights) sum += w.weight;
    worstUnity = std::max(worstUnity, std::abs(sum - 1.0));
    // Bilinear reproduction: phi_t = B_t on the footprint of every interior texel t.
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const int x = static_cast<int>(std::floor(p.grid.x())) + dx;
        const int y = static_cast<int>(std::floor(p.grid.y())) + dy;
        if (x < 0 || y < 0 || x >= grid.nx || y >= grid.ny) continue;
        const int t = grid.texelIndex(x, y);
        if (grid.texelClass[static_cast<size_t>(t)] != TexelClass::Interior) continue;
        const int u = grid.unknownOfTexel[static_cast<size_t>(t)];
        double phi = 0.0;
        for (const auto& w : weights)
          if (w.unknown == u) phi = w.weight;
        worstBilinear = std::max(worstBilinear, std::abs(phi - test::bilinear(grid, u, p.grid)));
        ++bilinearChecks;
      }
  }
  EXPECT_LE(worstUnity, kTight);
  EXPECT_GT(bilinearChecks, kSamples);  // most random points lie in interior footprints
  EXPECT_LE(worstBilinear, kTight);

  if (shared.seamEdges == 0) {
    EXPECT_EQ(basis.seamCount(), 0);
    return;
  }
  ASSERT_GT(basis.seamCount(), 0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::VectorXd x(grid.unknownCount());
  for (auto& v : x) v = unit(rng);
  Eigen::Vector3d lo = mesh.positions.front(), hi = lo;
  for (const auto& v : mesh.positions) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double extent = (hi - lo).norm();
  double worstJump = 0.0, worstRatio = 0.0;
  int aboveTight = 0;
  for (int k = 0; k < kSamples; ++k) {
    const auto [p, q] = basis.randomSeamPair(rng);
    EXPECT_LE((basis.position(p) - basis.position(q)).norm(), 1e-12 * extent);
    const double jump = std::abs(basis.evaluate(p, x) - basis.evaluate(q, x));
    const double bound = std::max(kTight, roundingBound(basis, p, q, x.cwiseAbs().maxCoeff()));
    EXPECT_LE(jump, bound) << "seam pair on faces " << p.face << " and " << q.face;
    worstJump = std::max(worstJump, jump);
    worstRatio = std::max(worstRatio, jump / bound);
    aboveTight += jump > kTight;
  }
  std::printf(
      "%s %d: max |1 - sum phi| %.2e, max |phi - B| %.2e over %d interior checks, max seam jump "
      "%.2e (%d of %d pairs above %.0e; max jump / rounding bound %.2f)\n",
      shared.name.c_str(), resolution, worstUnity, worstBilinear, bilinearChecks, worstJump,
      aboveTight, kSamples, kTight, worstRatio);
}

std::string paramName(const ::testing::TestParamInfo<Param>& info) {
  return std::get<0>(info.param).name + "_" + std::to_string(std::get<1>(info.param));
}

// 1024^2 over all meshes takes tens of seconds (more under ASan): Release pass only.
INSTANTIATE_TEST_SUITE_P(AllMeshes256, SharedMeshBasis,
                         ::testing::Combine(::testing::ValuesIn(test::sharedMeshes()),
                                            ::testing::Values(256)),
                         paramName);
INSTANTIATE_TEST_SUITE_P(AllMeshes1024Slow, SharedMeshBasis,
                         ::testing::Combine(::testing::ValuesIn(test::sharedMeshes()),
                                            ::testing::Values(1024)),
                         paramName);

}  // namespace
}  // namespace texgrad::fem
