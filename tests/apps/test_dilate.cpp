// Gutter padding: active texels untouched, gutters filled, seam-aware first ring.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "texgrad/apps/dilate.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/image_sampling.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

constexpr float kBackground = -7.0f;

Image randomOnActive(const TexelGrid& grid, int channels, uint32_t seed) {
  Image image(grid.imageWidth, grid.imageHeight, channels, PixelFormat::Float);
  std::fill(image.pixels.begin(), image.pixels.end(), kBackground);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.0f, 1.0f);
  for (int y = 0; y < grid.ny; ++y)
    for (int x = 0; x < grid.nx; ++x)
      if (grid.inImage(x, y) && grid.texelClass[grid.texelIndex(x, y)] != TexelClass::Inactive)
        for (int c = 0; c < channels; ++c) image.at(x + grid.x0, y + grid.y0, c) = value(rng);
  return image;
}

TEST(Dilate, ActiveTexelsBitIdenticalAndInfiniteFillsEverything) {
  const TexturedMesh mesh = procedural::cube(4);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, 96, 64);
  const Image input = randomOnActive(grid, 3, 1);
  DilateOptions options;
  options.infinite = true;
  const Image out = dilateGutters(mesh, atlas, grid, input, options);
  int gutter = 0;
  for (size_t k = 0; k < input.pixels.size(); ++k) {
    if (input.pixels[k] != kBackground) {
      EXPECT_EQ(std::memcmp(&input.pixels[k], &out.pixels[k], sizeof(float)), 0) << k;
    } else {
      ++gutter;
      EXPECT_NE(out.pixels[k], kBackground) << "gutter texel kept the background: " << k;
      EXPECT_GE(out.pixels[k], 0.0f);
      EXPECT_LE(out.pixels[k], 1.0f);
    }
  }
  EXPECT_GT(gutter, 0) << "fixture must have gutters";
}

TEST(Dilate, RadiusLimitsTheRings) {
  const TexturedMesh mesh = procedural::cube(4);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, 192, 128);
  const Image input = randomOnActive(grid, 1, 2);
  DilateOptions options;
  options.radius = 2;
  const Image out = dilateGutters(mesh, atlas, grid, input, options);
  // Chebyshev distance of every texel to the nearest active texel, by brute force.
  for (int j = 0; j < input.height; ++j)
    for (int i = 0; i < input.width; ++i) {
      if (input.at(i, j) != kBackground) continue;
      int best = 1 << 20;
      for (int y = std::max(0, j - 4); y <= std::min(input.height - 1, j + 4); ++y)
        for (int x = std::max(0, i - 4); x <= std::min(input.width - 1, i + 4); ++x)
          if (input.at(x, y) != kBackground)
            best = std::min(best, std::max(std::abs(x - i), std::abs(y - j)));
      if (best <= 2)
        EXPECT_NE(out.at(i, j), kBackground) << i << "," << j;
      else
        EXPECT_EQ(out.at(i, j), kBackground) << i << "," << j;
    }
}

TEST(Dilate, FirstRingContinuesAcrossTheCylinderSeam) {
  const TexturedMesh mesh = procedural::cylinder(64, 8);
  const Atlas atlas = buildAtlas(mesh);
  ASSERT_EQ(atlas.charts.size(), 1u);
  ASSERT_FALSE(atlas.seams.empty());
  const int size = 256;
  const TexelGrid grid = buildTexelGrid(mesh, atlas, size, size);
  const Eigen::Vector2d lo = atlas.charts[0].uvMin, hi = atlas.charts[0].uvMax;
  // The cylinder wraps around along one UV axis: the one along which the seam edges run apart.
  const auto& seam = atlas.seams.front();
  const Eigen::Vector2d ua = mesh.uvs[mesh.uvTriangles[seam.a.face][seam.a.corner]];
  const Eigen::Vector2d ub = mesh.uvs[mesh.uvTriangles[seam.b.face][seam.b.corner]];
  const int axis = std::abs(ua.x() - ub.x()) > std::abs(ua.y() - ub.y()) ? 0 : 1;
  const double period = hi[axis] - lo[axis];
  auto periodic = [&](double u) {
    return 0.5 + 0.5 * std::sin(2 * std::numbers::pi * (u - lo[axis]) / period);
  };
  Image input(size, size, 1, PixelFormat::Float);
  std::fill(input.pixels.begin(), input.pixels.end(), kBackground);
  for (int y = 0; y < grid.ny; ++y)
    for (int x = 0; x < grid.nx; ++x)
      if (grid.inImage(x, y) && grid.texelClass[grid.texelIndex(x, y)] != TexelClass::Inactive) {
        const Eigen::Vector2d uv = grid.toUv(Eigen::Vector2d(x, y));
        input.at(x + grid.x0, y + grid.y0) = static_cast<float>(periodic(uv[axis]));
      }
  DilateOptions options;
  options.radius = 1;
  const Image out = dilateGutters(mesh, atlas, grid, input, options);
  const double texelsAround = period * size;
  const double tolerance = 4.0 * std::pow(2 * std::numbers::pi / texelsAround, 2) + 1e-4;
  int checked = 0;
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      if (input.at(i, j) != kBackground || out.at(i, j) == kBackground) continue;
      const Eigen::Vector2d uv((i + 0.5) / size, (j + 0.5) / size);
      const double across = axis == 0 ? uv.y() : uv.x();
      const double acrossLo = axis == 0 ? lo.y() : lo.x(), acrossHi = axis == 0 ? hi.y() : hi.x();
      if (across < acrossLo || across > acrossHi) continue;  // beyond the cylinder's rims
      EXPECT_NEAR(out.at(i, j), periodic(uv[axis]), tolerance) << i << "," << j;
      ++checked;
    }
  EXPECT_GT(checked, 50);
}

TEST(Dilate, InfiniteValuesDoNotTurnIntoNan) {
  // Unreachable geodesic distances are +inf; a lookup next to one, with weight 0 on it, is exact.
  Image image(2, 2, 1, PixelFormat::Float);
  image.pixels = {1.0f, std::numeric_limits<float>::infinity(), 3.0f, 4.0f};
  EXPECT_EQ(sampleBilinearTexel(image, Eigen::Vector2d(0.0, 0.5), 0), 2.0f);
  EXPECT_EQ(sampleBilinearTexel(image, Eigen::Vector2d(0.5, 1.0), 0), 3.5f);
  EXPECT_TRUE(std::isinf(sampleBilinearTexel(image, Eigen::Vector2d(0.5, 0.0), 0)));
  // Every chart at +inf: the gutters, filled across the seam and ring by ring, are +inf too.
  const TexturedMesh mesh = procedural::cylinder(64, 8);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, 256, 256);
  Image input = randomOnActive(grid, 1, 3);
  for (float& v : input.pixels)
    if (v != kBackground) v = std::numeric_limits<float>::infinity();
  const Image out = dilateGutters(mesh, atlas, grid, input);
  int nan = 0;
  for (float v : out.pixels) nan += std::isnan(v) ? 1 : 0;
  EXPECT_EQ(nan, 0);
}

}  // namespace
}  // namespace texgrad
