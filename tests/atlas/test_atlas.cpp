// buildAtlas on procedural meshes with known structure and on every shared mesh (INDEX.md counts).
#include <gtest/gtest.h>

#include "shared_meshes.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/atlas_report.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

int32_t vertexAt(const TexturedMesh& m, FaceEdge e, int k) {
  return m.triangles[e.face][(e.corner + k) % 3];
}

/// Every seam pair joins the same 3-D edge, in the direction `sameDirection` says, and its two
/// UV edges differ; seamOfEdge points back at it.
void expectConsistentSeams(const TexturedMesh& m, const Atlas& atlas) {
  for (size_t s = 0; s < atlas.seams.size(); ++s) {
    const SeamPair& p = atlas.seams[s];
    const int32_t a0 = vertexAt(m, p.a, 0), a1 = vertexAt(m, p.a, 1);
    const int32_t b0 = vertexAt(m, p.b, p.sameDirection ? 0 : 1);
    const int32_t b1 = vertexAt(m, p.b, p.sameDirection ? 1 : 0);
    ASSERT_EQ(a0, b0) << "seam " << s;
    ASSERT_EQ(a1, b1) << "seam " << s;
    EXPECT_EQ(atlas.seamOfEdge[3 * p.a.face + p.a.corner], static_cast<int32_t>(s));
    EXPECT_EQ(atlas.seamOfEdge[3 * p.b.face + p.b.corner], static_cast<int32_t>(s));
  }
}

TEST(Atlas, CubeHasSixChartsAndTwelveSeamsPerSubdivision) {
  const int n = 3;
  const TexturedMesh m = procedural::cube(n);
  const Atlas atlas = buildAtlas(m);
  EXPECT_EQ(atlas.charts.size(), 6u);
  EXPECT_EQ(atlas.seams.size(), static_cast<size_t>(12 * n));
  EXPECT_TRUE(atlas.openBoundary.empty());
  EXPECT_TRUE(atlas.nonManifoldEdges.empty());
  for (const SeamPair& s : atlas.seams) EXPECT_FALSE(s.sameDirection);  // consistently oriented
  expectConsistentSeams(m, atlas);
  size_t faces = 0;
  for (const Chart& c : atlas.charts) {
    faces += c.faces.size();
    EXPECT_GT(c.uvArea, 0.0);
  }
  EXPECT_EQ(faces, m.faceCount());
}

TEST(Atlas, CylinderHasOneChartOneSeamAndTwoOpenRims) {
  const int around = 12, along = 5;
  const TexturedMesh m = procedural::cylinder(around, along);
  const Atlas atlas = buildAtlas(m);
  EXPECT_EQ(atlas.charts.size(), 1u);
  EXPECT_EQ(atlas.seams.size(), static_cast<size_t>(along));
  EXPECT_EQ(atlas.openBoundary.size(), static_cast<size_t>(2 * around));
  expectConsistentSeams(m, atlas);
}

TEST(Atlas, TwoChartSquareHasOneSeamOfNEdges) {
  const TexturedMesh m = procedural::twoChartSquare(6);
  const Atlas atlas = buildAtlas(m);
  EXPECT_EQ(atlas.charts.size(), 2u);
  EXPECT_EQ(atlas.seams.size(), 6u);
  expectConsistentSeams(m, atlas);
}

TEST(Atlas, NonManifoldEdgeNeitherJoinsNorSeams) {
  // Three triangles sharing the edge (0, 1), all with coinciding UVs on it.
  TexturedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.uvs = {{0.1, 0.1}, {0.9, 0.1}, {0.1, 0.9}, {0.5, 0.05}, {0.5, 0.5}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  m.uvTriangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const Atlas atlas = buildAtlas(m);
  ASSERT_EQ(atlas.nonManifoldEdges.size(), 1u);
  EXPECT_EQ(atlas.nonManifoldEdges[0].size(), 3u);
  EXPECT_EQ(atlas.charts.size(), 3u);
  EXPECT_TRUE(atlas.seams.empty());
  const AtlasReport report = analyzeAtlas(m, atlas);
  bool found = false;
  for (const AtlasIssue& issue : report.issues) found |= issue.kind == "non-manifold-edges";
  EXPECT_TRUE(found);
}

TEST(Atlas, ReportFindsDegenerateFlippedAndOutsideUvs) {
  TexturedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {1.2, 0.5}, {0.5, 0.5}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}, {1, 4, 2}, {0, 1, 4}};
  m.uvTriangles = {{0, 1, 2}, {0, 2, 3}, {5, 4, 1}, {0, 0, 5}};  // face 2 clockwise, 3 flat
  const Atlas atlas = buildAtlas(m);
  const AtlasReport report = analyzeAtlas(m, atlas);
  auto idsOf = [&](const std::string& kind) {
    for (const AtlasIssue& issue : report.issues)
      if (issue.kind == kind) return issue.ids;
    return std::vector<int64_t>{};
  };
  EXPECT_EQ(idsOf("uvs-outside-unit-square"), std::vector<int64_t>{4});
  EXPECT_EQ(idsOf("degenerate-uv-triangles"), std::vector<int64_t>{3});
  EXPECT_EQ(idsOf("flipped-uv-triangles"), std::vector<int64_t>{2});
}

