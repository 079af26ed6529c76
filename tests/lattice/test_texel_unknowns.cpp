// TexelUnknowns, the rank-stored unknown numbering: equal to numbering the active texels one by
// one, for any active set and any texel count (word boundaries included), at 0.19 bytes a texel.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "texgrad/core/error.h"
#include "texgrad/lattice/texel_unknowns.h"

namespace texgrad {
namespace {

/// The numbering counted texel by texel: the unknown of each active texel, -1 elsewhere.
std::vector<int32_t> countedNumbering(size_t texels, const std::vector<int32_t>& active) {
  std::vector<int32_t> unknown(texels, -1);
  for (size_t u = 0; u < active.size(); ++u)
    unknown[static_cast<size_t>(active[u])] = static_cast<int32_t>(u);
  return unknown;
}

/// Every texel of `texels` active with probability `density` (fixed seed), ascending.
std::vector<int32_t> randomActive(size_t texels, double density, unsigned seed) {
  std::mt19937 random(seed);
  std::bernoulli_distribution isActive(density);
  std::vector<int32_t> active;
  for (size_t t = 0; t < texels; ++t)
    if (isActive(random)) active.push_back(static_cast<int32_t>(t));
  return active;
}

void expectCountedNumbering(size_t texels, const std::vector<int32_t>& active) {
  const TexelUnknowns numbering(texels, active);
  const std::vector<int32_t> expected = countedNumbering(texels, active);
  ASSERT_EQ(numbering.size(), texels);
  for (size_t t = 0; t < texels; ++t)
    ASSERT_EQ(numbering[t], expected[t]) << "texel " << t << " of " << texels;
}

TEST(TexelUnknowns, EqualsTheNumberingCountedTexelByTexel) {
  // Counts on either side of a 64-texel word, and densities from none to all.
  for (size_t texels : {1, 63, 64, 65, 127, 128, 129, 1000, 4097})
    for (double density : {0.0, 0.03, 0.5, 0.97, 1.0})
      expectCountedNumbering(texels, randomActive(texels, density, static_cast<unsigned>(texels)));
}

TEST(TexelUnknowns, LastTexelOfAWordAndFirstOfTheNext) {
  expectCountedNumbering(192, {0, 63, 64, 127, 128, 191});
  expectCountedNumbering(130, {63, 64, 129});
  expectCountedNumbering(0, {});
}

TEST(TexelUnknowns, EqualOnlyForTheSameTexelsAndActiveSet) {
  const TexelUnknowns numbering(65, std::vector<int32_t>{1, 64});
  EXPECT_FALSE(numbering.empty());
  EXPECT_EQ(numbering, TexelUnknowns(65, std::vector<int32_t>{1, 64}));
  EXPECT_NE(numbering, TexelUnknowns(65, std::vector<int32_t>{1, 63}));
  EXPECT_NE(TexelUnknowns(64, std::vector<int32_t>{1}), TexelUnknowns(65, std::vector<int32_t>{1}));
  EXPECT_NE(numbering, TexelUnknowns());
}

TEST(TexelUnknowns, RefusesActiveTexelsOutOfOrderOrRange) {
  EXPECT_THROW(TexelUnknowns(10, std::vector<int32_t>{3, 3}), InvalidInputError);
  EXPECT_THROW(TexelUnknowns(10, std::vector<int32_t>{5, 2}), InvalidInputError);
  EXPECT_THROW(TexelUnknowns(10, std::vector<int32_t>{10}), InvalidInputError);
  EXPECT_THROW(TexelUnknowns(10, std::vector<int32_t>{-1}), InvalidInputError);
}

TEST(TexelUnknowns, HoldsABitAndAFraction) {
  // A 4096² texture: a bit per texel and a 4-byte count per 64 (0.1875 bytes per texel), against
  // the 4 bytes of an int per texel, whichever texels are active (every other one here).
  const size_t texels = size_t{4096} * 4096;
  std::vector<int32_t> active;
  for (size_t t = 0; t < texels; t += 2) active.push_back(static_cast<int32_t>(t));
  const TexelUnknowns numbering(texels, active);
  EXPECT_LE(numbering.storageBytes(), static_cast<int64_t>(texels * 3 / 16 + 16));
}

TEST(TexelUnknowns, ClearFreesItsStorage) {
  TexelUnknowns numbering(1000, randomActive(1000, 0.5, 3));
  ASSERT_FALSE(numbering.empty());
  numbering.clear();
  EXPECT_TRUE(numbering.empty());
  EXPECT_EQ(numbering.size(), 0U);
  EXPECT_EQ(numbering.storageBytes(), 0);
  EXPECT_EQ(numbering, TexelUnknowns());
}

}  // namespace
}  // namespace texgrad
