// Solver module (private): Galerkin coarse operators by sparse accumulation, one coarse column at
// a time (the classic row-by-row RAP, transposed for column-major storage).
#include "texgrad/solver/galerkin.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "solver/grid_kernels.h"
#include "solver/level_system.h"
#include "texgrad/core/error.h"
#include "texgrad/core/page_allocator.h"

namespace texgrad {
namespace {

using Sparse = Eigen::SparseMatrix<double>;
using RowMajor = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// Coarse columns per task (fixed, so the split does not depend on the thread count).
constexpr Eigen::Index kColumnsPerTask = 2048;

/// Sums of values by index for the few indices one column touches, in the order first touched,
/// by open addressing with linear probing in a table at most half full: sized by one column's
/// entries, not by the matrix's order, so a thread's accumulators stay small at any texture size
/// (dense ones over the fine unknowns held 12 bytes per fine unknown per thread, docs/memory.md).
class Accumulator {
 public:
  /// Adds v to the sum at index i (i >= 0: -1 marks an empty slot).
  void add(int i, double v) {
    size_t s = slotOf(i);
    while (keys_[s] != i) {
      if (keys_[s] < 0) {
        s = insert(i, s);
        break;
      }
      s = (s + 1) & mask_;
    }
    sums_[s] += v;
  }
  /// Calls f(index, sum) for each index touched since clear(), in the order first touched.
  template <typename F>
  void forEach(F&& f) const {
    for (size_t s : touched_) f(keys_[s], sums_[s]);
  }
  /// Forgets every sum.
  void clear() {
    for (size_t s : touched_) keys_[s] = -1;
    touched_.clear();
  }

