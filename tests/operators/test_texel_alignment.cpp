// Operator invariants (paper Sec. 5) on a cube whose UVs lie on texel centres, so that chart
// edges run on lattice lines, and on the same cube moved up to 1e-4 texel off the lattice
// (issue 31): unmoved coordinates and coordinates within kLatticeSnapTexels of a line must give
// the same, well-conditioned operators.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <memory>
#include <random>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/procedural.h"
#include "texgrad/operators/texel_operators.h"

namespace texgrad {
namespace {

/// UV offset of the jittered cube, in texels (below kLatticeSnapTexels).
constexpr double kJitterTexels = 1e-4;

struct CubeOperators {
  TexturedMesh mesh;
  Atlas atlas;
  TexelGrid grid;
  std::unique_ptr<TexelOperators> ops;
};

std::unique_ptr<CubeOperators> buildCube(double jitter) {
  auto c = std::make_unique<CubeOperators>();
  c->mesh = procedural::alignedCube(4, jitter);
  c->atlas = buildAtlas(c->mesh);
  c->grid = buildTexelGrid(c->mesh, c->atlas, procedural::kAlignedCubeResolution,
                           procedural::kAlignedCubeResolution);
  c->ops = std::make_unique<TexelOperators>(c->mesh, c->atlas, c->grid);
  return c;
}

TEST(TexelAlignment, CubeOperatorsKeepTheirInvariants) {
  for (double jitter : {0.0, kJitterTexels}) {
    const auto c = buildCube(jitter);
    const SparseMatrixd& m = c->ops->mass();
    const SparseMatrixd s(c->ops->stiffness());
    const Eigen::VectorXd one = Eigen::VectorXd::Ones(m.rows());
    EXPECT_EQ(c->ops->report().unexpectedCrossings, 0) << jitter;
    EXPECT_NEAR(one.dot(m * one), 1.0, 1e-9) << jitter;
    EXPECT_LE((s * one).norm(), 1e-10 * s.diagonal().norm()) << jitter;
    EXPECT_EQ((m - SparseMatrixd(m.transpose())).norm(), 0.0) << jitter;
    EXPECT_EQ((s - SparseMatrixd(s.transpose())).norm(), 0.0) << jitter;
    Eigen::SimplicialLLT<SparseMatrixd> llt(m);
    ASSERT_EQ(llt.info(), Eigen::Success) << jitter << ": M not positive definite";
    // Every texel carries a share of the surface: the lightest row of M is at least a corner
    // texel's (one cell of four, seam-averaged), not a sliver's (~1e-19 of the heaviest).
    EXPECT_GT(m.diagonal().minCoeff(), 0.1 * m.diagonal().maxCoeff()) << jitter;
    // Stiffness stays that of texel-sized pieces: no ramp across a sliver.
    EXPECT_LT(s.diagonal().maxCoeff(), 10.0) << jitter;
    // Partition of unity (paper Sec. 4) at random points of M.
    std::mt19937_64 rng(31);
    double worst = 0.0;
    for (int k = 0; k < 2000; ++k) {
      double sum = 0.0;
      for (const auto& w : c->ops->basis().evaluate(c->ops->basis().randomPoint(rng)))
        sum += w.weight;
      worst = std::max(worst, std::abs(sum - 1.0));
    }
    EXPECT_LE(worst, 1e-12) << jitter;
  }
}

TEST(TexelAlignment, CoordinatesWithinTheSnapDistanceGiveTheAlignedOperators) {
  const auto aligned = buildCube(0.0), jittered = buildCube(kJitterTexels);
  ASSERT_EQ(jittered->grid.unknownCount(), aligned->grid.unknownCount());
  EXPECT_EQ(jittered->grid.texelOfUnknown, aligned->grid.texelOfUnknown);
  const SparseMatrixd dm = jittered->ops->mass() - aligned->ops->mass();
  const SparseMatrixd ds =
      SparseMatrixd(jittered->ops->stiffness()) - SparseMatrixd(aligned->ops->stiffness());
  EXPECT_EQ(dm.norm(), 0.0);
  EXPECT_EQ(ds.norm(), 0.0);
}

}  // namespace
}  // namespace texgrad
