// buildTexelGrid against texel counts worked out by hand, lattice-aligned vertices, gutters,
// and structural invariants on procedural and shared meshes.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "shared_meshes.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/atlas_report.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

/// Appends an axis-aligned UV rectangle [u0,u1]x[v0,v1] as its own chart (flat, z = chart id).
void addRectangle(TexturedMesh& m, double u0, double v0, double u1, double v1) {
  const auto base = static_cast<int32_t>(m.positions.size());
  const double z = static_cast<double>(m.positions.size());
  for (const auto& [u, v] : {std::pair{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}}) {
    m.positions.emplace_back(u, v, z);
    m.uvs.emplace_back(u, v);
  }
  m.triangles.push_back({base, base + 1, base + 2});
  m.triangles.push_back({base, base + 2, base + 3});
  m.uvTriangles.push_back(m.triangles[m.triangles.size() - 2]);
  m.uvTriangles.push_back(m.triangles.back());
}

struct Counts {
  int active = 0, interior = 0, boundary = 0;
};

Counts countTexels(const TexelGrid& g) {
  Counts c;
  for (TexelClass k : g.texelClass) {
    c.active += k != TexelClass::Inactive;
    c.interior += k == TexelClass::Interior;
    c.boundary += k == TexelClass::Boundary;
  }
  return c;
}

TEST(TexelGrid, RectangleBetweenTexelCentresCountsByHand) {
  // UV [0.25, 0.75]^2 at 16x16: grid coordinates 3.5 .. 11.5. Cells 3..11 are met (3 and 11
  // half), so texels 3..12 are active (10 per axis) and texels 5..10 have four full cells.
  TexturedMesh m;
  addRectangle(m, 0.25, 0.25, 0.75, 0.75);
  const TexelGrid g = buildTexelGrid(m, buildAtlas(m), 16, 16);
  const Counts c = countTexels(g);
  EXPECT_EQ(c.active, 100);
  EXPECT_EQ(c.interior, 36);
  EXPECT_EQ(c.boundary, 64);
  EXPECT_EQ(g.unknownCount(), 100);
  EXPECT_TRUE(g.multiChartTexels.empty());
}

TEST(TexelGrid, VerticesExactlyOnTexelCentresNeedNoJitter) {
  // UV (2.5/16 .. 10.5/16): grid coordinates 2 .. 10 exactly; cells 2..9 are full, texels 2..10
  // active (9 per axis), texels 3..9 interior (7 per axis).
  TexturedMesh m;
  addRectangle(m, 2.5 / 16, 2.5 / 16, 10.5 / 16, 10.5 / 16);
  const TexelGrid g = buildTexelGrid(m, buildAtlas(m), 16, 16);
  const Counts c = countTexels(g);
  EXPECT_EQ(c.active, 81);
  EXPECT_EQ(c.interior, 49);
  for (int b = 2; b <= 9; ++b)
    for (int a = 2; a <= 9; ++a)
      EXPECT_EQ(g.cellCoverage[g.cellIndex(a - g.x0, b - g.y0)], CellCoverage::Full);
}

TEST(TexelGrid, UnknownNumberingIsABijectionInRowMajorOrder) {
  const TexturedMesh m = procedural::cubeSphere(6);
  const TexelGrid g = buildTexelGrid(m, buildAtlas(m), 64, 64);
  int previous = -1;
  for (int u = 0; u < g.unknownCount(); ++u) {
    const int t = g.texelOfUnknown[u];
    EXPECT_GT(t, previous);
    previous = t;
    EXPECT_EQ(g.unknownOfTexel[t], u);
    EXPECT_NE(g.texelClass[t], TexelClass::Inactive);
    EXPECT_GE(g.chartOfUnknown[static_cast<size_t>(u)], 0);
    EXPECT_EQ(g.chartOfTexel(static_cast<size_t>(t)), g.chartOfUnknown[static_cast<size_t>(u)]);
  }
}

