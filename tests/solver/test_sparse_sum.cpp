// SparseSum: the screened system alpha M + S read from M and S without being formed, and a third
// matrix within their pattern added through its bit marks.
#include <gtest/gtest.h>

#include "synthetic_problem.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/galerkin.h"
#include "texgrad/solver/grid_hierarchy.h"
#include "texgrad/solver/sparse_sum.h"

using namespace texgrad;

namespace {

/// Largest |a - b| over the entries of two matrices of one pattern; -1 if the patterns differ.
double largestDifference(const Eigen::SparseMatrix<double>& a,
                         const Eigen::SparseMatrix<double>& b) {
  if (a.rows() != b.rows() || a.nonZeros() != b.nonZeros()) return -1.0;
  for (Eigen::Index k = 0; k <= a.outerSize(); ++k)
    if (a.outerIndexPtr()[k] != b.outerIndexPtr()[k]) return -1.0;
  double largest = 0.0;
  for (Eigen::Index e = 0; e < a.nonZeros(); ++e) {
    if (a.innerIndexPtr()[e] != b.innerIndexPtr()[e]) return -1.0;
    largest = std::max(largest, std::abs(a.valuePtr()[e] - b.valuePtr()[e]));
  }
  return largest;
}

}  // namespace

TEST(SparseSum, ReadsTheSameEntriesAsTheFormedSum) {
  const test::SyntheticProblem p = test::multiChartProblem(8);
  const Eigen::SparseMatrix<double> formed = p.system(1e3);
  const SparseSum sum(1e3, p.mass, 1.0, p.stiffness);
  EXPECT_EQ(sum.rows(), formed.rows());
  EXPECT_EQ(sum.nonZeros(), formed.nonZeros());
  EXPECT_EQ(largestDifference(sum.toMatrix(), formed), 0.0);
  // A Map over M's pattern with other values (how TexelOperators hands out S) binds too.
  const Eigen::Map<const Eigen::SparseMatrix<double>> view(
      p.stiffness.rows(), p.stiffness.cols(), p.stiffness.nonZeros(), p.mass.outerIndexPtr(),
      p.mass.innerIndexPtr(), p.stiffness.valuePtr());
  EXPECT_EQ(largestDifference(SparseSum(2.0, p.mass, 1.0, view).toMatrix(), p.system(2.0)), 0.0);
  // One matrix: its own entries.
  EXPECT_EQ(largestDifference(SparseSum(p.stiffness).toMatrix(), p.stiffness), 0.0);
}

TEST(SparseSum, RejectsOperandsItCannotReadTogether) {
  const test::SyntheticProblem p = test::squareProblem(6);
  const test::SyntheticProblem q = test::squareProblem(7);
  EXPECT_THROW(SparseSum(1.0, p.mass, 1.0, q.stiffness), InvalidInputError);  // sizes differ
  // Same row count, fewer columns: its column starts must not be read past their end.
  const Eigen::SparseMatrix<double> narrow = p.stiffness.leftCols(p.stiffness.cols() - 1);
  EXPECT_THROW(SparseSum(1.0, p.mass, 1.0, narrow), InvalidInputError);
  Eigen::SparseMatrix<double> extra = p.stiffness;
  extra.coeffRef(0, extra.rows() - 1) = 1.0;  // an entry M does not have
  extra.makeCompressed();
  EXPECT_THROW(SparseSum(1.0, p.mass, 1.0, extra), InvalidInputError);
  Eigen::SparseMatrix<double> loose = p.stiffness;
  loose.uncompress();
  EXPECT_THROW(SparseSum(1.0, p.mass, 1.0, loose), InvalidInputError);
  EXPECT_THROW(SparseSum{loose}, InvalidInputError);
  const Eigen::SparseMatrix<double> wide(3, 4);
  EXPECT_THROW(SparseSum{wide}, InvalidInputError);
}

TEST(SparseSum, AddsAMatrixWithinThePatternAsAddingItToTheFormedSumDoes) {
  const test::SyntheticProblem p = test::multiChartProblem(8);
  // Z on every 7th entry of the pattern (entries in most 64-entry words of the bit marks, some
  // words with several) and on every entry of one column, with its own values.
  Eigen::SparseMatrix<double> z(p.mass.rows(), p.mass.cols());
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index j = 0; j < p.mass.outerSize(); ++j)
    for (int e = p.mass.outerIndexPtr()[j]; e < p.mass.outerIndexPtr()[j + 1]; ++e)
      if (e % 7 == 3 || j == 5)
        entries.emplace_back(p.mass.innerIndexPtr()[e], static_cast<int>(j), 0.25 + e);
  z.setFromTriplets(entries.begin(), entries.end());
  ASSERT_GT(z.nonZeros(), 64);
  Eigen::SparseMatrix<double> formed = p.system(3.0);  // 3 M + S: add Z's entries in place
  for (Eigen::Index j = 0; j < z.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(z, j); it; ++it)
      formed.coeffRef(it.row(), j) += it.value();
  const SparseSum sum(3.0, p.mass, 1.0, p.stiffness, z);
  EXPECT_EQ(sum.nonZeros(), formed.nonZeros());
  EXPECT_EQ(largestDifference(sum.toMatrix(), formed), 0.0);

  Eigen::SparseMatrix<double> outside(p.mass.rows(), p.mass.cols());
  outside.insert(0, p.mass.rows() - 1) = 1.0;  // an entry M does not have
  EXPECT_THROW(SparseSum(3.0, p.mass, 1.0, p.stiffness, outside), InvalidInputError);
  const Eigen::SparseMatrix<double> small(3, 3);
  EXPECT_THROW(SparseSum(3.0, p.mass, 1.0, p.stiffness, small), InvalidInputError);
}

TEST(SparseSum, GalerkinProductEqualsTheOneOfTheFormedSum) {
  const test::SyntheticProblem p = test::multiChartProblem(10);
  const GridHierarchy h = GridHierarchy::build(p.grid, 2, 16);
  ASSERT_GE(h.levelCount(), 2);
  const Eigen::SparseMatrix<double> fromSum =
      galerkinProduct(SparseSum(1e4, p.mass, 1.0, p.stiffness), h.level(0), h.level(1));
  const Eigen::SparseMatrix<double> fromMatrix =
      galerkinProduct(p.system(1e4), h.level(0), h.level(1));
  EXPECT_GT(fromSum.nonZeros(), 0);
  EXPECT_EQ(largestDifference(fromSum, fromMatrix), 0.0);
}
