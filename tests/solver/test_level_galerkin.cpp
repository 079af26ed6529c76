// Solver tests: A^1 formed from level 0's own data (stencils and boundary rows) equals the Galerkin
// product of the matrix they came from, so the set-up can free A^0 before forming A^1.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <span>
#include <vector>

#include "solver/level_system.h"
#include "synthetic_problem.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/galerkin.h"
#include "texgrad/solver/grid_hierarchy.h"
#include "texgrad/solver/multigrid_solver.h"

using namespace texgrad;

namespace {

/// Bound on double rounding in a sum, relative to the sum of the magnitudes of its terms.
constexpr double kSumRounding = 1e-14;

/// A^0 with the couplings between footprint-interior diagonal neighbours (u, v) removed where
/// (u + v) % 3 == 0, and every such coupling with (u + v) % 3 == 1 stored as an explicit zero:
/// interior rows whose pattern is not the full 3 x 3 lattice neighbourhood, and rows with
/// stored zeros, which rows read back from the stencils must reproduce.
Eigen::SparseMatrix<double> thinned(const Eigen::SparseMatrix<double>& a, const GridLevel& level) {
  Eigen::SparseMatrix<double> out = a;
  for (int v = 0; v < out.outerSize(); ++v)
    for (Eigen::SparseMatrix<double>::InnerIterator it(out, v); it; ++it) {
      const int u = static_cast<int>(it.row());
      const LatticePoint p = level.point(u), q = level.point(v);
      const bool diagonal = p.box == q.box && std::abs(p.x - q.x) == 1 && std::abs(p.y - q.y) == 1;
      if (!diagonal || !level.footprintInterior[static_cast<size_t>(u)] ||
          !level.footprintInterior[static_cast<size_t>(v)] || (u + v) % 3 == 2)
        continue;
      it.valueRef() = (u + v) % 3 == 0 ? std::numeric_limits<double>::quiet_NaN() : 0.0;
    }
  out.prune([](Eigen::Index, Eigen::Index, double value) { return !std::isnan(value); });
  return out;
}

/// Per slot of level 0: the sum of A's row rounded to T, as the multigrid set-up stores it.
template <typename T>
std::vector<T> rowSumsOf(const GridLevel& fine, const Eigen::SparseMatrix<double>& a) {
  const Eigen::VectorXd sums = a * Eigen::VectorXd::Ones(a.cols());
  std::vector<T> out(static_cast<size_t>(fine.slotCount), T(0));
  for (int u = 0; u < fine.unknownCount(); ++u)
    out[static_cast<size_t>(fine.slotOfUnknown[static_cast<size_t>(u)])] = static_cast<T>(sums(u));
  return out;
}

/// Level 0 classified from `a` and its boundary data assigned, as the multigrid set-up does
/// before the stencils.
detail::LevelSystem boundaryAssigned(const GridLevel& fine, const Eigen::SparseMatrix<double>& a) {
  detail::LevelSystem system;
  detail::classifyLevel(fine, a, MultigridOptions().weakRowReach, system);
  detail::assignBoundary(fine, a, system);
  detail::factoriseBoundary(fine, system);
  return system;
}

/// Level 0's data assigned from `a` as the multigrid set-up does, then A^1 from them (with the
/// shortcut for interior columns unless `interiorShortcut` is false).
template <typename T>
Eigen::SparseMatrix<double> coarseFromLevelData(const GridHierarchy& h,
                                                const Eigen::SparseMatrix<double>& a,
                                                bool interiorShortcut = true) {
  const GridLevel& fine = h.level(0);
  const detail::LevelSystem system = boundaryAssigned(fine, a);
  PageArray<T> stencils;
  detail::assignStencils<T>(fine, a, system, stencils);
  EXPECT_GT(system.interiorCount(), 0);
  EXPECT_GT(system.boundaryCount(), 0);
  return detail::galerkinFromLevel<T>(fine, system,
                                      std::span<const T>(stencils.data(), stencils.size()),
                                      rowSumsOf<T>(fine, a), h.level(1), interiorShortcut);
}

/// True if a and b hold the same entries, bit for bit.
bool sameBits(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
  const auto n = static_cast<size_t>(a.nonZeros());
  return a.rows() == b.rows() && a.cols() == b.cols() && a.nonZeros() == b.nonZeros() &&
         std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1, b.outerIndexPtr()) &&
         std::equal(a.innerIndexPtr(), a.innerIndexPtr() + n, b.innerIndexPtr()) &&
         std::memcmp(a.valuePtr(), b.valuePtr(), n * sizeof(double)) == 0;
}