TEST(TexelGrid, GutterIsMeasuredInTexelsAndTouchingChartsShareTexels) {
  // Two lattice-aligned squares at 32x32: cells 2..9 and 14..19 -> 4 texels apart.
  TexturedMesh apart;
  addRectangle(apart, 2.5 / 32, 2.5 / 32, 10.5 / 32, 10.5 / 32);
  addRectangle(apart, 14.5 / 32, 2.5 / 32, 20.5 / 32, 10.5 / 32);
  const Atlas atlasApart = buildAtlas(apart);
  const TexelGrid g = buildTexelGrid(apart, atlasApart, 32, 32);
  const AtlasReport report = analyzeAtlas(apart, atlasApart, &g);
  ASSERT_TRUE(report.texels && report.texels->minGutterTexels);
  EXPECT_EQ(*report.texels->minGutterTexels, 4.0);
  EXPECT_EQ(report.texels->multiChartTexels, 0);

  // Charts in neighbouring cells: the texel between them meets both.
  TexturedMesh touching;
  addRectangle(touching, 2.5 / 32, 2.5 / 32, 10.5 / 32, 10.5 / 32);
  addRectangle(touching, 10.5 / 32, 2.5 / 32, 14.5 / 32, 10.5 / 32);
  const Atlas atlasTouching = buildAtlas(touching);
  const TexelGrid t = buildTexelGrid(touching, atlasTouching, 32, 32);
  EXPECT_EQ(t.multiChartTexels.size(), 9u);  // column x = 10, rows 2..10
  const AtlasReport r2 = analyzeAtlas(touching, atlasTouching, &t);
  EXPECT_EQ(*r2.texels->minGutterTexels, 0.0);
}

TEST(TexelGrid, UvsOutsideTheImageExtendTheGrid) {
  TexturedMesh m;
  addRectangle(m, -0.1, 0.2, 0.5, 0.6);
  const TexelGrid g = buildTexelGrid(m, buildAtlas(m), 20, 20);
  EXPECT_LT(g.x0, 0);
  const AtlasReport report = analyzeAtlas(m, buildAtlas(m), &g);
  EXPECT_GT(report.texels->texelsOutsideImage, 0);
  EXPECT_EQ(report.texels->chartsTouchingBorder, std::vector<int32_t>{0});
}

TEST(TexelGrid, TilingUvsAndOversizedTexturesAreRefusedWithTheirOwnReason) {
  // Refused before any per-cell array is allocated, so these cost nothing. UVs over 3 x 3
  // texture widths of an 8192² texture: more than 2^28 cells and 4 times the image's, tiling.
  TexturedMesh tiled;
  addRectangle(tiled, -1.0, -1.0, 2.0, 2.0);
  try {
    buildTexelGrid(tiled, buildAtlas(tiled), 8192, 8192);
    ADD_FAILURE() << "tiling UVs were accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("span 3 x 3 texture widths"), std::string::npos)
        << e.what();
  }
  // An atlas inside [0, 1]^2 on a texture above 32768²: too large, not tiling (a 16384²
  // texture, 2^28 cells, was refused as tiling before; bench/memory.py runs it).
  TexturedMesh unit;
  addRectangle(unit, 0.0, 0.0, 1.0, 1.0);
  try {
    buildTexelGrid(unit, buildAtlas(unit), 40000, 40000);
    ADD_FAILURE() << "a 40000x40000 grid was accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("40000x40000 texture is larger than texgrad supports"),
              std::string::npos)
        << e.what();
  }
}

TEST(TexelGrid, StackedChartsAreReportedAsOverlap) {
  TexturedMesh m;
  addRectangle(m, 0.2, 0.2, 0.6, 0.6);
  addRectangle(m, 0.4, 0.4, 0.8, 0.8);
  const Atlas atlas = buildAtlas(m);
  const TexelGrid g = buildTexelGrid(m, atlas, 32, 32);
  EXPECT_FALSE(g.overlapCells.empty());
  EXPECT_FALSE(g.multiChartTexels.empty());
}

