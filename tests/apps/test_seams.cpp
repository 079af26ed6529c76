// Seam smoothing: only the free texels change, and the seam jump falls at least 5x.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <functional>
#include <string>

#include "app_fixtures.h"
#include "shared_meshes.h"
#include "texgrad/apps/seams.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/seam_jump.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

/// Per-chart constant colours: the worst seams a texture can have.
Image chartColours(const TexelDomain& domain, int w, int h) {
  Image image(w, h, 3);
  const TexelGrid& g = domain.grid();
  for (int32_t t : g.texelOfUnknown) {
    const int x = t % g.nx, y = t / g.nx;
    if (!g.inImage(x, y)) continue;
    const int chart = g.chartOfTexel(static_cast<size_t>(t));
    for (int c = 0; c < 3; ++c)
      image.at(x + g.x0, y + g.y0, c) = static_cast<float>(((chart * 7 + c * 3) % 11) / 10.0);
  }
  return image;
}

/// Every re-solved texel is a boundary texel (or under `mask`), and every other texel of the
/// image comes back bit for bit.
void expectOnlyResolvedTexelsChange(const TexelDomain& domain, const Image& in,
                                    const SeamsResult& r, const Image& mask) {
  const TexelGrid& g = domain.grid();
  ASSERT_EQ(r.freeTexels, static_cast<int64_t>(r.resolved.size()));
  std::vector<uint8_t> resolved(g.texelClass.size(), 0);
  for (int32_t u : r.resolved) {
    const int32_t t = g.texelOfUnknown[static_cast<size_t>(u)];
    resolved[static_cast<size_t>(t)] = 1;
    const int x = t % g.nx, y = t / g.nx;
    if (mask.empty()) {
      ASSERT_EQ(g.texelClass[static_cast<size_t>(t)], TexelClass::Boundary) << x << "," << y;
    } else if (g.inImage(x, y)) {
      ASSERT_GT(mask.at(x + g.x0, y + g.y0), 0.5f) << x << "," << y;
    }
  }
  for (int j = 0; j < in.height; ++j)
    for (int i = 0; i < in.width; ++i) {
      const int x = i - g.x0, y = j - g.y0;
      const bool inGrid = x >= 0 && y >= 0 && x < g.nx && y < g.ny;
      if (inGrid && resolved[static_cast<size_t>(g.texelIndex(x, y))]) continue;
      for (int c = 0; c < in.channels; ++c)
        ASSERT_EQ(r.image.at(i, j, c), in.at(i, j, c)) << "texel " << i << "," << j;
    }
}

/// No texel whose input is not black (some channel non-zero) comes out black.
void expectNoTexelTurnsBlack(const Image& in, const Image& out) {
  for (int j = 0; j < in.height; ++j)
    for (int i = 0; i < in.width; ++i) {
      bool wasBlack = true, isBlack = true;
      for (int c = 0; c < in.channels; ++c) {
        wasBlack = wasBlack && in.at(i, j, c) == 0.0f;
        isBlack = isBlack && out.at(i, j, c) == 0.0f;
      }
      ASSERT_FALSE(isBlack && !wasBlack) << "texel " << i << "," << j << " turned black";
    }
}

TEST(Seams, OnlyBoundaryTexelsChangeAndTheJumpFalls) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image input = chartColours(domain, 128, 128);
  const SeamsResult r = smoothSeams(domain, input);
  EXPECT_GT(r.freeTexels, 0);
  expectOnlyResolvedTexelsChange(domain, input, r, {});
  const double before = measureSeamJump(domain.mesh(), domain.atlas(), input).rms;
  const double after = measureSeamJump(domain.mesh(), domain.atlas(), r.image).rms;
  EXPECT_LT(after, before / 5.0) << before << " -> " << after;
}

TEST(Seams, MaskSelectsTheFreeTexels) {
  const TexelDomain domain(procedural::cube(3), 96, 64);
  const Image input = test::randomTexture(96, 64, 1, 9);
  Image mask(96, 64, 1);
  for (int j = 20; j < 40; ++j)
    for (int i = 10; i < 50; ++i) mask.at(i, j) = 1.0f;
  const SeamsResult r = smoothSeams(domain, input, mask);
  EXPECT_GT(r.freeTexels, 0);
  expectOnlyResolvedTexelsChange(domain, input, r, mask);
  // Harmonic values are smoother than noise.
  EXPECT_LT(test::dirichletEnergy(domain, r.image), test::dirichletEnergy(domain, input));
}

TEST(Seams, ConstantTextureStaysConstant) {
  const TexelDomain domain(procedural::cubeSphere(6), 64, 64);
  Image input(64, 64, 2);
  std::fill(input.pixels.begin(), input.pixels.end(), 0.375f);
  const SeamsResult r = smoothSeams(domain, input);
  for (float v : r.image.pixels) ASSERT_NEAR(v, 0.375f, 1e-6f);
}