/// Expects c to have reference's pattern and, per column j, |c_ij - r_ij| <= tolerance *
/// max_i |r_ij|; returns the largest such relative difference.
double expectSameProduct(const Eigen::SparseMatrix<double>& c,
                         const Eigen::SparseMatrix<double>& reference, double tolerance) {
  EXPECT_EQ(c.rows(), reference.rows());
  EXPECT_EQ(c.nonZeros(), reference.nonZeros());
  if (c.nonZeros() != reference.nonZeros() || c.cols() != reference.cols()) return 1.0;
  double largest = 0.0;
  for (Eigen::Index j = 0; j < c.cols(); ++j) {
    const int begin = reference.outerIndexPtr()[j], end = reference.outerIndexPtr()[j + 1];
    EXPECT_EQ(c.outerIndexPtr()[j + 1], end) << "column " << j;
    double scale = 0.0;
    for (int e = begin; e < end; ++e) scale = std::max(scale, std::abs(reference.valuePtr()[e]));
    for (int e = begin; e < end; ++e) {
      EXPECT_EQ(c.innerIndexPtr()[e], reference.innerIndexPtr()[e]) << "column " << j;
      const double relative = std::abs(c.valuePtr()[e] - reference.valuePtr()[e]) / scale;
      largest = std::max(largest, relative);
      EXPECT_LE(relative, tolerance) << "entry (" << c.innerIndexPtr()[e] << ", " << j << ")";
    }
  }
  return largest;
}

}  // namespace

TEST(LevelGalerkin, CoarseOperatorFromLevelDataEqualsTheProductOfA0) {
  // Three charts with seams (boundary rows with far-away entries), partial cells (boundary
  // texels) and, in the thinned variant, interior rows with absent and stored-zero neighbours.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  ASSERT_GE(h.levelCount(), 2);
  const Eigen::SparseMatrix<double> pt = h.prolongation(0).transpose();
  for (const bool thin : {false, true})
    for (const double alpha : {1e4, 1e-2}) {
      SCOPED_TRACE(::testing::Message() << "alpha " << alpha << (thin ? ", thinned" : ""));
      const Eigen::SparseMatrix<double> full = p.system(alpha);
      const Eigen::SparseMatrix<double> a = thin ? thinned(full, h.level(0)) : full;
      if (thin) {
        ASSERT_LT(a.nonZeros(), full.nonZeros());
      }
      const Eigen::SparseMatrix<double> reference = galerkinProduct(a, h.level(0), h.level(1));
      // Double stencils hold A^0's values: only the order of the sums differs.
      EXPECT_LE(expectSameProduct(coarseFromLevelData<double>(h, a), reference, 1e-13), 1e-13);
      // Float stencils round each interior coupling once (relative 2^-24); a coarse entry sums
      // a few dozen such terms, none much larger than the column's largest (seen: 3e-8).
      const Eigen::SparseMatrix<double> c = coarseFromLevelData<float>(h, a);
      const double floatError =
          expectSameProduct(c, reference, 2.0 * std::numeric_limits<float>::epsilon());
      EXPECT_GT(floatError, 0.0);  // the float route really read the float stencils
      // Its row sums are Pᵀ (A^0 1) to the float rounding of A^0's row sums themselves, not of
      // the couplings: the screening part (alpha M 1, as S 1 = 0) survives the rounding.
      const Eigen::VectorXd ones = Eigen::VectorXd::Ones(c.cols());
      const Eigen::VectorXd sums = c * ones, expected = reference * ones;
      const Eigen::VectorXd bound = pt * (a * Eigen::VectorXd::Ones(a.cols())).cwiseAbs() *
                                    (2.0 * std::numeric_limits<float>::epsilon());
      const Eigen::VectorXd magnitudes = pt * (a.cwiseAbs() * Eigen::VectorXd::Ones(a.cols()));
      for (Eigen::Index k = 0; k < c.cols(); ++k)
        EXPECT_LE(std::abs(sums(k) - expected(k)), bound(k) + kSumRounding * magnitudes(k))
            << "row " << k << ": " << sums(k) << " against " << expected(k);
      // Symmetric like A^1 (the level-1 split reads its columns as rows, CHOLMOD one triangle):
      // a boundary row rounds its couplings to interior texels as their stencils do.
      const Eigen::SparseMatrix<double> asymmetry = c - Eigen::SparseMatrix<double>(c.transpose());
      for (Eigen::Index k = 0; k < asymmetry.outerSize(); ++k)
        for (Eigen::SparseMatrix<double>::InnerIterator it(asymmetry, k); it; ++it)
          EXPECT_LE(std::abs(it.value()), kSumRounding * magnitudes(k))
              << "entries (" << it.row() << ", " << k << ") and (" << k << ", " << it.row() << ")";
    }
}

