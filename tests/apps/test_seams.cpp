// Seam smoothing: only the free texels change, and the seam jump falls at least 5x.
#include <gtest/gtest.h>

#include "app_fixtures.h"
#include "shared_meshes.h"
#include "texgrad/apps/seams.h"
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
    const int chart = g.texelChart[t];
    for (int c = 0; c < 3; ++c)
      image.at(x + g.x0, y + g.y0, c) = static_cast<float>(((chart * 7 + c * 3) % 11) / 10.0);
  }
  return image;
}

void expectOnlyFreeTexelsChange(const TexelDomain& domain, const Image& in, const Image& out,
                                const Image& mask) {
  const TexelGrid& g = domain.grid();
  for (int j = 0; j < in.height; ++j)
    for (int i = 0; i < in.width; ++i) {
      const int x = i - g.x0, y = j - g.y0;
      const bool inGrid = x >= 0 && y >= 0 && x < g.nx && y < g.ny;
      const TexelClass k = inGrid ? g.texelClass[g.texelIndex(x, y)] : TexelClass::Inactive;
      const bool isFree = mask.empty() ? k == TexelClass::Boundary
                                       : (k != TexelClass::Inactive && mask.at(i, j) > 0.5f);
      if (isFree) continue;
      for (int c = 0; c < in.channels; ++c)
        ASSERT_EQ(out.at(i, j, c), in.at(i, j, c)) << "texel " << i << "," << j;
    }
}

TEST(Seams, OnlyBoundaryTexelsChangeAndTheJumpFalls) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const Image input = chartColours(domain, 128, 128);
  const SeamsResult r = smoothSeams(domain, input);
  EXPECT_GT(r.freeTexels, 0);
  expectOnlyFreeTexelsChange(domain, input, r.image, {});
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
  expectOnlyFreeTexelsChange(domain, input, r.image, mask);
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

// Full-size shared meshes: *Slow, so only the Release pass runs it (scripts/test.sh).
class SharedSeamsSlow : public ::testing::TestWithParam<test::SharedMesh> {};

TEST_P(SharedSeamsSlow, JumpFallsAtLeastFiveFoldOnTheRealTexture) {
  const test::SharedMesh& s = GetParam();
  const Image texture = test::textureAtMost(readImage(test::sharedData() / s.texture), 1024);
  const TexelDomain domain(readMesh(test::sharedData() / s.obj), texture.width, texture.height);
  const SeamsResult r = smoothSeams(domain, texture);
  expectOnlyFreeTexelsChange(domain, texture, r.image, {});
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

INSTANTIATE_TEST_SUITE_P(AllMeshes, SharedSeamsSlow, ::testing::ValuesIn(test::sharedMeshes()),
                         test::sharedMeshName);

}  // namespace
}  // namespace texgrad