TEST(TexelGrid, InteriorTexelsHaveFourFullCellsOfTheirChart) {
  const TexturedMesh m = procedural::cube(4);
  const TexelGrid g = buildTexelGrid(m, buildAtlas(m), 96, 64);
  int interior = 0;
  for (int y = 0; y < g.ny; ++y)
    for (int x = 0; x < g.nx; ++x) {
      if (g.texelClass[g.texelIndex(x, y)] != TexelClass::Interior) continue;
      ++interior;
      for (int b = y - 1; b <= y; ++b)
        for (int a = x - 1; a <= x; ++a) {
          ASSERT_EQ(g.cellCoverage[g.cellIndex(a, b)], CellCoverage::Full);
          ASSERT_EQ(g.cellChart[g.cellIndex(a, b)], g.chartOfTexel(static_cast<size_t>(g.texelIndex(x, y))));
        }
    }
  EXPECT_GT(interior, 0);
}

TEST(TexelGrid, CoveredAreaMatchesChartUvArea) {
  const TexturedMesh m = procedural::cubeSphere(8);
  const Atlas atlas = buildAtlas(m);
  const int w = 128, h = 128;
  const TexelGrid g = buildTexelGrid(m, atlas, w, h);
  double uvArea = 0.0;
  for (const Chart& c : atlas.charts) uvArea += c.uvArea;
  int full = 0, partial = 0;
  for (CellCoverage c : g.cellCoverage) {
    full += c == CellCoverage::Full;
    partial += c == CellCoverage::Partial;
  }
  // Full cells lie inside the charts; full + partial cells cover them.
  EXPECT_LE(full, uvArea * w * h + 1e-6);
  EXPECT_GE(full + partial, uvArea * w * h - 1e-6);
}

class SharedGrid : public ::testing::TestWithParam<test::SharedMesh> {};

TEST_P(SharedGrid, EveryUvTriangleCornerTexelIsActive) {
  const test::SharedMesh& s = GetParam();
  const TexturedMesh m = readMesh(test::sharedData() / s.obj);
  const Atlas atlas = buildAtlas(m);
  const TexelGrid g = buildTexelGrid(m, atlas, 256, 256);
  EXPECT_GT(g.unknownCount(), 0);
  // The nearest texel of a point inside a positive-area triangle has that point in its footprint.
  for (size_t f = 0; f < m.faceCount(); ++f) {
    const Eigen::Vector2d c = (m.uvs[m.uvTriangles[f][0]] + m.uvs[m.uvTriangles[f][1]] +
                               m.uvs[m.uvTriangles[f][2]]) / 3.0;
    const Eigen::Vector2d p = g.toGrid(c);
    const int x = static_cast<int>(std::lround(p.x())), y = static_cast<int>(std::lround(p.y()));
    const Eigen::Vector2d e1 = m.uvs[m.uvTriangles[f][1]] - m.uvs[m.uvTriangles[f][0]];
    const Eigen::Vector2d e2 = m.uvs[m.uvTriangles[f][2]] - m.uvs[m.uvTriangles[f][0]];
    if (e1.x() * e2.y() - e1.y() * e2.x() == 0.0) continue;
    ASSERT_NE(g.texelClass[g.texelIndex(x, y)], TexelClass::Inactive) << s.name << " face " << f;
  }
}

INSTANTIATE_TEST_SUITE_P(AllMeshes, SharedGrid, ::testing::ValuesIn(test::sharedMeshes()),
                         test::sharedMeshName);

}  // namespace
}  // namespace texgrad

namespace texgrad {
namespace {

/// Independent oracle for a convex UV polygon (grid coordinates): a texel is active iff its
/// footprint [x-1, x+1] x [y-1, y+1] overlaps the polygon with positive area (separating axes),
/// interior iff the footprint lies inside it.
struct ConvexOracle {
  std::vector<Eigen::Vector2d> poly;  // counter-clockwise