TEST(Atlas, UvsOfUdimTilesAreOutsideOnlyWhenTheyLeaveTheirTile) {
  // Two triangles in UDIM tiles 1002 (u in [1, 2]) and 1011 (v in [1, 2]); the second reaches
  // 0.1 past its tile's top.
  TexturedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  m.uvs = {{1.2, 0.2}, {1.8, 0.2}, {1.2, 0.8}, {0.2, 1.2}, {0.8, 1.2}, {0.2, 2.1}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  m.uvTriangles = m.triangles;
  PageLayout pages;
  pages.pages.resize(2);
  pages.pages[0].tileU = 1;
  pages.pages[1].tileV = 1;
  pages.facePage = {0, 1};
  auto outside = [&](const PageLayout* layout) {
    for (const AtlasIssue& issue : analyzeAtlas(m, buildAtlas(m), nullptr, layout).issues)
      if (issue.kind == "uvs-outside-unit-square") return issue.ids;
    return std::vector<int64_t>{};
  };
  EXPECT_EQ(outside(&pages), std::vector<int64_t>{5});
  // The same UVs against the unit square: all six are outside.
  EXPECT_EQ(outside(nullptr).size(), 6u);
}

TEST(Atlas, BowTieVertexIsNonManifold) {
  TexturedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  m.uvs = {{0.5, 0.5}, {0.9, 0.5}, {0.5, 0.9}, {0.1, 0.5}, {0.5, 0.1}};
  m.triangles = {{0, 1, 2}, {0, 3, 4}};
  m.uvTriangles = m.triangles;
  const AtlasReport report = analyzeAtlas(m, buildAtlas(m));
  bool found = false;
  for (const AtlasIssue& issue : report.issues)
    if (issue.kind == "non-manifold-vertices") found = issue.ids == std::vector<int64_t>{0};
  EXPECT_TRUE(found);
  EXPECT_EQ(report.connectedComponents, 1);
}

class SharedAtlas : public ::testing::TestWithParam<test::SharedMesh> {};

TEST_P(SharedAtlas, MatchesIndexCounts) {
  const test::SharedMesh& s = GetParam();
  const TexturedMesh m = readMesh(test::sharedData() / s.obj);
  EXPECT_EQ(m.positions.size(), static_cast<size_t>(s.vertices));
  EXPECT_EQ(m.faceCount(), static_cast<size_t>(s.faces));
  const Atlas atlas = buildAtlas(m);
  EXPECT_EQ(atlas.charts.size(), static_cast<size_t>(s.charts));
  EXPECT_EQ(atlas.seams.size(), static_cast<size_t>(s.seamEdges));
  EXPECT_EQ(atlas.openBoundary.size(), static_cast<size_t>(s.boundaryEdges));
  expectConsistentSeams(m, atlas);
}

TEST(SharedAtlasGltf, ObjAndGltfVersionsAgree) {
  for (const char* name : {"BoomBox", "WaterBottle", "Lantern", "Avocado", "Suzanne"}) {
    const std::filesystem::path dir = test::sharedData() / name;
    const TexturedMesh obj = readMesh(dir / "obj" / (std::string(name) + ".obj"));
    const TexturedMesh gltf = readMesh(dir / "glTF" / (std::string(name) + ".gltf"));
    const Atlas a = buildAtlas(obj), b = buildAtlas(gltf);
    EXPECT_EQ(a.charts.size(), b.charts.size()) << name;
    EXPECT_EQ(a.seams.size(), b.seams.size()) << name;
    EXPECT_EQ(a.openBoundary.size(), b.openBoundary.size()) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(AllMeshes, SharedAtlas, ::testing::ValuesIn(test::sharedMeshes()),
                         test::sharedMeshName);

}  // namespace
}  // namespace texgrad
