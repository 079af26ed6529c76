// The lattice's classification rule (classifyLattice) on hand-made cell covers: cell coverage
// from covered area, texel classes from footprints, chart ownership and the unknown numbering.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "texgrad/core/error.h"
#include "texgrad/lattice/texel_grid.h"

namespace texgrad {
namespace {

/// An nx x ny grid placed at the image origin, with an all-empty cover of its cells.
struct Lattice {
  TexelGrid grid;
  CellCover cover;
  Lattice(int nx, int ny) : grid(makeGrid(nx, ny)), cover(grid.cellCount()) {}
  /// Puts `area` of `chart` into cell (a, b), as the rasteriser adds one chart's share.
  void add(int a, int b, int chart, double area) {
    const auto k = static_cast<size_t>(grid.cellIndex(a, b));
    cover.area[k] += area;
    if (cover.chart[k] >= 0 && cover.chart[k] != chart) cover.severalCharts[k] = 1;
    if (cover.chart[k] < 0 || chart < cover.chart[k]) cover.chart[k] = chart;
  }
  TexelGrid classify() {
    classifyLattice(grid, cover);
    return grid;
  }
  static TexelGrid makeGrid(int nx, int ny) {
    TexelGrid g;
    g.imageWidth = g.nx = nx;
    g.imageHeight = g.ny = ny;
    return g;
  }
};

TexelClass classAt(const TexelGrid& g, int x, int y) {
  return g.texelClass[static_cast<size_t>(g.texelIndex(x, y))];
}

CellCoverage coverageAt(const TexelGrid& g, int a, int b) {
  return g.cellCoverage[static_cast<size_t>(g.cellIndex(a, b))];
}

TEST(TexelClasses, CellCoverageFollowsCoveredArea) {
  Lattice l(4, 2);
  l.add(0, 0, 0, 1.0);
  l.add(1, 0, 0, 1.0 - 1e-6);  // a visible gap: not the whole cell
  l.add(2, 0, 0, 0.25);
  l.add(2, 0, 0, 0.75);  // two faces of one chart fill it
  l.add(3, 0, 0, 1.5);   // stacked UVs
  const TexelGrid g = l.classify();
  EXPECT_EQ(coverageAt(g, 0, 0), CellCoverage::Full);
  EXPECT_EQ(coverageAt(g, 1, 0), CellCoverage::Partial);
  EXPECT_EQ(coverageAt(g, 2, 0), CellCoverage::Full);
  EXPECT_EQ(coverageAt(g, 3, 0), CellCoverage::Partial);
  EXPECT_EQ(coverageAt(g, 0, 1), CellCoverage::Empty);
  EXPECT_EQ(g.overlapCells, std::vector<int32_t>{g.cellIndex(3, 0)});
}

TEST(TexelClasses, InteriorNeedsFourFullCellsOfOneChart) {
  // Cells [0, 3) x [0, 3) Full in chart 0 except cell (2, 2), which is Partial.
  Lattice l(5, 5);
  for (int b = 0; b < 3; ++b)
    for (int a = 0; a < 3; ++a) l.add(a, b, 0, a == 2 && b == 2 ? 0.5 : 1.0);
  const TexelGrid g = l.classify();
  EXPECT_EQ(classAt(g, 1, 1), TexelClass::Interior);
  EXPECT_EQ(classAt(g, 2, 1), TexelClass::Interior);
  EXPECT_EQ(classAt(g, 2, 2), TexelClass::Boundary);  // meets the Partial cell
  EXPECT_EQ(classAt(g, 0, 0), TexelClass::Boundary);  // one covered footprint cell
  EXPECT_EQ(classAt(g, 3, 3), TexelClass::Boundary);
  EXPECT_EQ(classAt(g, 4, 4), TexelClass::Inactive);
  EXPECT_EQ(classAt(g, 4, 0), TexelClass::Inactive);
  EXPECT_EQ(g.chartOfTexel(static_cast<size_t>(g.texelIndex(4, 4))), -1);
  EXPECT_TRUE(g.multiChartTexels.empty());
}

TEST(TexelClasses, TexelsWhereChartsMeetAreBoundaryOwnedByTheSmallestChart) {
  // Full cells: chart 3 left of a = 2, chart 1 from a = 2 on; cell (4, 2), beside chart 1 only,
  // is shared by charts 1 and 2.
  Lattice l(5, 3);
  for (int b = 0; b < 2; ++b)
    for (int a = 0; a < 4; ++a) l.add(a, b, a < 2 ? 3 : 1, 1.0);
  l.add(4, 2, 2, 0.5);
  l.add(4, 2, 1, 0.5);
  const TexelGrid g = l.classify();
  EXPECT_EQ(coverageAt(g, 4, 2), CellCoverage::Partial);  // shared: never Full
  EXPECT_EQ(classAt(g, 1, 1), TexelClass::Interior);
  EXPECT_EQ(classAt(g, 2, 1), TexelClass::Boundary);
  EXPECT_EQ(g.chartOfTexel(static_cast<size_t>(g.texelIndex(2, 1))), 1);
  EXPECT_EQ(g.chartOfTexel(static_cast<size_t>(g.texelIndex(1, 1))), 3);
  EXPECT_EQ(g.chartOfTexel(static_cast<size_t>(g.texelIndex(4, 2))), 1);
  EXPECT_EQ(g.chartOfTexel(static_cast<size_t>(g.texelIndex(0, 2))), 3);  // one covered cell
  // Charts 3 and 1 meet along x = 2; texel (4, 2) meets chart 2 only inside the shared cell.
  const std::vector<int32_t> expected = {g.texelIndex(2, 0), g.texelIndex(2, 1), g.texelIndex(2, 2),
                                         g.texelIndex(4, 2)};
  EXPECT_EQ(g.multiChartTexels, expected);
}

TEST(TexelClasses, ActiveTexelsAreNumberedInRowMajorOrder) {
  Lattice l(6, 4);
  l.add(3, 2, 0, 1.0);
  l.add(0, 0, 1, 0.3);
  const TexelGrid g = l.classify();
  const std::vector<int32_t> expected = {g.texelIndex(0, 0), g.texelIndex(1, 0), g.texelIndex(0, 1),
                                         g.texelIndex(1, 1), g.texelIndex(3, 2), g.texelIndex(4, 2),
                                         g.texelIndex(3, 3), g.texelIndex(4, 3)};
  EXPECT_EQ(g.texelOfUnknown, expected);
  for (size_t t = 0; t < g.unknownOfTexel.size(); ++t) {
    const int32_t u = g.unknownOfTexel[t];
    EXPECT_EQ(u >= 0, g.texelClass[t] != TexelClass::Inactive);
    if (u >= 0) {
      EXPECT_EQ(g.texelOfUnknown[static_cast<size_t>(u)], static_cast<int32_t>(t));
    }
  }
}

TEST(TexelClasses, ReclassifyingAGridReplacesItsLists) {
  Lattice l(3, 3);
  l.add(0, 0, 0, 2.0);
  l.add(1, 1, 0, 0.5);
  l.add(1, 1, 1, 0.5);
  const TexelGrid once = l.classify();
  const TexelGrid twice = l.classify();
  EXPECT_EQ(twice.texelOfUnknown, once.texelOfUnknown);
  EXPECT_EQ(twice.chartOfUnknown, once.chartOfUnknown);
  EXPECT_EQ(twice.unknownOfTexel, once.unknownOfTexel);
  EXPECT_EQ(twice.overlapCells, once.overlapCells);
  EXPECT_EQ(twice.multiChartTexels, once.multiChartTexels);
  EXPECT_EQ(once.overlapCells.size(), 1u);
}

TEST(TexelClasses, CoverOfTheWrongSizeIsRejected) {
  TexelGrid g = Lattice::makeGrid(4, 4);
  EXPECT_THROW(classifyLattice(g, CellCover(g.cellCount() - 1)), InvalidInputError);
}

}  // namespace
}  // namespace texgrad
