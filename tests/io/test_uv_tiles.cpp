// cutAtTileBorders / wrapIntoUnitSquare: every face ends in one unit tile, areas and orientation
// are kept, the cut is watertight (also across seams no line crosses), and tiles move as the
// sampler reads them.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <map>
#include <set>

#include "texgrad/core/error.h"
#include "texgrad/io/procedural.h"
#include "texgrad/io/uv_tiles.h"

namespace texgrad {
namespace {

double uvArea(const TexturedMesh& m, size_t f) {  // signed
  const Triangle& t = m.uvTriangles[f];
  const Eigen::Vector2d a = m.uvs[t[1]] - m.uvs[t[0]], b = m.uvs[t[2]] - m.uvs[t[0]];
  return 0.5 * (a.x() * b.y() - a.y() * b.x());
}

Eigen::Vector3d areaVector(const TexturedMesh& m, size_t f) {
  const Triangle& t = m.triangles[f];
  return 0.5 * (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
}

/// Total length of the 3-D edges only one face uses: the surface's boundary. A crack (an edge
/// split on one side only) adds both of its sides.
double boundaryLength(const TexturedMesh& m) {
  std::map<std::pair<int32_t, int32_t>, int> uses;
  for (const Triangle& t : m.triangles)
    for (int e = 0; e < 3; ++e) ++uses[std::minmax(t[e], t[(e + 1) % 3])];
  double length = 0.0;
  for (const auto& [edge, count] : uses)
    if (count == 1) length += (m.positions[edge.first] - m.positions[edge.second]).norm();
  return length;
}

/// True if every corner of face f lies in its tile (within the tolerance).
bool inTile(const TexturedMesh& m, size_t f, UvTile tile) {
  for (int32_t i : m.uvTriangles[f]) {
    const Eigen::Vector2d& uv = m.uvs[i];
    if (uv.x() < tile.k - kTileBorderTolerance || uv.x() > tile.k + 1 + kTileBorderTolerance ||
        uv.y() < tile.l - kTileBorderTolerance || uv.y() > tile.l + 1 + kTileBorderTolerance)
      return false;
  }
  return true;
}

/// The checks every cut must pass against its input: tiles, UV and 3-D area per parent face,
/// orientation, and the 3-D boundary unchanged (watertight).
void expectValidCut(const TexturedMesh& input, const TileCut& cut) {
  const TexturedMesh& m = cut.mesh;
  ASSERT_EQ(cut.faceTile.size(), m.faceCount());
  ASSERT_EQ(cut.parentFace.size(), m.faceCount());
  std::vector<double> uvSum(input.faceCount(), 0.0);
  std::vector<Eigen::Vector3d> areaSum(input.faceCount(), Eigen::Vector3d::Zero());
  for (size_t f = 0; f < m.faceCount(); ++f) {
    EXPECT_TRUE(inTile(m, f, cut.faceTile[f])) << "face " << f;
    const auto parent = static_cast<size_t>(cut.parentFace[f]);
    const double a = uvArea(m, f), parentArea = uvArea(input, parent);
    EXPECT_GE(a * parentArea, 0.0) << "face " << f << " flipped";
    uvSum[parent] += a;
    areaSum[parent] += areaVector(m, f);
  }
  for (size_t f = 0; f < input.faceCount(); ++f) {
    EXPECT_NEAR(uvSum[f], uvArea(input, f), 1e-12) << "face " << f;
    EXPECT_LT((areaSum[f] - areaVector(input, f)).norm(), 1e-12) << "face " << f;
  }
  EXPECT_NEAR(boundaryLength(m), boundaryLength(input), 1e-12);
}

/// The tiles whose faces use 3-D position p.
std::set<std::pair<int, int>> tilesUsing(const TileCut& cut, int32_t p) {
  std::set<std::pair<int, int>> tiles;
  for (size_t f = 0; f < cut.mesh.faceCount(); ++f)
    for (int32_t q : cut.mesh.triangles[f])
      if (q == p) tiles.insert({cut.faceTile[f].k, cut.faceTile[f].l});
  return tiles;
}

TEST(UvTiles, AMeshInsideOneTileIsNotTouched) {
  const TexturedMesh cube = procedural::cube(3);
  const TileCut cut = cutAtTileBorders(cube);
  EXPECT_FALSE(cut.cut);
  EXPECT_EQ(cut.mesh.uvs, cube.uvs);
  EXPECT_EQ(cut.mesh.uvTriangles, cube.uvTriangles);
  EXPECT_EQ(cut.mesh.positions, cube.positions);
  for (size_t f = 0; f < cube.faceCount(); ++f) {
    EXPECT_EQ(cut.parentFace[f], static_cast<int32_t>(f));
    EXPECT_EQ(cut.faceTile[f], (UvTile{0, 0}));
  }
}

TEST(UvTiles, AFaceTouchingALineIsInTheTileOnItsSide) {
  // u in [0.5, 1] (touching u = 1 from the left), [1, 1.5], and [0.5, 1 + 1e-9] (within the
  // tolerance: not cut into a 1e-9 sliver).
  for (const auto& [u0, su, k] :
       {std::tuple{0.5, 0.5, 0}, std::tuple{1.0, 0.5, 1}, std::tuple{0.5, 0.5 + 1e-9, 0}}) {
    const TileCut cut = cutAtTileBorders(procedural::square(su, 1.0, u0, 0.0));
    EXPECT_FALSE(cut.cut) << u0 << " " << su;
    ASSERT_EQ(cut.mesh.faceCount(), 2u);
    for (const UvTile& tile : cut.faceTile) EXPECT_EQ(tile, (UvTile{k, 0})) << u0 << " " << su;
  }
}

TEST(UvTiles, ALineWithinTheToleranceOfACornerCutsThroughIt) {
  // u = 1 passes 1e-9 from corner 1 and crosses edge 0-2: one new point and two triangles, no
  // sliver between the corner and a point 1e-9 from it.
  TexturedMesh m;
  m.positions = {{0, 0, 0}, {1, 2, 0}, {2, 0, 0}};
  m.uvs = {{0.5, 0.2}, {1.0 + 1e-9, 0.8}, {1.5, 0.2}};
  m.triangles = {{0, 2, 1}};
  m.uvTriangles = {{0, 2, 1}};
  const TileCut cut = cutAtTileBorders(m);
  expectValidCut(m, cut);
  EXPECT_EQ(cut.mesh.positions.size(), 4u);
  EXPECT_EQ(cut.mesh.faceCount(), 2u);
}

TEST(UvTiles, AStraddlingSquareIsCutWatertightIntoTwoTiles) {
  TexturedMesh square = procedural::square(0.5, 1.0, 0.75, 0.0);  // u in [0.75, 1.25]
  square.faceMaterial = {3, 7};
  TextureRef everyFace, material7;
  everyFace.faces = 2;
  material7.faces = 1;
  material7.materials = {7};
  square.textures = {everyFace, material7};
  const TileCut cut = cutAtTileBorders(square);
  EXPECT_TRUE(cut.cut);
  expectValidCut(square, cut);
  const auto faces7 = std::count(cut.mesh.faceMaterial.begin(), cut.mesh.faceMaterial.end(), 7);
  EXPECT_EQ(cut.mesh.textures[0].faces, cut.mesh.faceCount());  // the faces each texture covers
  EXPECT_EQ(cut.mesh.textures[1].faces, static_cast<size_t>(faces7));
  EXPECT_GT(faces7, 1);
  double tileArea[2] = {0.0, 0.0};
  for (size_t f = 0; f < cut.mesh.faceCount(); ++f) {
    ASSERT_TRUE(cut.faceTile[f].k == 0 || cut.faceTile[f].k == 1);
    tileArea[cut.faceTile[f].k] += uvArea(cut.mesh, f);
    EXPECT_EQ(cut.mesh.faceMaterial[f], square.faceMaterial[cut.parentFace[f]]);
  }
  EXPECT_NEAR(std::abs(tileArea[0]), 0.25, 1e-12);
  EXPECT_NEAR(std::abs(tileArea[1]), 0.25, 1e-12);
  // Each new 3-D point (bottom edge, diagonal, top edge) is used on both sides, with one UV per
  // side at the same numeric value on u = 1.
  ASSERT_EQ(cut.mesh.positions.size(), square.positions.size() + 3);
  for (size_t p = square.positions.size(); p < cut.mesh.positions.size(); ++p) {
    EXPECT_EQ(tilesUsing(cut, static_cast<int32_t>(p)).size(), 2u) << p;
    EXPECT_NEAR(cut.mesh.positions[p].x(), 0.5, 1e-15);
    std::set<int32_t> uvIndices;
    for (size_t f = 0; f < cut.mesh.faceCount(); ++f)
      for (int c = 0; c < 3; ++c)
        if (cut.mesh.triangles[f][c] == static_cast<int32_t>(p)) {
          uvIndices.insert(cut.mesh.uvTriangles[f][c]);
          EXPECT_EQ(cut.mesh.uvs[cut.mesh.uvTriangles[f][c]].x(), 1.0);
        }
    EXPECT_EQ(uvIndices.size(), 2u) << p;
  }
}

TEST(UvTiles, ATileCornerInsideAFaceIsOnePointOfFourTiles) {
  TexturedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.uvs = {{0.6, 0.6}, {1.6, 0.6}, {0.6, 1.6}};  // (1, 1) lies inside: u + v = 2 < 2.2
  m.triangles = {{0, 1, 2}};
  m.uvTriangles = {{0, 1, 2}};
  const TileCut cut = cutAtTileBorders(m);
  expectValidCut(m, cut);
  int32_t corner = -1;
  for (size_t f = 0; f < cut.mesh.faceCount(); ++f)
    for (int c = 0; c < 3; ++c)
      if (cut.mesh.uvs[cut.mesh.uvTriangles[f][c]] == Eigen::Vector2d(1.0, 1.0))
        corner = cut.mesh.triangles[f][c];
  ASSERT_GE(corner, 0);
  EXPECT_EQ(tilesUsing(cut, corner).size(), 4u) << cut.mesh.positions.size();
  EXPECT_LT((cut.mesh.positions[corner] - Eigen::Vector3d(0.4, 0.4, 0)).norm(), 1e-15);
}

TEST(UvTiles, ASeamEdgeCutOnOneSideIsSplitOnTheOtherToo) {
  // Two charts joined by a seam; one chart moved so that v = 1 crosses its seam edges, the
  // other left whole inside tile (0, 0): the other chart's seam edges get the cut points too.
  TexturedMesh m = procedural::twoChartSquare(4);
  std::set<int32_t> left;
  for (size_t f = 0; f < m.faceCount(); ++f) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int32_t p : m.triangles[f]) centre += m.positions[p] / 3.0;
    if (centre.x() < 0.5) left.insert(m.uvTriangles[f].begin(), m.uvTriangles[f].end());
  }
  for (int32_t i : left) m.uvs[i].y() += 0.5 + 1.0 / 7.0;  // rows off the lattice of the cut
  const TileCut cut = cutAtTileBorders(m);
  EXPECT_TRUE(cut.cut);
  expectValidCut(m, cut);  // the boundary length would grow by each cracked seam edge
  std::set<std::pair<int, int>> tiles;
  for (const UvTile& t : cut.faceTile) tiles.insert({t.k, t.l});
  EXPECT_EQ(tiles, (std::set<std::pair<int, int>>{{0, 0}, {0, 1}}));
}

TEST(UvTiles, BothSidesOfASeamCutAtOnePointShareIt) {
  // Both charts moved alike: v = 1 crosses the seam edge at the same point on both sides, which
  // is one new 3-D point (not two coincident ones with a zero-area sliver between them). The
  // line crosses 5 vertical edges (the seam once) and 4 diagonals of the 4 x 4 cells.
  TexturedMesh m = procedural::twoChartSquare(4);
  for (Eigen::Vector2d& uv : m.uvs) uv.y() += 0.5 + 1.0 / 7.0;
  const TileCut cut = cutAtTileBorders(m);
  expectValidCut(m, cut);
  EXPECT_EQ(cut.mesh.positions.size(), m.positions.size() + 9);
  for (size_t p = m.positions.size(); p < cut.mesh.positions.size(); ++p)
    EXPECT_EQ(tilesUsing(cut, static_cast<int32_t>(p)).size(), 2u) << p;
}

TEST(UvTiles, RepeatShiftsMirrorFlipsClampKeeps) {
  const TexturedMesh square = procedural::square(1.0, 1.0, 1.0, -3.0);  // tile (1, -3)
  for (const auto& [u, v, expectU, expectV] :
       {std::tuple{TextureWrap::Repeat, TextureWrap::Repeat, 0.25, 0.5},
        std::tuple{TextureWrap::MirroredRepeat, TextureWrap::MirroredRepeat, 0.75, 0.5},
        std::tuple{TextureWrap::ClampToEdge, TextureWrap::MirroredRepeat, 1.25, 0.5}}) {
    const WrappedMesh w = wrapTextureCoordinates(square, {u, v});
    ASSERT_EQ(w.mesh.faceCount(), 2u);
    // The corner at 3-D (0.25, 0.5) had UV (1.25, -2.5).
    const Eigen::Vector2d uv = wrapUvPoint({1.25, -2.5}, {u, v});
    EXPECT_NEAR(uv.x(), expectU, 1e-15);
    EXPECT_NEAR(uv.y(), expectV, 1e-15);
    const bool mirrored = (u == TextureWrap::MirroredRepeat) != (v == TextureWrap::MirroredRepeat);
    for (size_t f = 0; f < 2; ++f) {
      EXPECT_EQ(uvArea(w.mesh, f) < 0.0, mirrored) << f;
      for (int32_t i : w.mesh.uvTriangles[f]) {
        EXPECT_GE(w.mesh.uvs[i].y(), 0.0);
        EXPECT_LE(w.mesh.uvs[i].y(), 1.0);
        if (u != TextureWrap::ClampToEdge) {
          EXPECT_GE(w.mesh.uvs[i].x(), 0.0);
        }
      }
    }
  }
}

TEST(UvTiles, WrappingDuplicatesUvsSharedAcrossTiles) {
  // Two faces sharing the UV edge u = 1: left in tile 0, right in tile 1; Repeat moves only the
  // right one, so the shared UVs are copied and the faces become two charts.
  TexturedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {2, 0, 0}};
  m.uvs = {{0.5, 0.2}, {1.0, 0.2}, {1.0, 0.8}, {1.5, 0.2}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}};
  m.uvTriangles = {{0, 1, 2}, {1, 3, 2}};
  const WrappedMesh w = wrapTextureCoordinates(m, {});
  ASSERT_EQ(w.mesh.faceCount(), 2u);
  EXPECT_EQ(w.mesh.positions.size(), 4u);  // touching, not cut
  EXPECT_EQ(w.mesh.uvs.size(), 6u);
  EXPECT_EQ(w.mesh.uvs[w.mesh.uvTriangles[1][0]], Eigen::Vector2d(0.0, 0.2));
  EXPECT_EQ(w.mesh.uvs[w.mesh.uvTriangles[0][1]], Eigen::Vector2d(1.0, 0.2));
}

