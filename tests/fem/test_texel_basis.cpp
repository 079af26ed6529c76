// Function-space guarantees (paper Sec. 4): partition of unity, phi_t = B_t on interior
// texels, seam continuity; clipping conformity and lattice-aligned input.
#include <gtest/gtest.h>

#include <random>

#include "fem_fixtures.h"
#include "texgrad/fem/quadrature.h"
#include "texgrad/fem/texel_basis.h"

namespace texgrad::fem {
namespace {

constexpr double kTight = 1e-12;
constexpr int kSamples = 1000;

struct Case {
  const char* name;
  TexturedMesh mesh;
  int resolution;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  out.push_back({"square", test::gridSquare(3, 0.9, 0.8, 0.031, 0.077), 32});
  out.push_back({"aligned", test::gridSquare(4), 32});
  out.push_back({"twoChart", test::twoChartSquare(5), 64});
  out.push_back({"twoChartDense", test::twoChartSquare(3, 0.05), 256});
  out.push_back({"sphere", test::cubeSphere(4), 48});
  out.push_back({"sphereFine", test::cubeSphere(9), 200});
  return out;
}

TEST(Quadrature, IntegratesMonomialsExactly) {
  auto factorial = [](int n) {
    double f = 1;
    for (int k = 2; k <= n; ++k) f *= k;
    return f;
  };
  for (int degree : {2, 4, 6}) {
    const auto rule = triangleRule(degree);
    double weightSum = 0;
    for (const auto& q : rule) weightSum += q.weight;
    EXPECT_NEAR(weightSum, 1.0, 1e-15);
    for (int i = 0; i <= degree; ++i)
      for (int j = 0; i + j <= degree; ++j) {
        double sum = 0;
        for (const auto& q : rule) sum += q.weight * std::pow(q.b1, i) * std::pow(q.b2, j);
        const double exact = 2.0 * factorial(i) * factorial(j) / factorial(i + j + 2);
        EXPECT_NEAR(sum, exact, 1e-15) << "degree " << degree << " x^" << i << " y^" << j;
      }
  }
  double sum = 0;
  for (const auto& [t, w] : segmentRule()) sum += w * std::pow(t, 5);
  EXPECT_NEAR(sum, 1.0 / 6.0, 1e-15);
}

TEST(CellClipping, PiecesTileEveryFaceAndShareEdgePoints) {
  for (const auto& c : cases()) {
    const Atlas atlas = buildAtlas(c.mesh);
    const TexelGrid grid = buildTexelGrid(c.mesh, atlas, c.resolution, c.resolution);
    const TexelBasis basis(c.mesh, atlas, grid);
    FaceClip clip;
    for (int f = 0; f < basis.faceCount(); ++f) {
      basis.clipFace(f, clip);
      EXPECT_EQ(clip.unexpectedCrossings, 0) << c.name;
      double area = 0;
      for (const auto& piece : clip.pieces) {
        const auto poly = clip.polygon(piece);
        area += polygonArea(poly);
        for (size_t i = 0; i < poly.size(); ++i) {
          EXPECT_NE(poly[i].p, poly[(i + 1) % poly.size()].p) << c.name << " duplicate point";
          EXPECT_GE(poly[i].p.x(), piece.cellX);
          EXPECT_LE(poly[i].p.x(), piece.cellX + 1);
          EXPECT_GE(poly[i].p.y(), piece.cellY);
          EXPECT_LE(poly[i].p.y(), piece.cellY + 1);
        }
      }
      const auto& k = basis.faceCorners(f);
      const Eigen::Vector2d e1 = k[1] - k[0], e2 = k[2] - k[0];
      EXPECT_NEAR(area, 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x()), 1e-11) << c.name;
    }
  }
}

TEST(CellClipping, LatticeCrossingsAreCanonical) {
  const Eigen::Vector2d a(0.3, 0.2), b(7.0, 3.0), mid(2.0, 1.0);
  const auto forward = latticeCrossings(a, b);
  const auto backward = latticeCrossings(b, a);
  ASSERT_EQ(forward.size(), backward.size());
  for (size_t i = 0; i < forward.size(); ++i)
    EXPECT_EQ(forward[i].p, backward[forward.size() - 1 - i].p);
  // Through a lattice point: one event on both lines.
  const auto through = latticeCrossings({0.5, 0.5}, {2.5, 2.5});
  ASSERT_EQ(through.size(), 2u);
  EXPECT_EQ(through[0].p, Eigen::Vector2d(1, 1));
  EXPECT_EQ(through[0].onX, 1);
  EXPECT_EQ(through[0].onY, 1);
  EXPECT_TRUE(latticeCrossings(mid, {2.0, 3.5}).size() == 2u) << "vertical edge on a line";
}

TEST(TexelBasis, PartitionOfUnity) {
  for (const auto& c : cases()) {
    const Atlas atlas = buildAtlas(c.mesh);
    const TexelGrid grid = buildTexelGrid(c.mesh, atlas, c.resolution, c.resolution);
    const TexelBasis basis(c.mesh, atlas, grid);
    std::mt19937_64 rng(7);
    double worst = 0;
    for (int k = 0; k < kSamples; ++k) {
      double sum = 0;
      for (const auto& w : basis.evaluate(basis.randomPoint(rng))) sum += w.weight;
      worst = std::max(worst, std::abs(sum - 1.0));
    }
    EXPECT_LE(worst, kTight) << c.name;
  }
}

TEST(TexelBasis, ReproducesBilinearOnInteriorTexels) {
  for (const auto& c : cases()) {
    const Atlas atlas = buildAtlas(c.mesh);
    const TexelGrid grid = buildTexelGrid(c.mesh, atlas, c.resolution, c.resolution);
    const TexelBasis basis(c.mesh, atlas, grid);
    std::mt19937_64 rng(11);
    int checked = 0;
    for (int k = 0; k < kSamples; ++k) {
      const SurfacePoint p = basis.randomPoint(rng);
      const auto weights = basis.evaluate(p);
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const int x = int(std::floor(p.grid.x())) + dx, y = int(std::floor(p.grid.y())) + dy;
          if (x < 0 || y < 0 || x >= grid.nx || y >= grid.ny) continue;
          const int t = grid.texelIndex(x, y);
          if (grid.texelClass[t] != TexelClass::Interior) continue;
          const int u = grid.unknownOfTexel[t];
          double phi = 0;
          for (const auto& w : weights)
            if (w.unknown == u) phi = w.weight;
          EXPECT_NEAR(phi, test::bilinear(grid, u, p.grid), kTight) << c.name;
          ++checked;
        }
    }
    EXPECT_GT(checked, 0) << c.name;
  }
}