TEST(LevelGalerkin, InteriorColumnShortcutGivesTheGeneralPathsBits) {
  // The shortcut for coarse columns whose children all have interior rows sums in the general
  // path's order: the same bits, with and without absent neighbours, in float and double.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  for (const bool thin : {false, true})
    for (const double alpha : {1e4, 1e-2}) {
      SCOPED_TRACE(::testing::Message() << "alpha " << alpha << (thin ? ", thinned" : ""));
      const Eigen::SparseMatrix<double> full = p.system(alpha);
      const Eigen::SparseMatrix<double> a = thin ? thinned(full, h.level(0)) : full;
      EXPECT_TRUE(sameBits(coarseFromLevelData<float>(h, a, true),
                           coarseFromLevelData<float>(h, a, false)));
      EXPECT_TRUE(sameBits(coarseFromLevelData<double>(h, a, true),
                           coarseFromLevelData<double>(h, a, false)));
    }
}

TEST(LevelGalerkin, BoundaryIndexCountsTheBoundaryUnknownsBeforeEachUnknown) {
  // Across word boundaries (64 unknowns a word): sizes around them, all-boundary, none, mixed.
  std::srand(7);
  for (const size_t n : {size_t(0), size_t(1), size_t(63), size_t(64), size_t(65), size_t(300)})
    for (const int pattern : {0, 1, 2}) {
      std::vector<uint8_t> interior(n);
      for (uint8_t& i : interior)
        i = static_cast<uint8_t>(pattern == 2 ? std::rand() % 2 : pattern);
      detail::BoundaryIndex index;
      index.assign(interior);
      int before = 0;
      for (size_t u = 0; u < n; ++u) {
        const int v = static_cast<int>(u);
        EXPECT_EQ(index.contains(v), interior[u] == 0) << n << " unknowns, unknown " << u;
        EXPECT_EQ(index.rank(v), before) << n << " unknowns, unknown " << u;
        before += interior[u] == 0;
      }
    }
}

TEST(LevelGalerkin, BoundaryFactorisationFromTheBoundaryRowsIsThatOfA0sBoundaryBlock) {
  // factoriseBoundary reads A_bb from the boundary rows (A^0 may be gone by then): it must
  // factorise A^0 restricted to the boundary unknowns, seams' far-away entries included.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  const GridLevel& fine = h.level(0);
  const Eigen::SparseMatrix<double> a = p.system(1e-2);
  const detail::LevelSystem system = boundaryAssigned(fine, a);
  const int nb = system.boundaryCount();
  ASSERT_GT(nb, 0);
  std::vector<int> unknownOfBoundary(static_cast<size_t>(nb));
  for (int j = 0; j < nb; ++j) {
    const int32_t slot = system.boundarySlots[static_cast<size_t>(j)];
    const int u = fine.unknownOfSlot[static_cast<size_t>(slot)];
    unknownOfBoundary[static_cast<size_t>(j)] = u;
    EXPECT_TRUE(system.boundaryIndex.contains(u));
    EXPECT_EQ(system.boundaryIndex.rank(u), j);
  }
  Eigen::MatrixXd dense(nb, nb);
  for (int i = 0; i < nb; ++i)
    for (int j = 0; j < nb; ++j)
      dense(i, j) = a.coeff(unknownOfBoundary[static_cast<size_t>(i)],
                            unknownOfBoundary[static_cast<size_t>(j)]);
  const Eigen::MatrixXd y = Eigen::MatrixXd::Random(nb, 2);
  const Eigen::MatrixXd x = system.boundarySolver.solve(y);
  EXPECT_LT((dense * x - y).norm() / y.norm(), 1e-12);
}

TEST(LevelGalerkin, SolverKeepsTheCoarsePatternOfInitForInteriorRowsOfAnyPattern) {
  // init forms A^1 from A^0's pattern, update from level 0's stencils: the pattern of A^1 must be
  // the same (update throws otherwise), also when interior rows lack lattice neighbours or store
  // zeros, and equal to the Galerkin product's.
  const test::SyntheticProblem p = test::multiChartProblem(12);
  MultigridOptions o;
  o.minCoarseUnknowns = 16;
  MultigridSolver<float> solver(o);
  solver.init(p.grid, p.system(1.0));
  GridHierarchy h = solver.hierarchy();
  h.restoreUnknownOfSlot();  // a solver frees it after each set-up
  const Eigen::SparseMatrix<double> a = thinned(p.system(1.0), h.level(0));
  ASSERT_LT(a.nonZeros(), p.system(1.0).nonZeros());
  solver.init(p.grid, a);
  EXPECT_NO_THROW(solver.update(a));
  const Eigen::SparseMatrix<double> a1 = galerkinProduct(a, h.level(0), h.level(1));
  EXPECT_EQ(solver.levelInfo()[1].nonZeros, a1.nonZeros());
  Eigen::SparseMatrix<double> handed = a;
  EXPECT_NO_THROW(solver.update(std::move(handed)));
  EXPECT_EQ(solver.levelInfo()[1].nonZeros, a1.nonZeros());
}

