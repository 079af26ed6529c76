// Solver module (private): one hierarchy level's operator split into regular interior stencils and
// an irregular boundary block (paper §6.2, Fig. 7), plus its CHOLMOD factorisation.
#pragma once

#include <Eigen/SparseCore>
#include <array>
#include <bit>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "texgrad/core/page_allocator.h"
#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/grid_hierarchy.h"
#include "texgrad/solver/sparse_sum.h"

namespace texgrad::detail {

/// Coefficient planes per stored slot of a row. A is symmetric, so a coupling is stored once, by
/// the slot whose forward half it lies in (from that slot's row of A, which serves both: coarse
/// A^l is symmetric up to the rounding of its sums): planes 0 to 3 hold the couplings to (dx, dy) =
/// (+1, 0),
/// (-1, +1), (0, +1), (+1, +1) (stencil indices 5 to 8, index (dy + 1) * 3 + (dx + 1)); a slot
/// reads the other half (indices 0 to 3) from the neighbour there, index k from plane 3 - k.
/// Then the centre and 1 / centre (0 on slots that are not interior: the mask). Ten planes per
/// slot before (docs/memory.md).
constexpr int kStencilPlanes = 6;
/// Plane holding the centre weight A_ss.
constexpr int kCentre = 4;
/// Plane holding 1 / A_ss (0 marks a slot that relaxation and residuals skip).
constexpr int kInverseDiagonal = 5;
/// Plane of the stored coupling for stencil index k (5 to 8) of the slot that stores it.
constexpr int forwardPlane(int k) {
  return k - 5;
}

/// One lattice row of a box: the slots [begin, end) that relaxation visits, every interior slot
/// of the row (empty if it has none), and the slots [storeBegin, storeEnd) whose forward
/// couplings are stored, every one an interior slot of this row or the row below reads. Stored
/// by colour: the slots storeBegin + c + 2i (c = 0, 1) have kStencilPlanes planes of stored(c)
/// coefficients each, c = 0 first, starting at `coeffs` (structure of arrays, so the relaxation
/// of one colour reads every plane with unit stride).
struct SlotRow {
  int64_t begin = 0, end = 0;            ///< visited slots [begin, end)
  int64_t storeBegin = 0, storeEnd = 0;  ///< stored slots, containing [begin - 1, end)
  int box = 0;                           ///< index into GridLevel::boxes
  int width = 0;                         ///< width of the box (row stride in slots)
  int xParity = 0;                       ///< parity of the lattice x coordinate of slot `begin`
  int y = 0;                             ///< lattice y of the row
  int64_t coeffs = 0;  ///< offset of this row's coefficients in the level's stencil array
  /// Parity of the lattice y coordinate of the row.
  int yParity() const { return y & 1; }
  /// Number of visited slots begin + q + 2i.
  int64_t runLength(int q) const { return (end - begin - q + 1) / 2; }
  /// Number of stored slots storeBegin + c + 2i.
  int64_t stored(int c) const { return (storeEnd - storeBegin - c + 1) / 2; }
  /// Offset of plane p's coefficient of stored slot t in the level's stencil array; the next
  /// slot of t's colour (t + 2) has the next offset.
  int64_t coefficient(int64_t t, int p) const {
    const int64_t d = t - storeBegin;
    const int c = static_cast<int>(d & 1);
    return coeffs + (c ? kStencilPlanes * stored(0) : 0) + p * stored(c) + (d >> 1);
  }
};

/// Slot offset of stencil index k's neighbour, (dy + 1) * 3 + (dx + 1), in a box of `width`.
constexpr int64_t stencilOffset(int k, int width) {
  return (k / 3 - 1) * int64_t{width} + (k % 3 - 1);
}

/// Offset in the stencil array of weight k (not the centre) of slot s of `row`: its own plane
/// for the forward half (k > 4), else the neighbour's plane 8 - k, stored by `row` (k = 3) or by
/// `above`, the row before it in its box.
inline int64_t couplingAt(const SlotRow& above, const SlotRow& row, int64_t s, int k) {
  if (k > 4) return row.coefficient(s, forwardPlane(k));
  const int64_t t = s + stencilOffset(k, row.width);
  return (k == 3 ? row : above).coefficient(t, forwardPlane(8 - k));
}

/// Where the 9 weights and 1 / centre of the visited slots begin + q + 2i of a row are: weight
/// k of slot i at w[k][i] (0 to 3 in the stored slots of the row itself and the row above, the
/// row below storing none of them), inverse[i].
template <typename T>
struct RunStencil {
  const T* w[9] = {};
  const T* inverse = nullptr;
};

/// The weights of colour q of `row` in `stencils`; `above` is the row before it in its box.
template <typename T>
RunStencil<T> runStencil(const T* stencils, const SlotRow& above, const SlotRow& row, int q) {
  RunStencil<T> r;
  const int64_t s = row.begin + q;
  for (int k = 0; k < 9; ++k)
    if (k != 4) r.w[k] = stencils + couplingAt(above, row, s, k);
  r.w[4] = stencils + row.coefficient(s, kCentre);
  r.inverse = stencils + row.coefficient(s, kInverseDiagonal);
  return r;
}

/// Box rows [first, end) of LevelSystem::boxRows relaxed as one cache-sized band; a cut side
/// borders the next band of the same box (paper §6.2: cache-blocked relaxation).
struct RowBand {
  int64_t first = 0, end = 0;
  bool cutBelow = false, cutAbove = false;
};

/// Rows per relaxation band: the sweeps of a V-cycle phase run over a band while its stencils
/// stay in cache. A band must hold at least 4 n + 2 rows for n sweeps at once.
constexpr int64_t kBandRows = 64;

/// Compressed rows with slot-indexed columns (rows of A for the boundary unknowns).
struct SlotCsr {
  std::vector<int64_t> ptr;  ///< row starts, size rows + 1
  std::vector<int32_t> col;  ///< slot index (< 2^31: GridHierarchy checks) of each entry
  std::vector<double> val;   ///< entry values
};

/// Which unknowns of a level are boundary unknowns and each one's compact boundary index (the
/// number of boundary unknowns before it) in 1.5 bits per unknown: a bit per unknown and a
/// running count per 64-bit word (rank over a bit vector), where two per-unknown arrays took 64.
class BoundaryIndex {
 public:
  /// Marks unknown u as a boundary unknown when interior[u] == 0.
  void assign(const std::vector<uint8_t>& interior);
  /// True if unknown u is a boundary unknown.
  bool contains(int u) const { return (bits_[static_cast<size_t>(u) >> 6] >> (u & 63)) & 1u; }
  /// Compact index of unknown u if it is a boundary unknown, else of the next one.
  int rank(int u) const {
    const size_t word = static_cast<size_t>(u) >> 6;
    const uint64_t below = bits_[word] & ((uint64_t{1} << (u & 63)) - 1);
    return before_[word] + std::popcount(below);
  }
  /// Bytes held.
  int64_t storageBytes() const;