 private:
  /// Fibonacci hashing: the top bits_ bits of i times 2^32 / phi.
  size_t slotOf(int i) const { return (static_cast<uint32_t>(i) * 2654435769u) >> (32 - bits_); }
  /// The first empty slot from i's own (i not in the table).
  size_t emptySlotFor(int i) const {
    size_t s = slotOf(i);
    while (keys_[s] >= 0) s = (s + 1) & mask_;
    return s;
  }
  /// Puts i, with a zero sum, in the empty slot s, or in a table twice as large if this one
  /// would be more than half full; returns its slot.
  size_t insert(int i, size_t s) {
    if (2 * (touched_.size() + 1) > keys_.size()) {
      grow();
      s = emptySlotFor(i);
    }
    keys_[s] = i;
    sums_[s] = 0.0;
    touched_.push_back(s);
    return s;
  }
  /// Doubles the table, keeping the touched order (out of line: add's loop stays small).
  [[gnu::noinline]] void grow() {
    const std::vector<int> keys = std::move(keys_);
    const std::vector<double> sums = std::move(sums_);
    std::vector<size_t> touched = std::move(touched_);
    ++bits_;
    keys_.assign(size_t(1) << bits_, -1);
    sums_.assign(keys_.size(), 0.0);
    mask_ = keys_.size() - 1;
    for (size_t& t : touched) {
      const size_t s = emptySlotFor(keys[t]);
      keys_[s] = keys[t];
      sums_[s] = sums[t];
      t = s;
    }
    touched_ = std::move(touched);
  }
  static constexpr int kFirstBits = 6;           ///< a first table of 64 slots holds most columns
  int bits_ = kFirstBits;                        ///< log2 of the table's size
  size_t mask_ = (size_t(1) << kFirstBits) - 1;  ///< the table's size - 1
  std::vector<int> keys_ = std::vector<int>(size_t(1) << kFirstBits, -1);  ///< -1: empty slot
  std::vector<double> sums_ = std::vector<double>(size_t(1) << kFirstBits, 0.0);
  std::vector<size_t> touched_;  ///< slots in the order first touched
};

/// One task's columns of the result, in compressed form with a local column pointer.
struct Block {
  std::vector<int> count;
  std::vector<int> inner;
  std::vector<double> values;
};

/// Frees a block's storage, letting the system drop its pages first: a block of the heap freed
/// in the middle of it would otherwise stay resident beside the result it was copied into.
void releaseBlock(Block& block) {
  detail::discardWholePages(block.inner.data(), block.inner.size() * sizeof(int));
  detail::discardWholePages(block.values.data(), block.values.size() * sizeof(double));
  block = Block();
}

struct Scratch {
  Accumulator fine, coarse;
  std::vector<std::pair<int, double>> column;  ///< (fine row, weight) of one column of P
  std::vector<std::pair<int, double>> sorted;  ///< one coarse column's entries by row
  Block block;  ///< the current task's columns, grown once per thread and copied out exactly
};

/// A column that galerkinColumns always forms itself.
struct NoShortcut {
  bool operator()(int, std::vector<std::pair<int, double>>&) const { return false; }
};

/// Pᵀ A P with A (fine x fine) given by its rows and P by its columns and rows: rowOf(r, f) calls
/// f(column, value) for the entries of row r of A, children(j, out) sets out to the (fine row,
/// weight) entries of column j of P by increasing row, parents(r, f) calls f(coarse column,
/// weight) for the entries of row r of P by increasing column. shortcut(j, out) may form column
/// j itself, (row, value) by increasing row, and return true.
template <typename Rows, typename Children, typename Parents, typename Shortcut = NoShortcut>
Sparse galerkinColumns(Rows rowOf, Eigen::Index nc, Children children, Parents parents,
                       Shortcut shortcut = {}) {
  const Eigen::Index tasks = (nc + kColumnsPerTask - 1) / kColumnsPerTask;
  std::vector<Block> blocks(static_cast<size_t>(tasks));
  tbb::enumerable_thread_specific<Scratch> scratch;
  tbb::parallel_for(Eigen::Index(0), tasks, [&](Eigen::Index t) {
    Scratch& s = scratch.local();
    Block& block = s.block;
    block.count.clear();
    block.inner.clear();
    block.values.clear();
    const int first = static_cast<int>(t * kColumnsPerTask);
    const int last = static_cast<int>(std::min(nc, t * kColumnsPerTask + kColumnsPerTask));
    for (int j = first; j < last; ++j) {
      s.sorted.clear();
      if (!shortcut(j, s.sorted)) {
        s.fine.clear();
        s.coarse.clear();
        children(j, s.column);
        for (const auto& [row, weight] : s.column)  // (A P)_{:, j}
          rowOf(row, [&, w = weight](int column, double value) { s.fine.add(column, value * w); });
        s.fine.forEach([&](int r, double sum) {  // (Pᵀ A P)_{:, j}
          parents(r, [&](int k, double weight) { s.coarse.add(k, weight * sum); });
        });
        s.coarse.forEach([&](int k, double sum) { s.sorted.emplace_back(k, sum); });
        std::sort(s.sorted.begin(), s.sorted.end(),
                  [](const auto& x, const auto& y) { return x.first < y.first; });
      }
      block.count.push_back(static_cast<int>(s.sorted.size()));
      for (const auto& [k, sum] : s.sorted) {
        block.inner.push_back(k);
        block.values.push_back(sum);
      }
    }
    // Exact-size copy: growth slack would otherwise stay allocated until the result is built.
    Block& out = blocks[static_cast<size_t>(t)];
    out.count.assign(block.count.begin(), block.count.end());
    out.inner.assign(block.inner.begin(), block.inner.end());
    out.values.assign(block.values.begin(), block.values.end());
  });
  scratch.clear();  // the threads' accumulators and blocks go before the result is allocated
  Sparse c(nc, nc);
  Eigen::Index nonZeros = 0;
  for (const Block& block : blocks) nonZeros += static_cast<Eigen::Index>(block.inner.size());
  c.resizeNonZeros(nonZeros);  // resident only as written, or where it reuses resident memory
  int* outer = c.outerIndexPtr();
  outer[0] = 0;
  Eigen::Index column = 0;
  for (const Block& block : blocks)
    for (int count : block.count) {
      outer[column + 1] = outer[column] + count;
      ++column;
    }
  // Each block is released once copied, so the result grows as the blocks shrink: A^1 is never
  // held twice.
  tbb::parallel_for(Eigen::Index(0), tasks, [&](Eigen::Index t) {
    Block& block = blocks[static_cast<size_t>(t)];
    const int offset = outer[t * kColumnsPerTask];
    std::copy(block.inner.begin(), block.inner.end(), c.innerIndexPtr() + offset);
    std::copy(block.values.begin(), block.values.end(), c.valuePtr() + offset);
    releaseBlock(block);
  });
  return c;
}

/// Row source of galerkinColumns for a SparseSum: column r of the symmetric A is its row r.
auto rowsOf(const SparseSum& a) {
  return [&a](int r, const auto& f) {
    for (int e = a.outer()[r]; e != a.outer()[r + 1]; ++e) f(a.inner()[e], a.value(e));
  };
}

/// Pᵀ A P for the bilinear prolongation P from `coarse` to `fine`, from the lattice positions
/// without storing P; rowOf gives the rows of A, shortcut may form a column (galerkinColumns).
template <typename Rows, typename Shortcut = NoShortcut>
Sparse latticeProduct(const GridLevel& fine, const GridLevel& coarse, Rows rowOf,
                      Shortcut shortcut = {}) {
  return galerkinColumns(
      rowOf, coarse.unknownCount(),
      [&](Eigen::Index j, std::vector<std::pair<int, double>>& out) {
        // The fine texels within one lattice step of coarse texel j's position, in its chart.
        out.clear();
        const LatticePoint p = coarse.point(static_cast<int>(j));
        const GridBox& box = fine.boxOfChartAt(coarse.boxes[static_cast<size_t>(p.box)].chart);
        const int x = p.x, y = p.y;
        for (int fy = 2 * y - 1; fy <= 2 * y + 1; ++fy)
          for (int fx = 2 * x - 1; fx <= 2 * x + 1; ++fx) {
            if (!box.contains(fx, fy)) continue;
            const int r = fine.unknownOfSlot[static_cast<size_t>(box.slot(fx, fy))];
            if (r >= 0)
              out.emplace_back(
                  r, detail::transferWeight<double>(fx, x) * detail::transferWeight<double>(fy, y));
          }
        std::sort(out.begin(), out.end());  // by fine index, as in P's column, for any numbering
      },
      [&](int r, const auto& add) {
        const LatticePoint p = fine.point(r);
        const GridBox& box = coarse.boxOfChartAt(fine.boxes[static_cast<size_t>(p.box)].chart);
        const LatticeParents px = latticeParents(p.x), py = latticeParents(p.y);
        for (int jy = 0; jy < py.count; ++jy)  // slot order = increasing coarse index
          for (int ix = 0; ix < px.count; ++ix) {
            const size_t x = static_cast<size_t>(ix), y = static_cast<size_t>(jy);
            add(coarse.unknownOfSlot[static_cast<size_t>(box.slot(px.index[x], py.index[y]))],
                px.weight[x] * py.weight[y]);
          }
      },
      shortcut);
}

/// Throws unless a is n x n with n = `fineUnknowns`.
void requireSquare(const SparseSum& a, Eigen::Index fineUnknowns) {
  if (a.rows() != fineUnknowns)
    throw InvalidInputError("Galerkin product: matrix is " + std::to_string(a.rows()) + " x " +
                            std::to_string(a.rows()) + " but the fine level has " +
                            std::to_string(fineUnknowns) + " unknowns");
}

}  // namespace

Sparse galerkinProduct(const SparseSum& a, const Sparse& p) {
  requireSquare(a, p.rows());
  const RowMajor pRows = p;  // row r of P: the coarse columns fine texel r interpolates from
  return galerkinColumns(
      rowsOf(a), p.cols(),
      [&](Eigen::Index j, std::vector<std::pair<int, double>>& out) {
        out.clear();
        for (Sparse::InnerIterator pi(p, j); pi; ++pi)
          out.emplace_back(static_cast<int>(pi.row()), pi.value());
      },
      [&](int r, const auto& add) {
        for (RowMajor::InnerIterator pr(pRows, r); pr; ++pr)
          add(static_cast<int>(pr.col()), pr.value());
      });
}

Sparse galerkinProduct(const SparseSum& a, const GridLevel& fine, const GridLevel& coarse) {
  requireSquare(a, fine.unknownCount());
  if (fine.unknownOfSlot.size() != static_cast<size_t>(fine.slotCount) ||
      coarse.unknownOfSlot.size() != static_cast<size_t>(coarse.slotCount))
    throw InvalidInputError(
        "Galerkin product: the levels' unknownOfSlot was freed (a MultigridSolver's hierarchy "
        "frees it after a set-up); call GridHierarchy::restoreUnknownOfSlot first");
  return latticeProduct(fine, coarse, rowsOf(a));
}

namespace detail {

namespace {

/// The interior rows of a level's system as its stencils hold them.
template <typename T>
class InteriorRows {
 public:
  InteriorRows(const GridLevel& level, const LevelSystem& system, std::span<const T> stencils,
               std::span<const T> rowSums)
      : level_(level),
        system_(system),
        stencils_(stencils),
        rowSums_(rowSums),
        firstRow_(level.boxes.size(), {-1, 0}) {
    for (size_t k = 0; k < system.boxRows.size(); ++k) {
      auto& first = firstRow_[static_cast<size_t>(system.boxRows[k].box)];
      if (first.first < 0) first = {static_cast<int64_t>(k), system.boxRows[k].y};
    }
  }
  /// Calls f(k, value) for the entries of interior slot s (of box `box`, lattice row y) by
  /// stencil index k = (dy + 1) * 3 + (dx + 1): the couplings to the unknowns around it, then
  /// (k = 4) the diagonal, its row sum less them.
  template <typename F>
  void forEachEntry(int box, int y, int64_t s, F&& f) const {
    // The row holding slot s and the row above it, which stores s's couplings up.
    const auto& [first, y0] = firstRow_[static_cast<size_t>(box)];
    const auto i = static_cast<size_t>(first + y - y0);
    const SlotRow& row = system_.boxRows[i];
    const SlotRow& above = system_.boxRows[i - 1];
    double off = 0.0;
    for (int k = 0; k < 9; ++k) {
      // (A has no entry at an empty slot)
      if (k == 4 || level_.unknownOfSlot[static_cast<size_t>(s + stencilOffset(k, row.width))] < 0)
        continue;
      const double value =
          static_cast<double>(stencils_[static_cast<size_t>(couplingAt(above, row, s, k))]);
      off += value;
      f(k, value);
    }
    f(4, static_cast<double>(rowSums_[static_cast<size_t>(s)]) - off);
  }
  /// True if slot s holds an interior unknown.
  bool interior(int64_t s) const {
    return system_.kind[static_cast<size_t>(s)] == SlotKind::Interior;  // Empty without one
  }