// Atlases where the boundary texels of a chart (or a whole chart) have no fixed texel of their
// own: stacked, mirrored-and-stacked and thin charts, and textures of one texel. The cube's six
// charts sit in a 3 x 2 atlas; these fixtures move its UVs.

/// The cube with all six charts moved onto the atlas cell of chart 0 (stacked UVs); with
/// `mirrored`, every other chart is mirrored in u within that cell (flipped UV triangles).
TexturedMesh stackedCube(int subdivisions, bool mirrored) {
  TexturedMesh mesh = procedural::cube(subdivisions);
  const Atlas atlas = buildAtlas(mesh);
  std::vector<int> chartOfUv(mesh.uvs.size(), -1);
  for (size_t f = 0; f < mesh.faceCount(); ++f)
    for (int32_t uv : mesh.uvTriangles[f])
      chartOfUv[static_cast<size_t>(uv)] = atlas.chartOfFace[f];
  for (size_t k = 0; k < mesh.uvs.size(); ++k) {
    Eigen::Vector2d& uv = mesh.uvs[k];
    const double column = std::floor(uv.x() * 3.0), row = std::floor(uv.y() * 2.0);
    uv -= Eigen::Vector2d(column / 3.0, row / 2.0);
    if (mirrored && chartOfUv[k] % 2 == 1) uv.x() = 1.0 / 3.0 - uv.x();
  }
  return mesh;
}

/// The cube with chart 0 squashed in v to `fraction` of its height: a thin chart whose seams join
/// it to the other charts.
TexturedMesh cubeWithThinChart(int subdivisions, double fraction) {
  TexturedMesh mesh = procedural::cube(subdivisions);
  const Atlas atlas = buildAtlas(mesh);
  std::vector<uint8_t> inChart0(mesh.uvs.size(), 0);
  for (int32_t f : atlas.charts[0].faces)
    for (int32_t uv : mesh.uvTriangles[static_cast<size_t>(f)])
      inChart0[static_cast<size_t>(uv)] = 1;
  const double v0 = atlas.charts[0].uvMin.y();
  for (size_t k = 0; k < mesh.uvs.size(); ++k)
    if (inChart0[k]) mesh.uvs[k].y() = v0 + fraction * (mesh.uvs[k].y() - v0);
  return mesh;
}

struct SeamsCase {
  std::string name;
  std::function<TexturedMesh()> mesh;
  int width, height;
};

void PrintTo(const SeamsCase& c, std::ostream* os) {
  *os << c.name;
}

class SeamsWithoutOwnFixedTexels : public ::testing::TestWithParam<SeamsCase> {};

/// No texel whose input is not black comes out black, and texels that are not re-solved are
/// returned bit for bit (the Dirichlet problem must not invent values for texels nothing fixes).
TEST_P(SeamsWithoutOwnFixedTexels, NoTexelTurnsBlackAndFixedTexelsAreKept) {
  const SeamsCase& c = GetParam();
  const TexelDomain domain(c.mesh(), c.width, c.height);
  const Image input = test::randomTexture(c.width, c.height, 3, 17, 0.2f, 1.0f);
  const SeamsResult r = smoothSeams(domain, input);
  expectOnlyResolvedTexelsChange(domain, input, r, {});
  expectNoTexelTurnsBlack(input, r.image);
}

INSTANTIATE_TEST_SUITE_P(
    Fixtures, SeamsWithoutOwnFixedTexels,
    ::testing::Values(
        SeamsCase{"StackedCube", [] { return stackedCube(4, false); }, 96, 64},
        SeamsCase{"MirroredStackedCube", [] { return stackedCube(4, true); }, 96, 64},
        SeamsCase{"ThinChartWithSeams", [] { return cubeWithThinChart(4, 0.05); }, 96, 64},
        SeamsCase{"CubeWithoutInteriorTexels", [] { return procedural::cube(2); }, 6, 4},
        SeamsCase{"IsolatedThinChart", [] { return procedural::square(1.0, 0.01, 0.0, 0.5); }, 64,
                  64},
        SeamsCase{"CubeOnOneTexel", [] { return procedural::cube(2); }, 1, 1},
        SeamsCase{"SquareOnOneTexel", [] { return procedural::square(); }, 1, 1}),
    [](const ::testing::TestParamInfo<SeamsCase>& p) { return p.param.name; });

/// On a one-texel texture every texel is a chart-boundary texel and none is fixed: the Dirichlet
/// problem has no data, so the texel keeps its colour (it was written black before).
TEST(Seams, OneTexelTextureKeepsItsColour) {
  const TexelDomain domain(procedural::cube(2), 1, 1);
  Image input(1, 1, 3);
  const std::array<float, 3> colour{200.0f / 255.0f, 100.0f / 255.0f, 50.0f / 255.0f};
  for (int c = 0; c < 3; ++c) input.at(0, 0, c) = colour[static_cast<size_t>(c)];
  const SeamsResult r = smoothSeams(domain, input);
  EXPECT_EQ(r.freeTexels, 0);
  EXPECT_EQ(r.unanchoredTexels, domain.unknowns());
  for (int c = 0; c < 3; ++c) EXPECT_EQ(r.image.at(0, 0, c), colour[static_cast<size_t>(c)]);
}