TEST(TexelBasis, ContinuousAcrossSeams) {
  for (const auto& c : cases()) {
    const Atlas atlas = buildAtlas(c.mesh);
    if (atlas.seams.empty()) continue;
    const TexelGrid grid = buildTexelGrid(c.mesh, atlas, c.resolution, c.resolution);
    const TexelBasis basis(c.mesh, atlas, grid);
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    Eigen::VectorXd x(grid.unknownCount());
    for (auto& v : x) v = unit(rng);
    double worst = 0;
    for (int k = 0; k < kSamples; ++k) {
      const auto [p, q] = basis.randomSeamPair(rng);
      EXPECT_LT((basis.position(p) - basis.position(q)).norm(), 1e-12);
      worst = std::max(worst, std::abs(basis.evaluate(p, x) - basis.evaluate(q, x)));
    }
    EXPECT_LE(worst, kTight) << c.name;
    // The bilinear baseline is not continuous there.
    const TexelBasis plain(c.mesh, atlas, grid, {BasisKind::Bilinear});
    double jump = 0;
    for (int k = 0; k < 200; ++k) {
      const auto [p, q] = plain.randomSeamPair(rng);
      jump = std::max(jump, std::abs(plain.evaluate(p, x) - plain.evaluate(q, x)));
    }
    EXPECT_GT(jump, 1e-3) << c.name;
  }
}

}  // namespace
}  // namespace texgrad::fem