 private:
  const GridLevel& level_;
  const LevelSystem& system_;
  std::span<const T> stencils_, rowSums_;
  /// Per box: index in boxRows of its first row and that row's lattice y (a box's rows are
  /// consecutive from there, LevelSystem::boxRows).
  std::vector<std::pair<int64_t, int>> firstRow_;
};

/// Column j of A^1 = Pᵀ A P where every child of coarse texel j has an interior row, formed as
/// galerkinColumns forms it but with the fine entries in the 5 x 5 window around j's centre
/// child and the coarse ones in the 3 x 3 window around j, positions known from the lattice: no
/// accumulator's hashing, no sort, one point lookup per column. The same sums in the same order
/// (children by fine index, each row's entries in the order of its rowOf, fine entries in the
/// order first touched), so the same bits, as unknowns number a box's texels row by row (the
/// TexelGrid's order at level 0, slot order above). Other columns are left to galerkinColumns
/// (returns false).
template <typename T>
class InteriorColumns {
 public:
  InteriorColumns(const GridLevel& fine, const GridLevel& coarse, const InteriorRows<T>& rows)
      : fine_(fine), coarse_(coarse), rows_(rows) {}

  bool operator()(int j, std::vector<std::pair<int, double>>& out) const {
    const LatticePoint c = coarse_.point(j);
    const GridBox& coarseBox = coarse_.boxes[static_cast<size_t>(c.box)];
    const int fineBox = fine_.boxOfChart[static_cast<size_t>(coarseBox.chart)];
    Window window(2 * c.x - 2, 2 * c.y - 2);
    if (!sumFineEntries(c, fineBox, window)) return false;
    std::array<double, 9> sums{};
    std::array<bool, 9> reached{};
    for (int t = 0; t < window.touchedCount; ++t) {  // (Pᵀ A P)_{:, j}
      const int at = window.touched[static_cast<size_t>(t)];
      const LatticeParents px = latticeParents(window.x0 + at % 5);
      const LatticeParents py = latticeParents(window.y0 + at / 5);
      for (int jy = 0; jy < py.count; ++jy)
        for (int ix = 0; ix < px.count; ++ix) {
          const auto x = static_cast<size_t>(ix), y = static_cast<size_t>(jy);
          const auto k = static_cast<size_t>((py.index[y] - c.y + 1) * 3 + px.index[x] - c.x + 1);
          reached[k] = true;
          sums[k] += px.weight[x] * py.weight[y] * window.sum[static_cast<size_t>(at)];
        }
    }
    for (size_t k = 0; k < 9; ++k) {  // by increasing coarse index, as galerkinColumns sorts
      if (!reached[k]) continue;
      const int v = coarse_.unknownOfSlot[static_cast<size_t>(
          coarseBox.slot(c.x + static_cast<int>(k % 3) - 1, c.y + static_cast<int>(k / 3) - 1))];
      if (v < 0) {  // a parent without an unknown: not a column of this shape
        out.clear();
        return false;
      }
      out.emplace_back(v, sums[k]);
    }
    return true;
  }

