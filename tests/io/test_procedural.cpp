// Procedural meshes: invariants every later stage relies on (welded positions, counter-clockwise
// UVs inside the unit square, gutters between charts), checked over every mesh, plus areas,
// volumes, seams and the sample texture.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <string_view>

#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

constexpr double kPi = std::numbers::pi;
/// Smallest UV distance the atlas promises between two charts.
constexpr double kMinGutter = 0.02;

struct MeshCase {
  std::string name;
  TexturedMesh mesh;
  size_t faces;
  int charts;
  double area;           ///< analytic 3-D surface area
  double areaTolerance;  ///< relative
  bool closed;           ///< every edge has two faces
  double volume;         ///< analytic enclosed volume (closed meshes)
};

/// Names of the cases of allMeshes(), in order. Test names are made when the tests register, in
/// every process of test_io: taken from here, no mesh is built then
/// (Procedural.EveryCaseHasItsName checks that the two lists agree).
constexpr std::array<std::string_view, 11> kMeshNames = {
    "square",   "mirrored_square", "two_charts", "two_charts_odd", "cube",         "cube1",
    "cylinder", "sphere",          "torus",      "aligned_cube",   "jittered_cube"};

std::vector<MeshCase> allMeshes() {
  const double torusArea = 4 * kPi * kPi * 1.0 * 0.4;
  const double torusVolume = 2 * kPi * kPi * 1.0 * 0.4 * 0.4;
  return {
      {"square", procedural::square(0.8, 0.7, 0.1, 0.2), 2, 1, 1.0, 1e-12, false, 0},
      {"mirrored_square", procedural::square(-0.8, 0.7, 0.9, 0.2), 2, 1, 1.0, 1e-12, false, 0},
      {"two_charts", procedural::twoChartSquare(4), 32, 2, 1.0, 1e-12, false, 0},
      {"two_charts_odd", procedural::twoChartSquare(5), 60, 2, 1.0, 1e-12, false, 0},
      {"cube", procedural::cube(4), 6 * 2 * 16, 6, 6.0, 1e-12, true, 1.0},
      {"cube1", procedural::cube(1), 12, 6, 6.0, 1e-12, true, 1.0},
      {"cylinder", procedural::cylinder(32, 16), 2 * 32 * 16, 1, 1.0, 2e-3, false, 0},
      {"sphere", procedural::cubeSphere(16), 6 * 2 * 256, 6, 4 * kPi, 0.02, true, 4.0 / 3.0 * kPi},
      {"torus", procedural::sampleTorus(), 0, 4, torusArea, 0.02, true, torusVolume},
      {"aligned_cube", procedural::alignedCube(4), 6 * 2 * 16, 6, 6.0, 1e-12, true, 1.0},
      {"jittered_cube", procedural::alignedCube(4, 1e-4), 6 * 2 * 16, 6, 6.0, 1e-12, true, 1.0},
  };
}

double triangleArea3d(const TexturedMesh& m, size_t f) {
  const auto& t = m.triangles[f];
  const Eigen::Vector3d& a = m.positions[size_t(t[0])];
  return 0.5 * (m.positions[size_t(t[1])] - a).cross(m.positions[size_t(t[2])] - a).norm();
}

double signedUvArea(const TexturedMesh& m, size_t f) {
  const auto& t = m.uvTriangles[f];
  const Eigen::Vector2d e1 = m.uvs[size_t(t[1])] - m.uvs[size_t(t[0])];
  const Eigen::Vector2d e2 = m.uvs[size_t(t[2])] - m.uvs[size_t(t[0])];
  return 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
}

/// Charts: faces joined across edges shared in UV index space (docs/architecture.md, Conventions).
std::vector<int> chartOfFace(const TexturedMesh& m) {
  std::vector<int> parent(m.faceCount());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[size_t(x)] != x) x = parent[size_t(x)] = parent[size_t(parent[size_t(x)])];
    return x;
  };
  std::map<std::pair<int, int>, int> faceOfUvEdge;
  for (size_t f = 0; f < m.faceCount(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = m.uvTriangles[f][size_t(c)], b = m.uvTriangles[f][size_t((c + 1) % 3)];
      const auto [it, added] = faceOfUvEdge.try_emplace({std::min(a, b), std::max(a, b)}, int(f));
      if (!added) parent[size_t(find(int(f)))] = find(it->second);
    }
  std::map<int, int> chartOfRoot;
  std::vector<int> chart(m.faceCount());
  for (size_t f = 0; f < m.faceCount(); ++f)
    chart[f] = chartOfRoot.try_emplace(find(int(f)), int(chartOfRoot.size())).first->second;
  return chart;
}

