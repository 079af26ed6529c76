// Solver tests: per-chart grid hierarchy (paper §6.1) on synthetic texel grids.
#include <gtest/gtest.h>

#include "synthetic_problem.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/galerkin.h"
#include "texgrad/solver/grid_hierarchy.h"

using namespace texgrad;

TEST(GridHierarchy, LevelZeroIsTheTexelGrid) {
  const test::SyntheticProblem p = test::multiChartProblem(8);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  ASSERT_GE(h.levelCount(), 3);
  EXPECT_EQ(h.chartCount(), 3);
  const GridLevel& l0 = h.level(0);
  ASSERT_EQ(l0.unknownCount(), p.grid.unknownCount());
  for (int u = 0; u < l0.unknownCount(); ++u) {
    const size_t t = static_cast<size_t>(p.grid.texelOfUnknown[static_cast<size_t>(u)]);
    EXPECT_EQ(l0.chartOf(u), p.grid.chartOfUnknown[static_cast<size_t>(u)]);
    const LatticePoint at = l0.point(u);
    EXPECT_EQ(at.x, static_cast<int>(t) % p.grid.nx);
    EXPECT_EQ(at.y, static_cast<int>(t) / p.grid.nx);
    EXPECT_EQ(l0.footprintInterior[static_cast<size_t>(u)] != 0, p.grid.texelClass[t] == TexelClass::Interior);
    EXPECT_EQ(l0.unknownOfSlot[static_cast<size_t>(l0.slotOfUnknown[static_cast<size_t>(u)])], u);
  }
}

TEST(GridHierarchy, ProlongationReproducesConstantsAndCoarsensByFour) {
  const test::SyntheticProblem p = test::multiChartProblem(16);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  ASSERT_EQ(h.levelCount(), 5);
  for (int l = 0; l + 1 < h.levelCount(); ++l) {
    const Eigen::SparseMatrix<double>& pl = h.prolongation(l);
    ASSERT_EQ(pl.rows(), h.level(l).unknownCount());
    ASSERT_EQ(pl.cols(), h.level(l + 1).unknownCount());
    const Eigen::VectorXd ones = pl * Eigen::VectorXd::Ones(pl.cols());
    EXPECT_NEAR(ones.minCoeff(), 1.0, 1e-15);  // bilinear up-sampling is a partition of unity
    EXPECT_NEAR(ones.maxCoeff(), 1.0, 1e-15);
    const Eigen::RowVectorXd colSums = Eigen::RowVectorXd::Ones(pl.rows()) * pl;
    EXPECT_GT(colSums.minCoeff(), 0.0);  // every coarse texel has a fine child
    EXPECT_LT(h.level(l + 1).unknownCount(), h.level(l).unknownCount() / 2);
  }
}

TEST(GridHierarchy, CoarseInteriorMeansFootprintInsideChart) {
  const test::SyntheticProblem p = test::squareProblem(64);
  const GridHierarchy h = GridHierarchy::build(p.grid, 3, 16);
  ASSERT_EQ(h.levelCount(), 4);
  // Full cells are [1, 64]^2: level-l texel (x, y) at fine (2^l x, 2^l y) is interior iff
  // [2^l (x - 1), 2^l (x + 1)] lies in [1, 65] in both axes.
  for (int l = 1; l < h.levelCount(); ++l) {
    const GridLevel& g = h.level(l);
    const int s = 1 << l;
    for (int u = 0; u < g.unknownCount(); ++u) {
      const auto [box, x, y] = g.point(u);
      const bool expected = s * (x - 1) >= 1 && s * (x + 1) <= 65 && s * (y - 1) >= 1 && s * (y + 1) <= 65;
      EXPECT_EQ(g.footprintInterior[static_cast<size_t>(u)] != 0, expected) << "level " << l;
    }
  }
}

TEST(GridHierarchy, StopsCoarseningTinyCharts) {
  const test::SyntheticProblem p = test::squareProblem(6);
  const GridHierarchy h = GridHierarchy::build(p.grid, 8, 16);
  EXPECT_LT(h.levelCount(), 9);
  EXPECT_GE(h.level(h.levelCount() - 1).unknownCount(), 1);
}

TEST(GridHierarchy, UnknownOfSlotFreedIsRebuiltAsBuiltAndProlongationsDoWithoutIt) {
  const test::SyntheticProblem p = test::multiChartProblem(16);
  const GridHierarchy built = GridHierarchy::build(p.grid, 4, 16);
  GridHierarchy h = built;
  const int64_t whole = h.storageBytes();
  h.releaseUnknownOfSlot();
  EXPECT_LT(h.storageBytes(), whole);
  for (int l = 0; l < h.levelCount(); ++l) {
    EXPECT_TRUE(h.level(l).unknownOfSlot.empty()) << "level " << l;
    if (l + 1 < h.levelCount()) {
      EXPECT_EQ((h.prolongation(l) - built.prolongation(l)).norm(), 0.0) << "level " << l;
    }
  }
  const Eigen::SparseMatrix<double> a = p.system(1.0);
  EXPECT_THROW(galerkinProduct(a, h.level(0), h.level(1)), InvalidInputError);
  h.restoreUnknownOfSlot();
  for (int l = 0; l < h.levelCount(); ++l)
    EXPECT_EQ(h.level(l).unknownOfSlot, built.level(l).unknownOfSlot) << "level " << l;
  EXPECT_EQ((galerkinProduct(a, h.level(0), h.level(1)) -
             galerkinProduct(a, built.level(0), built.level(1))).norm(), 0.0);
  EXPECT_EQ(h.storageBytes(), whole);
}

TEST(GridHierarchy, PointOfEverySlotIsThatSlotOfItsBox) {
  // Boxes of several widths over many pages of slots (boxOfSlotPage), on every level.
  const test::SyntheticProblem p = test::multiChartProblem(64);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  ASSERT_GE(h.levelCount(), 4);
  ASSERT_GT(h.level(0).slotCount, int64_t{64} << GridLevel::kSlotPageBits);
  for (int l = 0; l < h.levelCount(); ++l) {
    const GridLevel& g = h.level(l);
    for (int64_t s = 0; s < g.slotCount; ++s) {
      const LatticePoint at = g.pointOfSlot(s);
      ASSERT_GE(at.box, 0);
      const GridBox& box = g.boxes[static_cast<size_t>(at.box)];
      ASSERT_TRUE(box.contains(at.x, at.y)) << "level " << l << " slot " << s;
      ASSERT_EQ(box.slot(at.x, at.y), s) << "level " << l;
    }
  }
}