  static std::pair<double, double> project(const std::vector<Eigen::Vector2d>& pts,
                                           const Eigen::Vector2d& axis) {
    double lo = 1e300, hi = -1e300;
    for (const auto& p : pts) lo = std::min(lo, p.dot(axis)), hi = std::max(hi, p.dot(axis));
    return {lo, hi};
  }
  bool overlaps(const std::vector<Eigen::Vector2d>& box) const {
    std::vector<Eigen::Vector2d> axes{{1, 0}, {0, 1}};
    for (size_t k = 0; k < poly.size(); ++k) {
      const Eigen::Vector2d e = poly[(k + 1) % poly.size()] - poly[k];
      axes.emplace_back(-e.y(), e.x());
    }
    for (const auto& a : axes) {
      const auto [p0, p1] = project(poly, a);
      const auto [b0, b1] = project(box, a);
      if (std::min(p1, b1) - std::max(p0, b0) <= 1e-12 * a.norm()) return false;
    }
    return true;
  }
  bool contains(const Eigen::Vector2d& q) const {
    for (size_t k = 0; k < poly.size(); ++k) {
      const Eigen::Vector2d e = poly[(k + 1) % poly.size()] - poly[k], d = q - poly[k];
      if (e.x() * d.y() - e.y() * d.x() < -1e-12) return false;
    }
    return true;
  }
};

TEST(TexelGrid, SquareRotatedThirtyDegreesMatchesTheOracle) {
  const double c = std::cos(std::numbers::pi / 6), s = std::sin(std::numbers::pi / 6);
  const Eigen::Vector2d centre(0.5, 0.5);
  std::vector<Eigen::Vector2d> uv;
  for (const auto& [x, y] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}})
    uv.push_back(centre + 0.25 * Eigen::Vector2d(c * x - s * y, s * x + c * y));
  TexturedMesh m;
  for (const auto& p : uv) {
    m.positions.emplace_back(p.x(), p.y(), 0.0);
    m.uvs.push_back(p);
  }
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.uvTriangles = m.triangles;
  const int n = 64;
  const TexelGrid g = buildTexelGrid(m, buildAtlas(m), n, n);
  ConvexOracle oracle;
  for (const auto& p : uv) oracle.poly.push_back(p * n - Eigen::Vector2d(0.5, 0.5));
  int active = 0, interior = 0, checked = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d q(i, j);
      const std::vector<Eigen::Vector2d> box{q + Eigen::Vector2d(-1, -1), q + Eigen::Vector2d(1, -1),
                                             q + Eigen::Vector2d(1, 1), q + Eigen::Vector2d(-1, 1)};
      const bool isActive = oracle.overlaps(box);
      bool isInterior = isActive;
      for (const auto& corner : box) isInterior &= oracle.contains(corner);
      active += isActive;
      interior += isInterior;
      const int x = i - g.x0, y = j - g.y0;
      const bool inGrid = x >= 0 && y >= 0 && x < g.nx && y < g.ny;
      const TexelClass k = inGrid ? g.texelClass[g.texelIndex(x, y)] : TexelClass::Inactive;
      ASSERT_EQ(k != TexelClass::Inactive, isActive) << i << "," << j;
      ASSERT_EQ(k == TexelClass::Interior, isInterior) << i << "," << j;
      ++checked;
    }
  EXPECT_EQ(g.unknownCount(), active);
  EXPECT_GT(interior, 0);
}

TEST(TexelGrid, TwoChartSquareCountsMatchEachChartAlone) {
  // Charts far apart in UV: each texel belongs to exactly one chart, and the counts are the sums
  // of the counts of each chart's triangles taken on their own.
  const TexturedMesh both = procedural::twoChartSquare(4);
  const Atlas atlas = buildAtlas(both);
  ASSERT_EQ(atlas.charts.size(), 2u);
  const TexelGrid g = buildTexelGrid(both, atlas, 128, 128);
  int sum = 0, interiorSum = 0;
  for (const Chart& chart : atlas.charts) {
    TexturedMesh one = both;
    one.triangles.clear();
    one.uvTriangles.clear();
    for (int32_t f : chart.faces) {
      one.triangles.push_back(both.triangles[f]);
      one.uvTriangles.push_back(both.uvTriangles[f]);
    }
    const TexelGrid alone = buildTexelGrid(one, buildAtlas(one), 128, 128);
    sum += alone.unknownCount();
    for (TexelClass k : alone.texelClass) interiorSum += k == TexelClass::Interior;
  }
  int interior = 0;
  for (TexelClass k : g.texelClass) interior += k == TexelClass::Interior;
  EXPECT_EQ(g.unknownCount(), sum);
  EXPECT_EQ(interior, interiorSum);
  EXPECT_TRUE(g.multiChartTexels.empty());
}

}  // namespace
}  // namespace texgrad
