// Texture pages (texgrad/io/texture_pages.h) through the apps: the charts of one atlas moved by
// whole tiles onto 2 x 2 UDIM tiles give, tile by tile, what the single image holding the same
// tiles as its quadrants gives (filter, geodesic, seams), seams between tiles included; a chart
// straddling two tiles is cut at their border like its two halves built on the two tiles.
#include <gtest/gtest.h>

#include <array>

#include "app_fixtures.h"
#include "straddling_strip.h"
#include "texgrad/apps/filter.h"
#include "texgrad/apps/geodesic.h"
#include "texgrad/apps/seams.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/seam_jump.h"
#include "texgrad/core/error.h"
#include "texgrad/io/procedural.h"
#include "texgrad/io/texture_pages.h"

namespace texgrad {
namespace {

/// Texels per tile side (the charts keep >= 3 texels from every tile border at this size).
constexpr int kTile = 128;
/// Agreement asked for between the two runs (float texture values).
constexpr double kPagesTolerance = 1e-6;

/// The tile (k, l) of chart c: charts spread over the four tiles 1001, 1002, 1011, 1012.
std::array<int, 2> tileOfChart(int32_t c) {
  return {c % 2, (c / 2) % 2};
}

/// The same charts twice: moved by whole tiles (UDIM), and in one 2 x 2-tile image.
struct TiledCharts {
  TexturedMesh udim;           ///< chart c at UV + tileOfChart(c)
  TexturedMesh single;         ///< chart c at (UV + tileOfChart(c)) / 2
  std::array<Image, 4> tiles;  ///< tile images in page order (1001, 1002, 1011, 1012)
  Image quadrants;             ///< the tiles as the quadrants of one 2 kTile image
};

TiledCharts makeTiledCharts() {
  const TexturedMesh mesh = procedural::cubeSphere(4);
  const Atlas atlas = buildAtlas(mesh);
  TiledCharts t{mesh, mesh, {}, Image(2 * kTile, 2 * kTile, 3)};
  std::vector<int32_t> chartOfUv(mesh.uvs.size(), -1);
  for (size_t f = 0; f < mesh.faceCount(); ++f)
    for (int32_t uv : mesh.uvTriangles[f])
      chartOfUv[static_cast<size_t>(uv)] = atlas.chartOfFace[f];
  for (size_t i = 0; i < mesh.uvs.size(); ++i) {
    const std::array<int, 2> tile = tileOfChart(chartOfUv[i]);
    t.udim.uvs[i] += Eigen::Vector2d(tile[0], tile[1]);
    t.single.uvs[i] = t.udim.uvs[i] / 2.0;
  }
  for (int p = 0; p < 4; ++p) {
    t.tiles[static_cast<size_t>(p)] = test::randomTexture(kTile, kTile, 3, 7u + unsigned(p));
    const int k = p % 2, l = p / 2;
    for (int j = 0; j < kTile; ++j)
      for (int i = 0; i < kTile; ++i)
        for (int c = 0; c < 3; ++c)
          t.quadrants.at(k * kTile + i, l * kTile + j, c) =
              t.tiles[static_cast<size_t>(p)].at(i, j, c);
  }
  return t;
}

/// The UDIM layout of the tiled charts, arranged at kTile per tile.
PageLayout tiledLayout(const TexturedMesh& udim) {
  PageLayout layout = findTexturePages(udim, "baseColor", "tile.<UDIM>.png");
  for (TexturePage& page : layout.pages) page.width = page.height = kTile;
  arrangePages(layout);
  return layout;
}

/// Largest difference between page p of `pages` and the quadrant of its tile in `single`.
double pageVersusQuadrant(const PageLayout& layout, const Image& pages, const Image& single) {
  double worst = 0.0;
  for (size_t p = 0; p < layout.pages.size(); ++p) {
    const Image page = pageImage(layout, pages, p);
    const int k = layout.pages[p].tileU, l = layout.pages[p].tileV;
    for (int j = 0; j < kTile; ++j)
      for (int i = 0; i < kTile; ++i)
        for (int c = 0; c < page.channels; ++c)
          worst = std::max(worst, std::abs(double(page.at(i, j, c)) -
                                           single.at(k * kTile + i, l * kTile + j, c)));
  }
  return worst;
}

/// Both domains: the layout of the UDIM tiles and the single image.
struct PagesAndSingle {
  TiledCharts charts = makeTiledCharts();
  PageLayout layout = tiledLayout(charts.udim);
  Image layoutImage = composePages(layout, {charts.tiles.begin(), charts.tiles.end()});
  TexelDomain paged{placeOnPages(charts.udim, layout), layout.width, layout.height};
  TexelDomain single{charts.single, 2 * kTile, 2 * kTile};
};

TEST(TexturePagesApps, UdimTilesFilterLikeTheSingleImage) {
  PagesAndSingle d;
  ASSERT_EQ(d.layout.pages.size(), 4u);
  EXPECT_EQ(d.paged.unknowns(), d.single.unknowns());
  FilterOptions options;
  options.beta = 0.2;
  options.solver.kind = SolverKind::Direct;
  const FilterResult paged = filterTexture(d.paged, d.layoutImage, options);
  const FilterResult single = filterTexture(d.single, d.charts.quadrants, options);
  EXPECT_GT(test::activeRms(d.single, single.image, d.charts.quadrants), 0.01);  // it filtered
  EXPECT_LT(pageVersusQuadrant(d.layout, paged.image, single.image), kPagesTolerance);
}

TEST(TexturePagesApps, UdimTilesGeodesicLikeTheSingleImage) {
  PagesAndSingle d;
  GeodesicOptions options;
  options.solver.kind = SolverKind::Direct;
  const std::array<GeodesicSource, 1> sources{GeodesicSource::atVertex(0)};
  const GeodesicResult paged = geodesicDistance(d.paged, sources, options);
  const GeodesicResult single = geodesicDistance(d.single, sources, options);
  Image pagedImage(d.layout.width, d.layout.height, 1), singleImage(2 * kTile, 2 * kTile, 1);
  scatterTexels(d.paged.grid(), paged.distances, pagedImage);
  scatterTexels(d.single.grid(), single.distances, singleImage);
  EXPECT_GT(single.maxDistance, 1.0);
  EXPECT_NEAR(paged.maxDistance, single.maxDistance, kPagesTolerance);
  EXPECT_LT(pageVersusQuadrant(d.layout, pagedImage, singleImage), kPagesTolerance);
}

TEST(TexturePagesApps, SeamsBetweenTilesAreSmoothedLikeInTheSingleImage) {
  PagesAndSingle d;
  // Seams of the cube sphere join charts on different tiles.
  size_t crossing = 0;
  for (const SeamPair& s : d.paged.atlas().seams)
    crossing += d.layout.facePage[static_cast<size_t>(s.a.face)] !=
                d.layout.facePage[static_cast<size_t>(s.b.face)];
  ASSERT_GT(crossing, 0u);
  const SeamsResult paged = smoothSeams(d.paged, d.layoutImage);
  const SeamsResult single = smoothSeams(d.single, d.charts.quadrants);
  EXPECT_LT(pageVersusQuadrant(d.layout, paged.image, single.image), kPagesTolerance);
  // Continuous across the tile borders: the seam jump drops as in the single image.
  const double before = measureSeamJump(d.paged.mesh(), d.paged.atlas(), d.layoutImage).rms;
  const double after = measureSeamJump(d.paged.mesh(), d.paged.atlas(), paged.image).rms;
  const double singleAfter = measureSeamJump(d.single.mesh(), d.single.atlas(), single.image).rms;
  EXPECT_LT(after, 0.25 * before);
  EXPECT_NEAR(after, singleAfter, kPagesTolerance);
}

/// Texels per tile side of the straddling strip's tiles.
constexpr int kStripTile = 64;

/// Filter (beta 0.2, direct solve) and geodesic distances of a mesh on UDIM tiles
/// "strip.<UDIM>.png" (random tile images), as layout images, and the placed mesh's atlas.
struct TiledStripOutputs {
  PageLayout layout;
  Image input, filtered, distances;
  size_t charts = 0, seams = 0;
};
TiledStripOutputs processOnTiles(const TexturedMesh& mesh, const Eigen::Vector3d& source) {
  TiledStripOutputs out;
  out.layout = findTexturePages(mesh, "baseColor", "strip.<UDIM>.png");
  std::vector<Image> tiles;
  for (TexturePage& page : out.layout.pages) {
    page.width = page.height = kStripTile;
    tiles.push_back(test::randomTexture(kStripTile, kStripTile, 3, 11u + unsigned(tiles.size())));
  }
  arrangePages(out.layout);
  out.input = composePages(out.layout, tiles);
  const TexelDomain domain(placeOnPages(mesh, out.layout), out.layout.width, out.layout.height);
  out.charts = domain.atlas().charts.size();
  out.seams = domain.atlas().seams.size();
  FilterOptions filter;
  filter.beta = 0.2;
  filter.solver.kind = SolverKind::Direct;
  out.filtered = filterTexture(domain, out.input, filter).image;
  GeodesicOptions geodesic;
  geodesic.solver.kind = SolverKind::Direct;
  const std::array<GeodesicSource, 1> sources{GeodesicSource::atPoint(source)};
  out.distances = Image(out.layout.width, out.layout.height, 1, PixelFormat::Float);
  scatterTexels(domain.grid(), geodesicDistance(domain, sources, geodesic).distances,
                out.distances);
  return out;
}

/// Largest difference of two images of one size.
double largestDifference(const Image& a, const Image& b) {
  EXPECT_EQ(a.pixels.size(), b.pixels.size());
  double worst = 0.0;
  for (size_t i = 0; i < a.pixels.size() && i < b.pixels.size(); ++i)
    worst = std::max(worst, static_cast<double>(std::abs(a.pixels[i] - b.pixels[i])));
  return worst;
}

TEST(TexturePagesApps, AChartStraddlingTwoTilesMatchesItsHalvesOnTheTwoTiles) {
  const test::StraddlingStrip strip;
  const TexturedMesh straddling = strip.straddling(), halves = strip.halves(0.0);
  // Library callers that skip meshForPages get the refusal naming the face.
  EXPECT_THROW(findTexturePages(straddling, "baseColor", "strip.<UDIM>.png"), InvalidInputError);
  const WrappedMesh cut = meshForPages(straddling, {}, "baseColor", "strip.<UDIM>.png");
  EXPECT_EQ(cut.mesh.faceCount(), straddling.faceCount() + 2);

  const Eigen::Vector3d source(0.3, 0.45, 0.1);
  const TiledStripOutputs a = processOnTiles(cut.mesh, source);
  const TiledStripOutputs b = processOnTiles(halves, source);
  ASSERT_EQ(a.layout.pages.size(), 2u);
  EXPECT_EQ(a.layout.pages[0].name, "1001");
  EXPECT_EQ(a.layout.pages[1].name, "1002");
  EXPECT_EQ(a.layout.pages[1].offset, b.layout.pages[1].offset);
  EXPECT_EQ(a.charts, 2u);  // one per tile
  EXPECT_EQ(a.seams, 2u);   // P1-X and X-R1, on the border of tiles 1001 and 1002
  EXPECT_GT(largestDifference(a.filtered, a.input), 0.1);  // it filtered
  EXPECT_LT(largestDifference(a.filtered, b.filtered), kPagesTolerance);
  EXPECT_LT(largestDifference(a.distances, b.distances), kPagesTolerance);
}

}  // namespace
}  // namespace texgrad