 private:
  /// Sums at the fine lattice positions (x0 + i, y0 + j), i, j < 5, in the order first touched.
  struct Window {
    Window(int x, int y) : x0(x), y0(y) {}
    void add(int x, int y, double value) {
      const auto at = static_cast<size_t>((y - y0) * 5 + (x - x0));
      if (!seen[at]) {
        seen[at] = true;
        touched[static_cast<size_t>(touchedCount++)] = static_cast<int8_t>(at);
      }
      sum[at] += value;
    }
    int x0, y0;
    std::array<double, 25> sum{};
    std::array<bool, 25> seen{};
    std::array<int8_t, 25> touched{};
    int touchedCount = 0;
  };

  /// (A P)_{:, j} into `window` for coarse texel c, its children in fine box `fineBox`; false
  /// if a child's row is not interior or c has no child.
  bool sumFineEntries(const LatticePoint& c, int fineBox, Window& window) const {
    const GridBox& box = fine_.boxes[static_cast<size_t>(fineBox)];
    int children = 0;
    for (int fy = 2 * c.y - 1; fy <= 2 * c.y + 1; ++fy)  // by increasing fine index
      for (int fx = 2 * c.x - 1; fx <= 2 * c.x + 1; ++fx) {
        if (!box.contains(fx, fy)) continue;
        const int64_t s = box.slot(fx, fy);
        if (fine_.unknownOfSlot[static_cast<size_t>(s)] < 0) continue;
        if (!rows_.interior(s)) return false;
        ++children;
        const double w =
            detail::transferWeight<double>(fx, c.x) * detail::transferWeight<double>(fy, c.y);
        rows_.forEachEntry(fineBox, fy, s, [&](int k, double value) {
          window.add(fx + k % 3 - 1, fy + k / 3 - 1, value * w);
        });
      }
    return children > 0;
  }