 private:
  std::vector<uint64_t> bits_;   ///< bit u & 63 of word u >> 6: unknown u is a boundary unknown
  std::vector<int32_t> before_;  ///< per word: boundary unknowns in the words before it
};

/// Interior/boundary split and the double-precision boundary data of one level.
struct LevelSystem {
  std::vector<SlotKind> kind;  ///< per slot
  /// Consecutive rows of each box from the row before its first row with interior slots (which
  /// stores couplings to it) to its last row with interior slots, for the banded relaxation;
  /// a row with interior slots always has the row before it in boxRows before it.
  std::vector<SlotRow> boxRows;
  std::vector<RowBand> bands;          ///< bands of boxRows, in order
  std::vector<int32_t> boundarySlots;  ///< compact boundary index -> slot
  /// Boundary unknowns and their compact indices; the other unknowns are relaxed by Gauss–Seidel.
  BoundaryIndex boundaryIndex;
  int interiorTotal = 0;         ///< number of interior unknowns
  int64_t stencilSize = 0;       ///< coefficients over all rows (kStencilPlanes per stored slot)
  int64_t nonZeros = 0;          ///< non-zeros of A^l
  int64_t boundaryNonZeros = 0;  ///< non-zeros of A_bb^l
  /// [A_bi^l A_bb^l]: the complete boundary rows, each with its A_bi^l entries (non-boundary
  /// columns) first, up to offBlockEnd, then its A_bb^l entries (one copy serves both blocks).
  SlotCsr boundaryRows;
  std::vector<int64_t> offBlockEnd;  ///< per boundary row: end of its A_bi^l entries
  /// A_ib^l: per slot of fixupSlots (interior slots with a boundary neighbour), its entries with
  /// the compact boundary index as column.
  SlotCsr interiorNextToBoundary;
  std::vector<int32_t> fixupSlots;  ///< interior slots with a boundary neighbour
  CholmodSolver boundarySolver;     ///< factorisation of A_bb^l
  int interiorCount() const { return interiorTotal; }
  /// Slots of the level: the length of one channel plane of a slot vector.
  int64_t slotCount() const { return static_cast<int64_t>(kind.size()); }
  int boundaryCount() const { return static_cast<int>(boundarySlots.size()); }
  /// Bytes held: the arrays' capacity and the boundary factorisation.
  int64_t storageBytes() const;
};

/// The 3 x 3 stencil of row u of `a` (index (dy + 1) * 3 + (dx + 1)); entries outside the
/// lattice neighbourhood of u in its chart are left out.
std::array<double, 9> stencilRow(const GridLevel& level, const SparseSum& a, int u);

/// True if row u of `pattern` only has entries at the 3 x 3 lattice neighbours of u in its chart.
bool rowIsStencil(const GridLevel& level, const SparseSum& pattern, int u);

/// Symbolic phase: a texel is interior when its footprint is interior (§6.1), its row of
/// `pattern` only touches the 3 x 3 lattice neighbours in its own chart, and (reach > 0) it lies
/// more than weakRowReach lattice steps from a boundary texel whose row of `pattern` is weak
/// (diagonal < 1/4 of the off-diagonal magnitudes); A_bb^l is analysed. Only that last test
/// reads the values of `pattern`; any values give a correct solver.
void classifyLevel(const GridLevel& level, const SparseSum& pattern, int weakRowReach,
                   LevelSystem& system);

/// Numeric phase for the boundary: fills boundaryRows / offBlockEnd. With `rowSums` (per
/// unknown: the sums of A's rows before its entries were rounded, a FloatSystem's), each boundary
/// row whose diagonal `a` holds rounded (SparseSum::rounded) gets its row sum minus its other
/// entries as its diagonal, so the row keeps its sum as the difference form of the interior rows
/// does: rounding the entries then perturbs A only by a matrix with zero row sums (see
/// galerkinFromLevel).
void assignBoundary(const GridLevel& level, const SparseSum& a, LevelSystem& system,
                    std::span<const float> rowSums = {});

/// Factorises A_bb^l (system.boundarySolver) from the assigned boundary rows, so that a caller
/// can release A first and a handed-over A^0 never coexists with CHOLMOD's copy of the block and
/// the factorisation's work.
void factoriseBoundary(const GridLevel& level, LevelSystem& system);

/// Numeric phase for the interior: the stencil planes of every box row (see SlotRow) from the
/// rows of `a` at interior unknowns; a stored slot that is not interior holds its couplings to
/// interior neighbours and mask 0, the rest is zero. The rows are filled a band of lattice rows at
/// a time, upward; a new PageArray (unless `stencils` has the size already) is on pages of its own
/// if `ownPages`, so that it becomes resident as it is filled, else from the heap. After each band,
/// `consumed(u)`, if given, learns that no column of `a` before unknown u is read again (level 0
/// numbers its unknowns row by row), so that a caller owning `a` can release it meanwhile; after
/// the last band u is the unknown count (a level without interior slots has no band: `consumed` is
/// not called).
template <typename T>
void assignStencils(const GridLevel& level, const SparseSum& a, const LevelSystem& system,
                    PageArray<T>& stencils, bool ownPages = false,
                    const std::function<void(int)>& consumed = {});

/// Pᵀ Ã P for the bilinear prolongation P from `fine` to `coarse`, where Ã is A^l as the fine
/// level's assigned data hold it, read without a matrix: an interior row is its stencil at all 9
/// lattice neighbours (couplings in T; an entry A^l lacks is a zero coefficient) with the
/// diagonal rowSums[slot] minus those couplings, the difference form the cycles apply; a
/// boundary row is its boundaryRows entry, with its couplings to interior texels rounded to T as
/// their stencils hold them and the rounding moved to its diagonal. So Ã is symmetric and Ã 1 =
/// rowSums: rounding the couplings to float perturbs A^l only by a matrix with zero row sums, not
/// the small screening part that nearly singular systems hinge on. Equals galerkinProduct(A^l,
/// fine, coarse) in pattern when every row of A^l stores its diagonal (galerkin.cpp says why),
/// and for T = double in value up to the order of the sums. Defined in galerkin.cpp: one product
/// kernel. `interiorShortcut` false forms every column the general way (the shortcut for
/// columns whose children all have interior rows gives the same bits; a test compares them).
template <typename T>
Eigen::SparseMatrix<double> galerkinFromLevel(const GridLevel& fine, const LevelSystem& system,
                                              std::span<const T> stencils,
                                              std::span<const T> rowSums, const GridLevel& coarse,
                                              bool interiorShortcut = true);

}  // namespace texgrad::detail
