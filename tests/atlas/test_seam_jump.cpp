// Seam jump diagnostic: zero for constants, linear in the texture, sees a jump between charts.
#include <gtest/gtest.h>

#include <random>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/seam_jump.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

TEST(SeamJump, ZeroForConstantTexture) {
  const TexturedMesh mesh = procedural::cube(3);
  const Atlas atlas = buildAtlas(mesh);
  Image texture(64, 64, 3);
  std::fill(texture.pixels.begin(), texture.pixels.end(), 0.25f);
  const SeamJump jump = measureSeamJump(mesh, atlas, texture);
  EXPECT_GT(jump.samples, 0);
  EXPECT_EQ(jump.rms, 0.0);
  EXPECT_EQ(jump.maxAbs, 0.0);
}

TEST(SeamJump, ScalesLinearlyWithTheTexture) {
  const TexturedMesh mesh = procedural::cube(3);
  const Atlas atlas = buildAtlas(mesh);
  Image texture(64, 64, 2), doubled(64, 64, 2);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> value(0.0f, 0.5f);
  for (size_t k = 0; k < texture.pixels.size(); ++k) {
    texture.pixels[k] = value(rng);
    doubled.pixels[k] = 2.0f * texture.pixels[k];
  }
  const SeamJump a = measureSeamJump(mesh, atlas, texture);
  const SeamJump b = measureSeamJump(mesh, atlas, doubled);
  EXPECT_GT(a.rms, 0.0);
  EXPECT_NEAR(b.rms, 2.0 * a.rms, 1e-6 * a.rms);
  EXPECT_NEAR(b.rmsPerChannel[1], 2.0 * a.rmsPerChannel[1], 1e-6 * a.rmsPerChannel[1]);
}

TEST(SeamJump, ChartColouredTextureJumpsByTheColourDifference) {
  const TexturedMesh mesh = procedural::twoChartSquare(4);
  const Atlas atlas = buildAtlas(mesh);
  ASSERT_EQ(atlas.charts.size(), 2u);
  // Texels within 1.5 texels of chart 1's UV box are 1, all others 0: bilinear lookups on side a
  // see only 0 and on side b only 1 as long as the gutter is wider than 3 texels.
  const int size = 256;
  const double margin = 1.5 / size;
  const Eigen::Vector2d lo = atlas.charts[1].uvMin.array() - margin;
  const Eigen::Vector2d hi = atlas.charts[1].uvMax.array() + margin;
  Image texture(size, size, 1);
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      const Eigen::Vector2d uv((i + 0.5) / size, (j + 0.5) / size);
      const bool inOne = (uv.array() >= lo.array()).all() && (uv.array() <= hi.array()).all();
      texture.at(i, j) = inOne ? 1.0f : 0.0f;
    }
  const SeamJump jump = measureSeamJump(mesh, atlas, texture);
  EXPECT_NEAR(jump.rms, 1.0, 1e-9);
  EXPECT_NEAR(jump.seamLength3d, 1.0, 1e-9) << "the seam is the square's middle line";
}

}  // namespace
}  // namespace texgrad