  const GridLevel& fine_;
  const GridLevel& coarse_;
  const InteriorRows<T>& rows_;
};

}  // namespace

// Why reading all 9 lattice neighbours of an interior row keeps the pattern of Pᵀ A P although A
// may lack some of them (the walk's symbolic phase forms A^1 from A's pattern, its numeric phase
// from the stencils, and both must agree): an extra entry (u, v), v a lattice neighbour of u,
// adds coarse entries (J, K) for the parents J of u and K of v. Per axis 2J and 2K lie within one
// fine step of u and of v, so the fine texel m = J + K lies in u's 3 x 3 neighbourhood, all
// unknowns of u's chart (u's footprint is interior), and is a child of both J and K: m's
// diagonal entry already gives (J, K). The extra entries carry zeros, which add nothing.
template <typename T>
Sparse galerkinFromLevel(const GridLevel& fine, const LevelSystem& system,
                         std::span<const T> stencils, std::span<const T> rowSums,
                         const GridLevel& coarse, bool interiorShortcut) {
  if (stencils.size() != static_cast<size_t>(system.stencilSize) ||
      rowSums.size() != static_cast<size_t>(fine.slotCount) ||
      system.boundaryRows.ptr.size() != static_cast<size_t>(system.boundaryCount()) + 1)
    throw InvalidInputError("Galerkin product: level data not assigned");
  const auto unknownOf = [&](int64_t slot) {
    return fine.unknownOfSlot[static_cast<size_t>(slot)];
  };
  const InteriorRows<T> rows(fine, system, stencils, rowSums);
  const auto rowOf = [&](int r, const auto& f) {
    const int64_t s = fine.slotOfUnknown[static_cast<size_t>(r)];
    if (system.kind[static_cast<size_t>(s)] == SlotKind::Interior) {
      const LatticePoint p = fine.point(r);
      const int width = fine.boxes[static_cast<size_t>(p.box)].width;
      rows.forEachEntry(p.box, p.y, s, [&](int k, double value) {
        f(k == 4 ? r : unknownOf(s + stencilOffset(k, width)), value);
      });
      return;
    }
    const auto j = static_cast<size_t>(system.boundaryIndex.rank(r));
    const SlotCsr& boundary = system.boundaryRows;
    const int64_t offEnd = system.offBlockEnd[j];
    double rounding = 0.0;  // of the couplings to interior texels, which their stencils hold in T
    for (int64_t e = boundary.ptr[j]; e != offEnd; ++e) {
      const double exact = boundary.val[static_cast<size_t>(e)];
      const double value = static_cast<double>(static_cast<T>(exact));
      rounding += exact - value;
      f(unknownOf(boundary.col[static_cast<size_t>(e)]), value);
    }
    for (int64_t e = offEnd; e != boundary.ptr[j + 1]; ++e) {
      const int v = unknownOf(boundary.col[static_cast<size_t>(e)]);
      f(v, boundary.val[static_cast<size_t>(e)] + (v == r ? rounding : 0.0));
    }
  };
  if (!interiorShortcut) return latticeProduct(fine, coarse, rowOf);
  return latticeProduct(fine, coarse, rowOf, InteriorColumns<T>(fine, coarse, rows));
}

template Sparse galerkinFromLevel<float>(const GridLevel&, const LevelSystem&,
                                         std::span<const float>, std::span<const float>,
                                         const GridLevel&, bool);
template Sparse galerkinFromLevel<double>(const GridLevel&, const LevelSystem&,
                                          std::span<const double>, std::span<const double>,
                                          const GridLevel&, bool);

}  // namespace detail
}  // namespace texgrad
