// Core tests: a FloatSystem keeps the entries of its exact unknowns' rows and columns in double
// and the others rounded to float, holds each row's sum, refuses inconsistent sizes and leaves a
// system it was moved from empty.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "texgrad/core/error.h"
#include "texgrad/core/float_system.h"

using namespace texgrad;

namespace {

/// A 3 x 3 tridiagonal pattern (7 entries): column starts, then row indices.
struct Tridiagonal {
  std::vector<int> outer{0, 2, 5, 7};
  std::vector<int> inner{0, 1, 0, 1, 2, 1, 2};
};

}  // namespace

TEST(FloatSystem, KeepsTheEntriesOfExactUnknownsInDoubleAndRoundsTheRest) {
  auto pattern = std::make_shared<Tridiagonal>();
  const std::vector<uint8_t> exact{0, 0, 1};  // unknown 2: its row and column are exact
  FloatSystem a(3, pattern->outer.data(), pattern->inner.data(), exact);
  a.keepPatternAlive(pattern);
  ASSERT_EQ(a.rows(), 3);
  ASSERT_EQ(a.nonZeros(), 7);
  EXPECT_EQ(a.exactCount(), 3);  // (2, 1), (1, 2) and (2, 2)
  const double third = 1.0 / 3.0;
  for (int64_t e = 0; e < 7; ++e) a.set(e, third * static_cast<double>(e + 1));
  for (int u = 0; u < 3; ++u) a.setRowSum(u, third * u);
  for (int u = 0; u < 3; ++u)
    for (int e = pattern->outer[u]; e < pattern->outer[u + 1]; ++e) {
      const bool expected = exact[static_cast<size_t>(u)] || exact[pattern->inner[e]];
      EXPECT_EQ(a.exact(e), expected) << "entry " << e;
      const double value = third * static_cast<double>(e + 1);
      EXPECT_EQ(a.value(e), expected ? value : static_cast<double>(static_cast<float>(value)))
          << "entry " << e;
    }
  for (int u = 0; u < 3; ++u) EXPECT_EQ(a.rowSums()[u], static_cast<float>(third * u));
  // Column starts and row indices, rounded values, row sums, one word of marks with its rank,
  // three exact values.
  EXPECT_EQ(a.storageBytes(), (4 + 7) * 4 + 7 * 4 + 3 * 4 + 8 + 4 + 3 * 8);

  FloatSystem moved = std::move(a);
  EXPECT_EQ(moved.nonZeros(), 7);
  EXPECT_EQ(moved.value(6), third * 7.0);
  EXPECT_EQ(a.rows(), 0);  // NOLINT(bugprone-use-after-move): a moved-from system is empty
  EXPECT_EQ(a.nonZeros(), 0);
  EXPECT_TRUE(a.rowSums().empty());
}

TEST(FloatSystem, RefusesSizesThatDisagree) {
  Tridiagonal pattern;
  EXPECT_THROW(FloatSystem(3, pattern.outer.data(), pattern.inner.data(), std::vector<uint8_t>(2)),
               InvalidInputError);
  EXPECT_THROW(FloatSystem(3, nullptr, nullptr, std::vector<uint8_t>(3)), InvalidInputError);
  const FloatSystem empty(0, nullptr, nullptr, {});
  EXPECT_EQ(empty.nonZeros(), 0);
  EXPECT_EQ(empty.outer()[0], 0);  // column starts to read, as an empty Eigen matrix has
  EXPECT_EQ(FloatSystem().outer()[0], 0);
}
