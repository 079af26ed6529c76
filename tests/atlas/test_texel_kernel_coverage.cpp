// Barely covered texels: the part of a texel's bilinear kernel the charts cover, against the
// closed form on an axis-aligned chart.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/atlas/texel_kernel_coverage.h"
#include "texgrad/core/error.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

/// Integral of the 1-D hat kernel 1 - |x - t| over [lo, hi] (texel coordinates).
double hatIntegral(double t, double lo, double hi) {
  const auto antiderivative = [](double z) {
    z = std::clamp(z, -1.0, 1.0);
    return z - z * std::abs(z) / 2.0;
  };
  return std::max(0.0, antiderivative(hi - t) - antiderivative(lo - t));
}

TEST(TexelKernelCoverage, MatchesTheClosedFormOnARectangle) {
  // The chart [3.98, 10.3] x [2.97, 9.5] in texel coordinates at 16 x 16: texel 3 sees 0.02 of
  // its hat across (kernel 2e-4), texel 2 in y 0.03 (4.5e-4), texel 11 across 0.3 (0.045).
  constexpr int kSize = 16;
  constexpr double x0 = 3.98, x1 = 10.3, y0 = 2.97, y1 = 9.5;
  const TexturedMesh mesh = procedural::square((x1 - x0) / kSize, (y1 - y0) / kSize,
                                               (x0 + 0.5) / kSize, (y0 + 0.5) / kSize);
  const TexelGrid grid = buildTexelGrid(mesh, buildAtlas(mesh), kSize, kSize);
  std::vector<double> coverage;  // per unknown, closed form
  for (int32_t u = 0; u < grid.unknownCount(); ++u) {
    const int32_t t = grid.texelOfUnknown[static_cast<size_t>(u)];
    const int i = t % grid.nx + grid.x0, j = t / grid.nx + grid.y0;
    coverage.push_back(hatIntegral(i, x0, x1) * hatIntegral(j, y0, y1));
  }
  // Thresholds just above and just below each coverage under a quarter: the sets match only if
  // every computed coverage is within that relative distance of the closed form.
  constexpr double kRelative = 1e-9;
  std::vector<double> fractions;
  for (double c : coverage)
    if (c < kMaxBarelyCoveredFraction)
      fractions.insert(fractions.end(), {c * (1 + kRelative), c * (1 - kRelative)});
  ASSERT_GE(fractions.size(), 20u);
  for (double fraction : fractions) {
    std::vector<int32_t> expected;
    for (int32_t u = 0; u < grid.unknownCount(); ++u)
      if (coverage[static_cast<size_t>(u)] < fraction) expected.push_back(u);
    EXPECT_EQ(barelyCoveredTexels(mesh, grid, fraction), expected) << fraction;
  }
}

TEST(TexelKernelCoverage, ChartEdgesOnLatticeLinesLeaveNoneAndSliversSome) {
  // The aligned cube's chart edges run on texel lines: every active texel has at least a quarter
  // of its kernel covered. Moved off the lines by up to 0.01 texel, edges cut slivers.
  const int size = procedural::kAlignedCubeResolution;
  for (double jitter : {0.0, 0.01}) {
    const TexturedMesh mesh = procedural::alignedCube(4, jitter);
    const TexelGrid grid = buildTexelGrid(mesh, buildAtlas(mesh), size, size);
    EXPECT_EQ(barelyCoveredTexels(mesh, grid, 1e-3).empty(), jitter == 0.0) << jitter;
  }
}

TEST(TexelKernelCoverage, RefusesAFractionOutsideItsRange) {
  const TexturedMesh mesh = procedural::square();
  const TexelGrid grid = buildTexelGrid(mesh, buildAtlas(mesh), 8, 8);
  for (double fraction : {0.0, -1.0, 0.3, std::nan("")})
    EXPECT_THROW(barelyCoveredTexels(mesh, grid, fraction), InvalidInputError) << fraction;
}

}  // namespace
}  // namespace texgrad