TEST(UvTiles, HugeCoordinatesAreRefusedInOneLine) {
  try {
    cutAtTileBorders(procedural::square(1.0, 1.0, 2e6, 0.0));
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("beyond +-1e6 tiles"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(UvTiles, AFaceOverMillionsOfTilesIsRefusedBeforeCutting) {
  // A square repeating its texture 3000 x 3000 times: 9 million pieces are not made.
  try {
    cutAtTileBorders(procedural::square(3000.0, 3000.0));
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("more tiles"), std::string::npos) << e.what();
  }
  // Along an axis that is not cut (ClampToEdge), nothing is counted or refused.
  EXPECT_FALSE(cutAtTileBorders(procedural::square(1.0, 3e6, 0.0, 0.0), true, false).cut);
}

TEST(UvTiles, ParentFacesCarryPerFaceValues) {
  const TileCut cut = cutAtTileBorders(procedural::square(0.5, 1.0, 0.75, 0.0));
  const std::vector<int> values{10, 20};
  const std::vector<int> children = followParentFaces(values, cut.parentFace);
  ASSERT_EQ(children.size(), cut.mesh.faceCount());
  for (size_t f = 0; f < children.size(); ++f) EXPECT_EQ(children[f], values[cut.parentFace[f]]);
  EXPECT_EQ(children[0], 10);  // the first piece keeps its face's index
  EXPECT_EQ(children[1], 20);
  EXPECT_THROW(followParentFaces(std::vector<int>{1}, cut.parentFace), InvalidInputError);
}

}  // namespace
}  // namespace texgrad
