// Galerkin products: equal to the reference sparse product, with a structural pattern.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "synthetic_problem.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/galerkin.h"
#include "texgrad/solver/grid_hierarchy.h"

using namespace texgrad;

namespace {

Eigen::SparseMatrix<double> randomSparse(int rows, int cols, int entries, std::mt19937& rng) {
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_int_distribution<int> row(0, rows - 1), col(0, cols - 1);
  std::vector<Eigen::Triplet<double>> t;
  for (int k = 0; k < entries; ++k) t.emplace_back(row(rng), col(rng), value(rng));
  Eigen::SparseMatrix<double> m(rows, cols);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

/// The largest absolute entry of c - reference.
double largestDifference(const Eigen::SparseMatrix<double>& c,
                         const Eigen::SparseMatrix<double>& reference) {
  const Eigen::SparseMatrix<double> difference = c - reference;
  double largest = 0.0;
  for (Eigen::Index k = 0; k < difference.nonZeros(); ++k)
    largest = std::max(largest, std::abs(difference.valuePtr()[k]));
  return largest;
}

}  // namespace

TEST(Galerkin, EqualsTheReferenceProduct) {
  std::mt19937 rng(3);
  // Enough coarse columns for several parallel tasks.
  const Eigen::SparseMatrix<double> a = randomSparse(6000, 6000, 36000, rng);
  const Eigen::SparseMatrix<double> p = randomSparse(6000, 5000, 15000, rng);
  const Eigen::SparseMatrix<double> reference = Eigen::SparseMatrix<double>(p.transpose()) * a * p;
  const Eigen::SparseMatrix<double> c = galerkinProduct(a, p);
  ASSERT_EQ(c.rows(), 5000);
  ASSERT_EQ(c.cols(), 5000);
  const double largest = largestDifference(c, reference);
  EXPECT_GT(reference.nonZeros(), 1000);
  EXPECT_LT(largest, 1e-12);
  EXPECT_TRUE(c.isCompressed());
}

TEST(Galerkin, EqualsTheReferenceProductWhenAColumnReachesEveryRow) {
  // A column of P over every fine row: its accumulators outgrow their first tables many times.
  std::mt19937 rng(5);
  const Eigen::SparseMatrix<double> a = randomSparse(3000, 3000, 12000, rng);
  Eigen::SparseMatrix<double> p = randomSparse(3000, 40, 300, rng);
  for (int r = 0; r < 3000; ++r) p.coeffRef(r, 7) = 1.0 + r % 5;
  p.makeCompressed();
  const Eigen::SparseMatrix<double> reference = Eigen::SparseMatrix<double>(p.transpose()) * a * p;
  const Eigen::SparseMatrix<double> c = galerkinProduct(a, p);
  const double largest = largestDifference(c, reference);
  EXPECT_EQ(c.col(7).nonZeros(), 40);
  EXPECT_LT(largest, 1e-9);
}

TEST(Galerkin, KeepsStructuralZerosSoThePatternIgnoresValues) {
  // A = [1 0; 0 1] with an explicitly stored zero at (0, 1) and (1, 0); P = I.
  Eigen::SparseMatrix<double> a(2, 2);
  a.insert(0, 0) = 1.0;
  a.insert(1, 0) = 0.0;
  a.insert(0, 1) = 0.0;
  a.insert(1, 1) = 1.0;
  a.makeCompressed();
  Eigen::SparseMatrix<double> p(2, 2);
  p.setIdentity();
  const Eigen::SparseMatrix<double> c = galerkinProduct(a, p);
  EXPECT_EQ(c.nonZeros(), 4);
}

TEST(Galerkin, RejectsAMatrixOfTheWrongSize) {
  const test::SyntheticProblem p = test::squareProblem(16);
  const test::SyntheticProblem q = test::squareProblem(17);
  const GridHierarchy h = GridHierarchy::build(p.grid, 2, 16);
  ASSERT_GE(h.levelCount(), 2);
  EXPECT_THROW(galerkinProduct(q.system(1.0), h.level(0), h.level(1)), InvalidInputError);
  EXPECT_THROW(galerkinProduct(q.system(1.0), h.prolongation(0)), InvalidInputError);
}

TEST(Galerkin, LatticeProlongationMatchesTheStoredOneBitForBit) {
  // Three charts, several levels: every coarse column sums the same entries in the same order.
  const test::SyntheticProblem p = test::multiChartProblem(24);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  ASSERT_GE(h.levelCount(), 4);
  Eigen::SparseMatrix<double> a = p.system(3.0);
  for (int l = 0; l + 1 < h.levelCount(); ++l) {
    const Eigen::SparseMatrix<double> stored = galerkinProduct(a, h.prolongation(l));
    const Eigen::SparseMatrix<double> lattice = galerkinProduct(a, h.level(l), h.level(l + 1));
    ASSERT_EQ(lattice.rows(), stored.rows());
    ASSERT_EQ(lattice.nonZeros(), stored.nonZeros()) << "level " << l;
    EXPECT_TRUE(std::equal(stored.outerIndexPtr(), stored.outerIndexPtr() + stored.cols() + 1,
                           lattice.outerIndexPtr()));
    EXPECT_TRUE(std::equal(stored.innerIndexPtr(), stored.innerIndexPtr() + stored.nonZeros(),
                           lattice.innerIndexPtr()));
    EXPECT_TRUE(
        std::equal(stored.valuePtr(), stored.valuePtr() + stored.nonZeros(), lattice.valuePtr()))
        << "level " << l;
    a = stored;
  }
}