TEST(LevelGalerkin, StencilsNeverReadAColumnTheyDeclaredConsumed) {
  // The multigrid releases A^0's pages as assignStencils declares columns consumed; here those
  // columns become NaN instead, so a later read would show in the stencils.
  const test::SyntheticProblem p = test::multiChartProblem(80);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  const GridLevel& fine = h.level(0);
  const Eigen::SparseMatrix<double> a = p.system(0.01);
  const detail::LevelSystem system = boundaryAssigned(fine, a);
  PageArray<float> expected;
  detail::assignStencils<float>(fine, a, system, expected);
  Eigen::SparseMatrix<double> poisoned = a;
  std::vector<int> declared;
  PageArray<float> stencils;
  detail::assignStencils<float>(fine, poisoned, system, stencils, true, [&](int u) {
    declared.push_back(u);
    std::fill(poisoned.valuePtr(), poisoned.valuePtr() + poisoned.outerIndexPtr()[u],
              std::numeric_limits<double>::quiet_NaN());
  });
  ASSERT_GT(declared.size(), 2u) << "several bands";
  EXPECT_TRUE(std::is_sorted(declared.begin(), declared.end()));
  EXPECT_EQ(declared.back(), fine.unknownCount()) << "every column, in the end";
  ASSERT_EQ(stencils.size(), expected.size());
  EXPECT_TRUE(std::equal(stencils.data(), stencils.data() + stencils.size(), expected.data()));
}

TEST(LevelGalerkin, EachRunReadsItsRowsOfAFromCouplingsStoredOnce) {
  // Every coupling is stored once, by the slot whose forward half it lies in; the weights a run
  // reads (runStencil) must still be each interior slot's whole row of A, absent entries as
  // zeros (thinned), 1 / centre as the mask, and a zero mask on the other visited slots.
  const test::SyntheticProblem p = test::multiChartProblem(24);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  const GridLevel& fine = h.level(0);
  for (const Eigen::SparseMatrix<double>& a : {p.system(0.01), thinned(p.system(0.01), fine)}) {
    const detail::LevelSystem system = boundaryAssigned(fine, a);
    PageArray<double> stencils;
    detail::assignStencils<double>(fine, a, system, stencils);
    int checked = 0;
    for (size_t r = 0; r < system.boxRows.size(); ++r) {
      const detail::SlotRow& row = system.boxRows[r];
      for (int q = 0; q < 2; ++q) {
        if (row.runLength(q) <= 0) continue;
        const auto run = detail::runStencil(stencils.data(), system.boxRows[r - 1], row, q);
        for (int64_t i = 0; i < row.runLength(q); ++i) {
          const int64_t s = row.begin + q + 2 * i;
          if (system.kind[static_cast<size_t>(s)] != SlotKind::Interior) {
            EXPECT_EQ(run.inverse[i], 0.0) << "slot " << s;
            continue;
          }
          const auto expected =
              detail::stencilRow(fine, a, fine.unknownOfSlot[static_cast<size_t>(s)]);
          for (int k = 0; k < 9; ++k)
            EXPECT_DOUBLE_EQ(run.w[k][i], expected[static_cast<size_t>(k)])
                << "slot " << s << ", weight " << k;
          EXPECT_DOUBLE_EQ(run.inverse[i], 1.0 / expected[4]) << "slot " << s;
          ++checked;
        }
      }
    }
    EXPECT_EQ(checked, system.interiorCount());
  }
}

TEST(LevelGalerkin, StencilsRefuseARowThatIsNotTheClassifiedStencil) {
  // An interior row with an entry beyond its 3 x 3 neighbourhood (a matrix of another pattern
  // handed to an update) is an error, not a write into some other slot's coefficients.
  const test::SyntheticProblem p = test::multiChartProblem(24);
  const GridHierarchy h = GridHierarchy::build(p.grid, 4, 16);
  const GridLevel& fine = h.level(0);
  const Eigen::SparseMatrix<double> a = p.system(0.01);
  const detail::LevelSystem system = boundaryAssigned(fine, a);
  int u = 0;
  while (system.kind[static_cast<size_t>(fine.slotOfUnknown[static_cast<size_t>(u)])] !=
         SlotKind::Interior)
    ++u;
  const int far = fine.unknownCount() - 1;
  ASSERT_GT(std::abs(fine.point(far).y - fine.point(u).y), 1);
  Eigen::SparseMatrix<double> other = a;
  other.coeffRef(u, far) = 0.0;
  other.coeffRef(far, u) = 0.0;
  other.makeCompressed();
  PageArray<float> stencils;
  EXPECT_THROW(detail::assignStencils<float>(fine, other, system, stencils), InvalidInputError);
  EXPECT_NO_THROW(detail::assignStencils<float>(fine, a, system, stencils));
}