/// 3-D edges (unordered position pairs) whose two faces use different UV edges.
int seamEdgeCount(const TexturedMesh& m) {
  std::map<std::pair<int, int>, std::vector<std::pair<int, int>>> uvEdgesOf;
  for (size_t f = 0; f < m.faceCount(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = m.triangles[f][size_t(c)], b = m.triangles[f][size_t((c + 1) % 3)];
      const int ua = m.uvTriangles[f][size_t(c)], ub = m.uvTriangles[f][size_t((c + 1) % 3)];
      uvEdgesOf[{std::min(a, b), std::max(a, b)}].push_back({std::min(ua, ub), std::max(ua, ub)});
    }
  int seams = 0;
  for (const auto& [edge, uvEdges] : uvEdgesOf)
    if (uvEdges.size() == 2 && uvEdges[0] != uvEdges[1]) ++seams;
  return seams;
}

class ProceduralMesh : public ::testing::TestWithParam<size_t> {
 protected:
  static const std::vector<MeshCase>& meshes() {
    static const std::vector<MeshCase> all = allMeshes();
    return all;
  }
  const MeshCase& c() const { return meshes()[GetParam()]; }
};

TEST_P(ProceduralMesh, IndicesAreConsistent) {
  const TexturedMesh& m = c().mesh;
  ASSERT_EQ(m.triangles.size(), m.uvTriangles.size());
  if (c().faces) {
    EXPECT_EQ(m.faceCount(), c().faces);
  }
  std::vector<bool> positionUsed(m.positions.size()), uvUsed(m.uvs.size());
  for (size_t f = 0; f < m.faceCount(); ++f)
    for (size_t k = 0; k < 3; ++k) {
      const int p = m.triangles[f][k], t = m.uvTriangles[f][k];
      ASSERT_GE(p, 0);
      ASSERT_LT(size_t(p), m.positions.size());
      ASSERT_GE(t, 0);
      ASSERT_LT(size_t(t), m.uvs.size());
      positionUsed[size_t(p)] = uvUsed[size_t(t)] = true;
    }
  EXPECT_EQ(std::count(positionUsed.begin(), positionUsed.end(), false), 0);
  EXPECT_EQ(std::count(uvUsed.begin(), uvUsed.end(), false), 0);
}

TEST_P(ProceduralMesh, PositionsAreWelded) {
  const TexturedMesh& m = c().mesh;
  std::set<std::array<double, 3>> distinct;
  for (const auto& p : m.positions) distinct.insert({p.x(), p.y(), p.z()});
  EXPECT_EQ(distinct.size(), m.positions.size()) << "two position indices at one 3-D point";
  // Also no near-duplicates a file round trip could merge or split.
  double closest = 1e300;
  for (size_t a = 0; a < m.positions.size(); ++a)
    for (size_t b = a + 1; b < m.positions.size(); ++b)
      closest = std::min(closest, (m.positions[a] - m.positions[b]).norm());
  EXPECT_GT(closest, 1e-3);
}

TEST_P(ProceduralMesh, UvTrianglesAreCounterClockwiseAndInsideTheUnitSquare) {
  const TexturedMesh& m = c().mesh;
  for (size_t f = 0; f < m.faceCount(); ++f) EXPECT_GT(signedUvArea(m, f), 0.0) << "face " << f;
  for (const auto& uv : m.uvs) {
    EXPECT_GT(uv.x(), 0.0);
    EXPECT_LT(uv.x(), 1.0);
    EXPECT_GT(uv.y(), 0.0);
    EXPECT_LT(uv.y(), 1.0);
  }
}

TEST_P(ProceduralMesh, ChartsAreSeparatedByGutters) {
  const TexturedMesh& m = c().mesh;
  const std::vector<int> chart = chartOfFace(m);
  const int charts = *std::max_element(chart.begin(), chart.end()) + 1;
  if (c().name == "torus") {
    EXPECT_GE(charts, c().charts);
  } else {
    EXPECT_EQ(charts, c().charts);
  }
  // Every chart is an axis-aligned rectangle in UV, so a gap between bounding boxes along
  // one axis is the gutter.
  std::vector<Eigen::AlignedBox2d> box(static_cast<size_t>(charts));
  for (size_t f = 0; f < m.faceCount(); ++f)
    for (int k : m.uvTriangles[f]) box[size_t(chart[f])].extend(m.uvs[size_t(k)]);
  for (size_t a = 0; a < box.size(); ++a)
    for (size_t b = a + 1; b < box.size(); ++b) {
      const Eigen::Vector2d gap =
          (box[a].min() - box[b].max()).cwiseMax(box[b].min() - box[a].max());
      EXPECT_GE(gap.maxCoeff(), kMinGutter) << "charts " << a << " and " << b;
    }
}

TEST_P(ProceduralMesh, SurfaceAreaMatchesTheAnalyticValue) {
  const TexturedMesh& m = c().mesh;
  double area = 0.0;
  for (size_t f = 0; f < m.faceCount(); ++f) {
    const double a = triangleArea3d(m, f);
    EXPECT_GT(a, 0.0) << "degenerate face " << f;
    area += a;
  }
  EXPECT_NEAR(area, c().area, c().areaTolerance * c().area);
}

TEST_P(ProceduralMesh, ClosedMeshesAreConsistentlyOrientedOutward) {
  const TexturedMesh& m = c().mesh;
  std::map<std::pair<int, int>, int> directedEdges;
  for (const auto& t : m.triangles)
    for (size_t k = 0; k < 3; ++k) ++directedEdges[{t[k], t[(k + 1) % 3]}];
  for (const auto& [edge, count] : directedEdges) {
    EXPECT_EQ(count, 1) << "edge used twice in one direction: inconsistent orientation";
    if (c().closed) {
      EXPECT_TRUE(directedEdges.count({edge.second, edge.first})) << "open edge on closed mesh";
    }
  }
  if (!c().closed) return;
  double volume = 0.0;  // divergence theorem: positive iff normals point outward
  for (const auto& t : m.triangles)
    volume +=
        m.positions[size_t(t[0])].dot(m.positions[size_t(t[1])].cross(m.positions[size_t(t[2])])) /
        6.0;
  EXPECT_NEAR(volume, c().volume, 0.03 * c().volume);
}

TEST(Procedural, EveryCaseHasItsName) {
  const std::vector<MeshCase> all = allMeshes();
  ASSERT_EQ(all.size(), kMeshNames.size());
  for (size_t k = 0; k < all.size(); ++k) EXPECT_EQ(all[k].name, kMeshNames[k]) << k;
}

INSTANTIATE_TEST_SUITE_P(AllMeshes, ProceduralMesh, ::testing::Range<size_t>(0, kMeshNames.size()),
                         [](const auto& param) { return std::string(kMeshNames[param.param]); });

TEST(Procedural, SeamEdgeCounts) {
  EXPECT_EQ(seamEdgeCount(procedural::square()), 0);
  EXPECT_EQ(seamEdgeCount(procedural::twoChartSquare(4)), 4);
  EXPECT_EQ(seamEdgeCount(procedural::twoChartSquare(7)), 7);
  EXPECT_EQ(seamEdgeCount(procedural::cube(3)), 12 * 3);
  EXPECT_EQ(seamEdgeCount(procedural::cylinder(32, 16)), 16);
  EXPECT_EQ(seamEdgeCount(procedural::cubeSphere(5)), 12 * 5);
  EXPECT_GT(seamEdgeCount(procedural::sampleTorus()), 0);
}

TEST(Procedural, AlignedCubeUvsAreTexelCentresAndJitterStaysWithinItsBound) {
  constexpr int kSize = procedural::kAlignedCubeResolution;
  const TexturedMesh aligned = procedural::alignedCube(8);
  const TexturedMesh jittered = procedural::alignedCube(8, 1e-4);
  ASSERT_EQ(aligned.uvs.size(), jittered.uvs.size());
  int moved = 0;
  for (size_t k = 0; k < aligned.uvs.size(); ++k)
    for (int a = 0; a < 2; ++a) {
      const double texel = aligned.uvs[k][a] * kSize - 0.5;
      EXPECT_EQ(texel, std::round(texel)) << "uv " << k;
      const double offset = jittered.uvs[k][a] * kSize - 0.5 - texel;
      EXPECT_LE(std::abs(offset), 1e-4 * (1.0 + 1e-9)) << "uv " << k;
      moved += offset != 0.0;
    }
  EXPECT_EQ(moved, static_cast<int>(2 * aligned.uvs.size()));
  EXPECT_EQ(seamEdgeCount(aligned), 12 * 8);
  EXPECT_ANY_THROW(procedural::alignedCube(3));  // 64 texels do not split into 3 quads
}

TEST(Procedural, DefaultSquareIsTheUnitSquare) {
  const TexturedMesh m = procedural::square();
  ASSERT_EQ(m.faceCount(), 2u);
  for (size_t k = 0; k < m.uvs.size(); ++k) {
    EXPECT_EQ(m.uvs[k].x(), m.positions[k].x());
    EXPECT_EQ(m.uvs[k].y(), m.positions[k].y());
  }
}

TEST(Procedural, CylinderAndTwoChartsAreMappedIsometrically) {
  // UV length / 3-D length is the same for every edge (up to the chord-vs-arc difference of
  // the cylinder's polygonal cross-section).
  for (const TexturedMesh& m : {procedural::cylinder(64, 8), procedural::twoChartSquare(6)}) {
    double lo = 1e300, hi = 0.0;
    for (size_t f = 0; f < m.faceCount(); ++f)
      for (size_t k = 0; k < 3; ++k) {
        const double l3 = (m.positions[size_t(m.triangles[f][(k + 1) % 3])] -
                           m.positions[size_t(m.triangles[f][k])])
                              .norm();
        const double l2 =
            (m.uvs[size_t(m.uvTriangles[f][(k + 1) % 3])] - m.uvs[size_t(m.uvTriangles[f][k])])
                .norm();
        lo = std::min(lo, l2 / l3);
        hi = std::max(hi, l2 / l3);
      }
    EXPECT_LT(hi / lo, 1.001);
  }
}

TEST(Procedural, SampleTorusHasTheAdvertisedSize) {
  const TexturedMesh m = procedural::sampleTorus();
  EXPECT_GE(m.faceCount(), size_t(2 * 56 * 32));
  EXPECT_LE(m.faceCount(), size_t(2 * 72 * 32));
}

TEST(Procedural, InvalidSizesAreRejected) {
  EXPECT_ANY_THROW(procedural::cube(0));
  EXPECT_ANY_THROW(procedural::cylinder(2, 4));
  EXPECT_ANY_THROW(procedural::twoChartSquare(0));
  EXPECT_ANY_THROW(procedural::sampleTexture(0, 4));
}

TEST(Procedural, SampleTextureIsColourfulAsymmetricAndOnByteLevels) {
  const int w = 96, h = 64;
  const Image image = procedural::sampleTexture(w, h);
  ASSERT_EQ(image.width, w);
  ASSERT_EQ(image.height, h);
  ASSERT_EQ(image.channels, 3);
  EXPECT_EQ(image.format, PixelFormat::UInt8);
  for (float v : image.pixels) {
    ASSERT_GE(v, 0.0f);
    ASSERT_LE(v, 1.0f);
    EXPECT_EQ(v * 255.0f, std::round(v * 255.0f));
  }
  for (int c = 0; c < 3; ++c) {
    float lo = 1, hi = 0;
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) {
        lo = std::min(lo, image.at(i, j, c));
        hi = std::max(hi, image.at(i, j, c));
      }
    EXPECT_GT(hi - lo, 0.5f) << "channel " << c;
  }
  int vertical = 0, horizontal = 0, rotated = 0;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      for (int c = 0; c < 3; ++c) {
        vertical += image.at(i, j, c) != image.at(i, h - 1 - j, c);
        horizontal += image.at(i, j, c) != image.at(w - 1 - i, j, c);
        rotated += image.at(i, j, c) != image.at(w - 1 - i, h - 1 - j, c);
      }
  EXPECT_GT(vertical, w * h / 4);
  EXPECT_GT(horizontal, w * h / 4);
  EXPECT_GT(rotated, w * h / 4);
}

}  // namespace
}  // namespace texgrad
