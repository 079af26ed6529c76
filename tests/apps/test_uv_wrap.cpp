// Wrapped textures (issue 30): a mesh whose charts lie in other unit UV tiles, or straddle a tile
// border, filters and measures geodesics exactly like the same charts laid out in [0, 1]^2.
#include <gtest/gtest.h>

#include "app_fixtures.h"
#include "straddling_strip.h"
#include "test_paths.h"
#include "texgrad/apps/filter.h"
#include "texgrad/apps/geodesic.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/procedural.h"
#include "texgrad/io/uv_tiles.h"

namespace texgrad {
namespace {

/// The equivalence the issue asks for (float outputs).
constexpr double kSameOutput = 1e-6;
constexpr int kWrapSize = 64;

/// Largest difference of two images of one size.
double maxWrapDifference(const Image& a, const Image& b) {
  EXPECT_EQ(a.pixels.size(), b.pixels.size());
  double worst = 0.0;
  for (size_t i = 0; i < a.pixels.size() && i < b.pixels.size(); ++i)
    worst = std::max(worst, static_cast<double>(std::abs(a.pixels[i] - b.pixels[i])));
  return worst;
}

/// Filter (beta 0.2, direct solve) and geodesic distances from a 3-D point, both as images.
struct WrapOutputs {
  Image filtered, distances;
};
WrapOutputs processWrapped(TexturedMesh mesh, const Eigen::Vector3d& source) {
  const TexelDomain domain(std::move(mesh), kWrapSize, kWrapSize);
  FilterOptions filter;
  filter.beta = 0.2;
  filter.solver.kind = SolverKind::Direct;
  WrapOutputs out;
  out.filtered =
      filterTexture(domain, test::randomTexture(kWrapSize, kWrapSize, 3, 5), filter).image;
  GeodesicOptions geodesic;
  geodesic.solver.kind = SolverKind::Direct;
  const GeodesicSource sources[] = {GeodesicSource::atPoint(source)};
  const GeodesicResult result = geodesicDistance(domain, sources, geodesic);
  out.distances = Image(kWrapSize, kWrapSize, 1, PixelFormat::Float);
  scatterTexels(domain.grid(), result.distances, out.distances);
  return out;
}

void expectSameWrapOutputs(const TexturedMesh& wrapped, const TexturedMesh& reference,
                           const Eigen::Vector3d& source) {
  const WrapOutputs a = processWrapped(wrapped, source), b = processWrapped(reference, source);
  EXPECT_LT(maxWrapDifference(a.filtered, b.filtered), kSameOutput);
  EXPECT_LT(maxWrapDifference(a.distances, b.distances), kSameOutput);
}

/// The mesh with each chart's UVs moved by a whole tile (chart c by moves[c % moves.size()]).
TexturedMesh moveCharts(TexturedMesh mesh, const std::vector<Eigen::Vector2d>& moves) {
  const Atlas atlas = buildAtlas(mesh);
  std::vector<int> chartOfUv(mesh.uvs.size(), -1);
  for (size_t f = 0; f < mesh.faceCount(); ++f)
    for (int32_t i : mesh.uvTriangles[f]) chartOfUv[i] = atlas.chartOfFace[f];
  for (size_t i = 0; i < mesh.uvs.size(); ++i)
    if (chartOfUv[i] >= 0) mesh.uvs[i] += moves[static_cast<size_t>(chartOfUv[i]) % moves.size()];
  return mesh;
}

const Eigen::Vector3d kCubeSource(0.5, 0.1, -0.2);  // on the cube's +x face

TEST(UvWrap, ChartsInVOneToTwoMatchTheirCopyInTheImage) {
  const TexturedMesh cube = procedural::cube(3);
  TexturedMesh up = moveCharts(cube, {{0.0, 1.0}});
  EXPECT_THROW(TexelDomain(up, kWrapSize, kWrapSize), InvalidInputError);  // today's refusal
  expectSameWrapOutputs(wrapTextureCoordinates(std::move(up), {}).mesh, cube, kCubeSource);
}

TEST(UvWrap, ChartsSpreadOverSeveralTilesMatchTheirCopyInTheImage) {
  const TexturedMesh cube = procedural::cube(3);
  const TexturedMesh spread = moveCharts(cube, {{0, 0}, {1, 0}, {-1, 2}, {3, -2}, {0, 1}, {2, 2}});
  expectSameWrapOutputs(wrapTextureCoordinates(spread, {}).mesh, cube, kCubeSource);
}

TEST(UvWrap, SpotWithChartsMovedByWholeTilesMatchesSpot) {
  // spot's atlas reaches past u = 0 and v = 1, so wrapping cuts it; with each chart moved by
  // another whole tile the cuts fall on other lines but leave the same pieces in the image.
  const std::filesystem::path path = test::sharedData() / "spot/spot_triangulated.obj";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  const TexturedMesh spot = readMesh(path);
  const TexturedMesh moved = moveCharts(spot, {{1, 0}, {0, 1}, {-2, 3}, {5, -1}, {0, 0}});
  const TexturedMesh reference = wrapTextureCoordinates(spot, {}).mesh;
  EXPECT_GT(reference.faceCount(), spot.faceCount());  // some charts were cut
  expectSameWrapOutputs(wrapTextureCoordinates(moved, {}).mesh, reference, {0.0, 0.3, 0.2});
}

TEST(UvWrap, MirroredTileMatchesTheMirroredCopy) {
  const TexturedMesh cube = procedural::cube(3);
  TexturedMesh inTileOne = cube, mirrored = cube;
  for (Eigen::Vector2d& uv : inTileOne.uvs) uv.x() += 1.0;
  for (Eigen::Vector2d& uv : mirrored.uvs) uv.x() = 1.0 - uv.x();
  const UvWrap mirror{TextureWrap::MirroredRepeat, TextureWrap::MirroredRepeat};
  expectSameWrapOutputs(wrapTextureCoordinates(inTileOne, mirror).mesh, mirrored, kCubeSource);
}

TEST(UvWrap, ClampToEdgeKeepsTheRefusal) {
  const TexturedMesh up = moveCharts(procedural::cube(3), {{0.0, 1.0}});
  const UvWrap clamp{TextureWrap::ClampToEdge, TextureWrap::ClampToEdge};
  try {
    const TexelDomain domain(wrapTextureCoordinates(up, clamp).mesh, kWrapSize, kWrapSize);
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("outside the image"), std::string::npos) << e.what();
  }
}

TEST(UvWrap, AChartStraddlingATileBorderMatchesItsTwoHalvesJoinedByASeam) {
  const test::StraddlingStrip strip;
  const TexturedMesh straddling = strip.straddling(), halves = strip.halves(-1.0);
  EXPECT_EQ(buildAtlas(straddling).charts.size(), 1u);
  const Atlas halvesAtlas = buildAtlas(halves);
  EXPECT_EQ(halvesAtlas.charts.size(), 2u);
  EXPECT_EQ(halvesAtlas.seams.size(), 2u);  // P1-X and X-R1
  const WrappedMesh wrapped = wrapTextureCoordinates(straddling, {});
  const Atlas wrappedAtlas = buildAtlas(wrapped.mesh);
  EXPECT_EQ(wrappedAtlas.charts.size(), 2u);
  EXPECT_EQ(wrappedAtlas.seams.size(), 2u);
  EXPECT_EQ(wrapped.mesh.faceCount(), straddling.faceCount() + 2);
  expectSameWrapOutputs(wrapped.mesh, halves, {0.3, 0.45, 0.1});
}

}  // namespace
}  // namespace texgrad
