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

/// Pᵀ A P with every sum in the order galerkinProduct documents, by dense accumulators: (A P)_{:,j}
/// from P's column j by increasing row, its entries in the order first touched; then Pᵀ of that.
Eigen::SparseMatrix<double> firstTouchProduct(const Eigen::SparseMatrix<double>& a,
                                              const Eigen::SparseMatrix<double>& p) {
  const Eigen::SparseMatrix<double, Eigen::RowMajor> pRows = p;
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < p.cols(); ++j) {
    std::vector<double> fine(static_cast<size_t>(a.rows()), 0.0);
    std::vector<double> coarse(static_cast<size_t>(p.cols()), 0.0);
    std::vector<int> fineOrder, coarseRows;
    for (Eigen::SparseMatrix<double>::InnerIterator pj(p, j); pj; ++pj)
      for (Eigen::SparseMatrix<double>::InnerIterator ar(a, pj.row()); ar; ++ar) {
        const auto r = static_cast<size_t>(ar.row());
        if (std::find(fineOrder.begin(), fineOrder.end(), ar.row()) == fineOrder.end())
          fineOrder.push_back(static_cast<int>(ar.row()));
        fine[r] += ar.value() * pj.value();
      }
    for (int r : fineOrder)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator pr(pRows, r); pr; ++pr) {
        const auto k = static_cast<size_t>(pr.col());
        if (std::find(coarseRows.begin(), coarseRows.end(), pr.col()) == coarseRows.end())
          coarseRows.push_back(static_cast<int>(pr.col()));
        coarse[k] += pr.value() * fine[static_cast<size_t>(r)];
      }
    for (int k : coarseRows) entries.emplace_back(k, j, coarse[static_cast<size_t>(k)]);
  }
  Eigen::SparseMatrix<double> c(p.cols(), p.cols());
  c.setFromTriplets(entries.begin(), entries.end());  // one triplet per entry: no sums
  return c;
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

TEST(Galerkin, SumsInTheOrderFirstTouchedWhenAColumnReachesEveryRow) {
  // A column of P over every fine row: its accumulators outgrow their first tables; every sum
  // still comes in the documented order, so each value is the same bits as the dense reference's.
  std::mt19937 rng(5);
  const Eigen::SparseMatrix<double> a = randomSparse(3000, 3000, 12000, rng);
  Eigen::SparseMatrix<double> p = randomSparse(3000, 40, 300, rng);
  for (int r = 0; r < 3000; ++r) p.coeffRef(r, 7) = 1.0 + r % 5;
  p.makeCompressed();
  const Eigen::SparseMatrix<double> reference = firstTouchProduct(a, p);
  const Eigen::SparseMatrix<double> c = galerkinProduct(a, p);
  EXPECT_GT(c.col(7).nonZeros(), 32);  // more than the first coarse table holds
  ASSERT_EQ(c.nonZeros(), reference.nonZeros());
  EXPECT_TRUE(
      std::equal(c.outerIndexPtr(), c.outerIndexPtr() + c.cols() + 1, reference.outerIndexPtr()));
  EXPECT_TRUE(
      std::equal(c.innerIndexPtr(), c.innerIndexPtr() + c.nonZeros(), reference.innerIndexPtr()));
  EXPECT_TRUE(std::equal(c.valuePtr(), c.valuePtr() + c.nonZeros(), reference.valuePtr()));
  const Eigen::SparseMatrix<double> product = Eigen::SparseMatrix<double>(p.transpose()) * a * p;
  EXPECT_LT(largestDifference(c, product), 1e-9);
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
