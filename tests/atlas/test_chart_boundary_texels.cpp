// Chart-boundary texels: the texels whose open footprint a chart edge crosses, exactly.
#include <gtest/gtest.h>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/chart_boundary_texels.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

/// Marked image texels of a mesh at W x H, as a set of (i, j) strings for readable failures.
std::vector<std::pair<int, int>> markedTexels(const TexturedMesh& mesh, int w, int h) {
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid g = buildTexelGrid(mesh, atlas, w, h);
  const std::vector<uint8_t> marked = chartBoundaryTexels(mesh, atlas, g);
  std::vector<std::pair<int, int>> texels;
  for (int y = 0; y < g.ny; ++y)
    for (int x = 0; x < g.nx; ++x)
      if (marked[static_cast<size_t>(g.texelIndex(x, y))]) texels.emplace_back(x + g.x0, y + g.y0);
  return texels;
}

TEST(ChartBoundaryTexels, EdgesOnTexelLinesMarkOnlyTheTexelsOnThem) {
  // UV [0.3125, 0.8125]^2 at 8 x 8 is grid [2, 6]^2: the chart's edges lie on texel lines, so
  // they cross the open footprints of texels 2 and 6 (across) and lie on the border of those of
  // texels 1, 3, 5 and 7, which they do not cross.
  const auto texels = markedTexels(procedural::square(0.5, 0.5, 0.3125, 0.3125), 8, 8);
  std::vector<std::pair<int, int>> expected;
  for (int j = 2; j <= 6; ++j)
    for (int i = 2; i <= 6; ++i)
      if (i == 2 || i == 6 || j == 2 || j == 6) expected.emplace_back(i, j);
  EXPECT_EQ(texels, expected);
}

TEST(ChartBoundaryTexels, EdgesBetweenTexelLinesMarkTwoTexelsAcross) {
  // Grid [1.5, 5.5]^2: each edge lies inside the footprints of the two texels on either side.
  const auto texels = markedTexels(procedural::square(0.5, 0.5, 0.25, 0.25), 8, 8);
  std::vector<std::pair<int, int>> expected;
  for (int j = 1; j <= 6; ++j)
    for (int i = 1; i <= 6; ++i)
      if (i <= 2 || i >= 5 || j <= 2 || j >= 5) expected.emplace_back(i, j);
  EXPECT_EQ(texels, expected);
}

TEST(ChartBoundaryTexels, StackedChartsMarkOnlyTheirBoundaries) {
  // Two copies of the square on the same UVs: every covered texel meets two charts, but only
  // the ring along the edges is crossed by them.
  TexturedMesh mesh = procedural::square(0.5, 0.5, 0.3125, 0.3125);
  const TexturedMesh copy = procedural::square(0.5, 0.5, 0.3125, 0.3125);
  for (const Eigen::Vector3d& p : copy.positions)
    mesh.positions.push_back(p + Eigen::Vector3d(3, 0, 0));
  for (const Triangle& t : copy.triangles) mesh.triangles.push_back({t[0] + 4, t[1] + 4, t[2] + 4});
  for (const Triangle& t : copy.uvTriangles) mesh.uvTriangles.push_back(t);
  EXPECT_EQ(markedTexels(mesh, 8, 8),
            markedTexels(procedural::square(0.5, 0.5, 0.3125, 0.3125), 8, 8));
}

}  // namespace
}  // namespace texgrad