/// Texels under stacked (or mirrored and stacked) charts whose footprint no chart boundary
/// crosses are interior to every chart over them: they are kept, and they anchor the boundary.
TEST(Seams, StackedChartInteriorsAreKeptAndAnchorTheBoundary) {
  for (const bool mirrored : {false, true}) {
    const TexelDomain domain(stackedCube(4, mirrored), 96, 64);
    const Image input = test::randomTexture(96, 64, 3, 5, 0.2f, 1.0f);
    const SeamsResult r = smoothSeams(domain, input);
    EXPECT_EQ(r.unanchoredTexels, 0);
    EXPECT_GT(r.freeTexels, 0);
    // All six charts lie on UV [0.03, 1/3 - 0.03] x [0.03, 0.47]: in grid coordinates
    // [2.38, 28.5] x [1.42, 29.58], so the footprints of texels 4..27 x 3..28 lie inside.
    const TexelGrid& g = domain.grid();
    for (int32_t u : r.resolved) {
      const int32_t t = g.texelOfUnknown[static_cast<size_t>(u)];
      const int i = t % g.nx + g.x0, j = t / g.nx + g.y0;
      EXPECT_FALSE(i >= 4 && i <= 27 && j >= 3 && j <= 28) << i << "," << j;
    }
  }
}

// Full-size shared meshes: *Slow, so only the Release pass runs it (scripts/test.sh).
class SharedSeamsSlow : public ::testing::TestWithParam<test::SharedMesh> {};

TEST_P(SharedSeamsSlow, JumpFallsAtLeastFiveFoldOnTheRealTexture) {
  const test::SharedMesh& s = GetParam();
  const Image texture = test::textureAtMost(readImage(test::sharedData() / s.texture), 1024);
  const TexelDomain domain(readMesh(test::sharedData() / s.obj), texture.width, texture.height);
  const SeamsResult r = smoothSeams(domain, texture);
  expectOnlyResolvedTexelsChange(domain, texture, r, {});
  expectNoTexelTurnsBlack(texture, r.image);
  const double before = measureSeamJump(domain.mesh(), domain.atlas(), texture).rms;
  const double after = measureSeamJump(domain.mesh(), domain.atlas(), r.image).rms;
  std::cout << "[ seams ] " << s.name << " seam jump " << before << " -> " << after << "\n";
  if (domain.atlas().seams.empty()) {  // Suzanne: nothing to measure, nothing may change
    EXPECT_EQ(before, 0.0);
    EXPECT_EQ(after, 0.0);
    return;
  }
  EXPECT_LE(after, before / 5.0);
}

/// The mesh plus its mirror image (x -> -x, moved apart so nothing welds) on the same UVs: every
/// chart is stacked on a mirrored twin, as in assets that texture both halves with one map.
TexturedMesh withMirroredTwin(TexturedMesh mesh) {
  const auto positions = static_cast<int32_t>(mesh.positions.size());
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : mesh.positions) box.extend(p);
  const double shift = 2.0 * box.diagonal().norm() + 1.0;
  for (int32_t k = 0; k < positions; ++k) {
    const Eigen::Vector3d p = mesh.positions[static_cast<size_t>(k)];
    mesh.positions.emplace_back(-p.x() + shift, p.y(), p.z());
  }
  const size_t faces = mesh.faceCount();
  for (size_t f = 0; f < faces; ++f) {
    const Triangle t = mesh.triangles[f], uv = mesh.uvTriangles[f];
    // Mirroring flips the 3-D orientation: reverse the corners so normals face outwards.
    mesh.triangles.push_back({t[0] + positions, t[2] + positions, t[1] + positions});
    mesh.uvTriangles.push_back({uv[0], uv[2], uv[1]});
  }
  return mesh;
}

/// Mirrored twins on the shared meshes: the texels under both twins' chart interiors are kept
/// (before, every texel was re-solved with nothing fixed and came out black).
TEST_P(SharedSeamsSlow, MirroredTwinsKeepTheirTextureAndTurnNothingBlack) {
  const test::SharedMesh& s = GetParam();
  const Image texture = test::textureAtMost(readImage(test::sharedData() / s.texture), 512);
  const TexelDomain domain(withMirroredTwin(readMesh(test::sharedData() / s.obj)), texture.width,
                           texture.height);
  const SeamsResult r = smoothSeams(domain, texture);
  expectOnlyResolvedTexelsChange(domain, texture, r, {});
  expectNoTexelTurnsBlack(texture, r.image);
  EXPECT_LT(r.freeTexels, domain.unknowns() / 2);
}

INSTANTIATE_TEST_SUITE_P(AllMeshes, SharedSeamsSlow, ::testing::ValuesIn(test::sharedMeshes()),
                         test::sharedMeshName);

}  // namespace
}  // namespace texgrad
