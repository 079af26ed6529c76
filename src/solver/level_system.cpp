// Solver module (private): interior/boundary split of one level and its numeric assignment.
#include "solver/level_system.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include "texgrad/core/error.h"
#include "texgrad/core/storage_bytes.h"

namespace texgrad::detail {
namespace {

/// The 3 x 3 lattice neighbourhood of one unknown within its box (so within its chart).
class Neighbourhood {
 public:
  Neighbourhood(const GridLevel& level, int u)
      : level_(level),
        slot_(level.slotOfUnknown[static_cast<size_t>(u)]),
        width_(level.boxes[static_cast<size_t>(level.point(u).box)].width) {}
  /// Stencil index of unknown v, (dy + 1) * 3 + (dx + 1), or -1 when v is not a 3 x 3 lattice
  /// neighbour in the same chart. From the slots' difference dy * width + dx alone: an unknown
  /// lies inside its box's empty ring, so its 3 x 3 neighbours' slots are in its box, and no
  /// other slot is that close (another chart's box has other slots).
  int stencilIndex(int v) const {
    const int64_t offset = level_.slotOfUnknown[static_cast<size_t>(v)] - slot_;
    for (int dy = -1; dy <= 1; ++dy) {
      const int64_t dx = offset - static_cast<int64_t>(dy) * width_;
      if (dx >= -1 && dx <= 1) return (dy + 1) * 3 + static_cast<int>(dx + 1);
    }
    return -1;
  }

 private:
  const GridLevel& level_;
  int64_t slot_;  ///< of the unknown
  int width_;     ///< of its box
};

}  // namespace

std::array<double, 9> stencilRow(const GridLevel& level, const SparseSum& a, int u) {
  std::array<double, 9> w{};
  const Neighbourhood around(level, u);
  for (int e = a.outer()[u]; e != a.outer()[u + 1]; ++e) {
    const int index = around.stencilIndex(a.inner()[e]);
    if (index >= 0) w[static_cast<size_t>(index)] = a.value(e);
  }
  return w;
}

bool rowIsStencil(const GridLevel& level, const SparseSum& pattern, int u) {
  const Neighbourhood around(level, u);
  for (int e = pattern.outer()[u]; e != pattern.outer()[u + 1]; ++e)
    if (around.stencilIndex(pattern.inner()[e]) < 0) return false;
  return true;
}

namespace {

/// Rows with a_uu < kWeakDiagonal sum_{v != u} |a_uv| count as weak (see lockNearWeakRows).
constexpr double kWeakDiagonal = 0.25;

/// True if row u of `a` is weak: its diagonal is small against its off-diagonal entries. Texels
/// that their chart barely covers have such rows (mixed-sign couplings from sliver pieces).
bool isWeakRow(const SparseSum& a, int u) {
  double diagonal = 0.0, off = 0.0;
  for (int e = a.outer()[u]; e != a.outer()[u + 1]; ++e) {
    if (a.inner()[e] == u)
      diagonal += a.value(e);
    else
      off += std::abs(a.value(e));
  }
  return diagonal < kWeakDiagonal * off;
}

/// Clears `interior` for every unknown within `reach` lattice steps (Chebyshev) of a
/// non-interior unknown with a weak row, in the same chart. Eliminating a weak row couples its
/// neighbours far more strongly than their own stencils say, so Gauss–Seidel on them barely
/// converges (the slow modes on spot and lpshead); solving them with the boundary does.
void lockNearWeakRows(const GridLevel& level, const SparseSum& a, int reach,
                      std::vector<uint8_t>& interior) {
  const int n = level.unknownCount();
  std::vector<uint8_t> weak(static_cast<size_t>(n), 0);
  tbb::parallel_for(0, n, [&](int u) {
    weak[static_cast<size_t>(u)] = !interior[static_cast<size_t>(u)] && isWeakRow(a, u);
  });
  for (int u = 0; u < n; ++u) {
    if (!weak[static_cast<size_t>(u)]) continue;
    const LatticePoint p = level.point(u);
    const GridBox& box = level.boxes[static_cast<size_t>(p.box)];
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const int x = p.x + dx, y = p.y + dy;
        if (!box.contains(x, y)) continue;
        const int v = level.unknownOfSlot[static_cast<size_t>(box.slot(x, y))];
        if (v >= 0) interior[static_cast<size_t>(v)] = 0;
      }
  }
}

/// Row r of `box` with its visited slots, from its first to its last interior slot (none if it
/// has no interior slot); its stored slots are set by storeRows.
SlotRow boxRowOf(const GridBox& box, int boxIndex, int r, const LevelSystem& system) {
  const int64_t rowStart = box.offset + static_cast<int64_t>(r) * box.width;
  int64_t first = -1, last = -1;
  for (int64_t s = rowStart; s < rowStart + box.width; ++s) {
    if (system.kind[static_cast<size_t>(s)] != SlotKind::Interior) continue;
    if (first < 0) first = s;
    last = s;
  }
  SlotRow row;
  row.box = boxIndex;
  row.width = box.width;
  row.y = box.y0 + r;
  if (first < 0) return row;
  row.begin = first;
  row.end = last + 1;
  row.xParity = (box.x0 + static_cast<int>(first - rowStart)) & 1;
  return row;
}

/// Sets the stored slots of box rows [first, end) (one box, consecutive rows) and their place in
/// the stencil array: a row stores its visited slots and the slot before them (their couplings
/// in the row) and the slots next to the visited slots of the row below (their couplings up).
/// The box's empty ring keeps every stored slot inside the box row.
void storeRows(int64_t first, int64_t end, LevelSystem& system) {
  for (int64_t i = first; i < end; ++i) {
    SlotRow& row = system.boxRows[static_cast<size_t>(i)];
    int64_t lo = std::numeric_limits<int64_t>::max(), hi = std::numeric_limits<int64_t>::min();
    if (row.begin != row.end) lo = row.begin - 1, hi = row.end;
    if (i + 1 < end) {
      const SlotRow& below = system.boxRows[static_cast<size_t>(i) + 1];
      if (below.begin != below.end)
        lo = std::min(lo, below.begin - row.width - 1),
        hi = std::max(hi, below.end - row.width + 1);
    }
    if (lo > hi) lo = hi = 0;
    row.storeBegin = lo;
    row.storeEnd = hi;
    row.coeffs = system.stencilSize;
    system.stencilSize += kStencilPlanes * (row.stored(0) + row.stored(1));
  }
}

/// Splits box rows [first, end) into bands of about kBandRows rows.
void addBands(int64_t first, int64_t end, LevelSystem& system) {
  const int64_t count = std::max<int64_t>(1, (end - first) / kBandRows);
  for (int64_t b = 0; b < count; ++b)
    system.bands.push_back({first + (end - first) * b / count,
                            first + (end - first) * (b + 1) / count, b > 0, b + 1 < count});
}

void collectRows(const GridLevel& level, LevelSystem& system) {
  system.boxRows.clear();
  system.bands.clear();
  system.stencilSize = 0;
  for (size_t b = 0; b < level.boxes.size(); ++b) {
    const GridBox& box = level.boxes[b];
    const int64_t boxFirst = static_cast<int64_t>(system.boxRows.size());
    int64_t boxEnd = boxFirst;
    for (int r = 1; r + 1 < box.height; ++r) {
      const SlotRow row = boxRowOf(box, static_cast<int>(b), r, system);
      const bool interior = row.begin != row.end;
      // Before the first interior row only the row just before it is kept (it stores the
      // couplings up to it). An interior slot has its 8 lattice neighbours, unknowns, so neither
      // it nor they lie on the box's empty ring: the row r = 1 is never interior.
      if (!interior && boxEnd == boxFirst) system.boxRows.resize(static_cast<size_t>(boxFirst));
      system.boxRows.push_back(row);
      if (interior) boxEnd = static_cast<int64_t>(system.boxRows.size());
    }
    system.boxRows.resize(static_cast<size_t>(boxEnd));  // drop rows after the last interior row
    if (boxEnd == boxFirst) continue;
    if (system.boxRows[static_cast<size_t>(boxFirst)].begin !=
        system.boxRows[static_cast<size_t>(boxFirst)].end)
      throw NumericalError("multigrid: an interior slot on a box's first row (internal error)");
    storeRows(boxFirst, boxEnd, system);
    addBands(boxFirst, boxEnd, system);
  }
}

/// Unknown of boundary row j.
int unknownOfBoundary(const GridLevel& level, const LevelSystem& system, int j) {
  return level.unknownOfSlot[static_cast<size_t>(system.boundarySlots[static_cast<size_t>(j)])];
}

/// Entries of column u of `a` (its row u: A is symmetric) whose row is (isBoundary true) or is
/// not (false) a boundary unknown.
int64_t countEntries(const SparseSum& a, int u, const LevelSystem& system, bool isBoundary) {
  int64_t count = 0;
  for (int e = a.outer()[u]; e != a.outer()[u + 1]; ++e)
    count += system.boundaryIndex.contains(a.inner()[e]) == isBoundary;
  return count;
}

/// Turns per-row counts in ptr[1..n] into row starts (ptr[0] = 0); returns the total.
int64_t countsToStarts(std::vector<int64_t>& ptr) {
  ptr[0] = 0;
  for (size_t j = 1; j < ptr.size(); ++j) ptr[j] += ptr[j - 1];
  return ptr.back();
}

/// A_bb^l, built in compressed form: column j of A_bb is column u(j) of A restricted to boundary
/// rows, and boundary indices grow with the unknown index (classifyLevel), so each column's rows
/// come out sorted without a triplet list.
Eigen::SparseMatrix<double> boundaryBlock(const GridLevel& level, const SparseSum& a,
                                          const LevelSystem& system) {
  const int nb = system.boundaryCount();
  std::vector<int64_t> start(static_cast<size_t>(nb) + 1, 0);
  tbb::parallel_for(0, nb, [&](int j) {
    start[static_cast<size_t>(j) + 1] =
        countEntries(a, unknownOfBoundary(level, system, j), system, true);
  });
  const int64_t total = countsToStarts(start);
  if (total > std::numeric_limits<int>::max())
    throw InvalidInputError("multigrid: the boundary block has more than 2^31 non-zeros");
  Eigen::SparseMatrix<double> bb(nb, nb);
  bb.resizeNonZeros(static_cast<Eigen::Index>(total));
  for (int j = 0; j <= nb; ++j)
    bb.outerIndexPtr()[j] = static_cast<int>(start[static_cast<size_t>(j)]);
  tbb::parallel_for(0, nb, [&](int j) {
    int64_t out = start[static_cast<size_t>(j)];
    const int u = unknownOfBoundary(level, system, j);
    for (int e = a.outer()[u]; e != a.outer()[u + 1]; ++e) {
      const int v = a.inner()[e];
      if (!system.boundaryIndex.contains(v)) continue;
      bb.innerIndexPtr()[out] = system.boundaryIndex.rank(v);
      bb.valuePtr()[out++] = a.value(e);
    }
  });
  return bb;
}

/// Fills interiorNextToBoundary and fixupSlots from the columns of `a` at interior unknowns
/// (A is symmetric, so column u holds row u), each array allocated at its exact size.
void assignInteriorNextToBoundary(const GridLevel& level, const SparseSum& a, LevelSystem& system) {
  SlotCsr& fix = system.interiorNextToBoundary;
  // Few interior unknowns touch the boundary: count their boundary entries on all cores.
  const int n = level.unknownCount();
  std::vector<uint8_t> touching(static_cast<size_t>(n), 0);  // at most 9 (a 3 x 3 stencil row)
  tbb::parallel_for(0, n, [&](int u) {
    if (!system.boundaryIndex.contains(u))
      touching[static_cast<size_t>(u)] = static_cast<uint8_t>(countEntries(a, u, system, true));
  });
  size_t rows = 0;
  for (uint8_t count : touching) rows += count > 0;
  fix.ptr.assign(rows + 1, 0);
  system.fixupSlots.resize(rows);
  size_t row = 0;
  for (int u = 0; u < n; ++u) {
    if (touching[static_cast<size_t>(u)] == 0) continue;
    fix.ptr[row + 1] = touching[static_cast<size_t>(u)];
    system.fixupSlots[row++] = level.slotOfUnknown[static_cast<size_t>(u)];
  }
  fix.col.resize(static_cast<size_t>(countsToStarts(fix.ptr)));
  fix.val.resize(fix.col.size());
  row = 0;
  for (int u = 0; u < n; ++u) {
    if (touching[static_cast<size_t>(u)] == 0) continue;
    int64_t out = fix.ptr[row++];
    for (int e = a.outer()[u]; e != a.outer()[u + 1]; ++e) {
      const int v = a.inner()[e];
      if (!system.boundaryIndex.contains(v)) continue;
      fix.col[static_cast<size_t>(out)] = system.boundaryIndex.rank(v);
      fix.val[static_cast<size_t>(out++)] = a.value(e);
    }
  }
}

}  // namespace

void BoundaryIndex::assign(const std::vector<uint8_t>& interior) {
  const size_t words = (interior.size() + 63) / 64;
  bits_.assign(words, 0);
  before_.assign(words, 0);
  for (size_t u = 0; u < interior.size(); ++u)
    if (!interior[u]) bits_[u >> 6] |= uint64_t{1} << (u & 63);
  int32_t count = 0;
  for (size_t w = 0; w < words; ++w) {
    before_[w] = count;
    count += std::popcount(bits_[w]);
  }
}

int64_t BoundaryIndex::storageBytes() const {
  return capacityBytes(bits_, before_);
}

void classifyLevel(const GridLevel& level, const SparseSum& pattern, int weakRowReach,
                   LevelSystem& system) {
  const int n = level.unknownCount();
  if (pattern.rows() != n)
    throw InvalidInputError("multigrid: matrix is " + std::to_string(pattern.rows()) + " x " +
                            std::to_string(pattern.rows()) + " but the level has " +
                            std::to_string(n) + " unknowns");
  std::vector<uint8_t> interior(static_cast<size_t>(n), 0);
  tbb::parallel_for(0, n, [&](int u) {
    const size_t su = static_cast<size_t>(u);
    interior[su] = level.footprintInterior[su] && rowIsStencil(level, pattern, u);
  });
  if (weakRowReach > 0) lockNearWeakRows(level, pattern, weakRowReach, interior);
  system.kind.assign(static_cast<size_t>(level.slotCount), SlotKind::Empty);
  system.boundaryIndex.assign(interior);
  const auto interiorCount = static_cast<size_t>(std::count(interior.begin(), interior.end(), 1));
  system.boundarySlots.clear();
  system.boundarySlots.reserve(static_cast<size_t>(n) - interiorCount);
  for (int u = 0; u < n; ++u) {
    const size_t su = static_cast<size_t>(u);
    const int32_t slot = level.slotOfUnknown[su];
    system.kind[static_cast<size_t>(slot)] = interior[su] ? SlotKind::Interior : SlotKind::Boundary;
    if (!interior[su]) system.boundarySlots.push_back(slot);
  }
  system.interiorTotal = static_cast<int>(interiorCount);
  collectRows(level, system);
  system.nonZeros = pattern.nonZeros();
  const Eigen::SparseMatrix<double> bb = boundaryBlock(level, pattern, system);
  system.boundaryNonZeros = bb.nonZeros();
  if (system.boundaryCount() > 0) system.boundarySolver.analyzePattern(bb);
}

void assignBoundary(const GridLevel& level, const SparseSum& a, LevelSystem& system,
                    std::span<const float> rowSums) {
  // Counted first so every array is allocated once at its exact size, then filled on all cores.
  const int nb = system.boundaryCount();
  SlotCsr& rows = system.boundaryRows;
  rows.ptr.assign(static_cast<size_t>(nb) + 1, 0);
  system.offBlockEnd.resize(static_cast<size_t>(nb));
  tbb::parallel_for(0, nb, [&](int j) {
    const int u = unknownOfBoundary(level, system, j);
    const int64_t offCount = countEntries(a, u, system, false);
    rows.ptr[static_cast<size_t>(j) + 1] = offCount + countEntries(a, u, system, true);
    system.offBlockEnd[static_cast<size_t>(j)] = offCount;  // a count until the fill below
  });
  rows.col.resize(static_cast<size_t>(countsToStarts(rows.ptr)));
  rows.val.resize(rows.col.size());
  tbb::parallel_for(0, nb, [&](int j) {
    const size_t sj = static_cast<size_t>(j);
    const int u = unknownOfBoundary(level, system, j);
    int64_t off = rows.ptr[sj], on = off + system.offBlockEnd[sj];
    system.offBlockEnd[sj] = on;
    for (int e = a.outer()[u]; e != a.outer()[u + 1]; ++e) {
      const int row = a.inner()[e];
      int64_t& out = system.boundaryIndex.contains(row) ? on : off;
      rows.col[static_cast<size_t>(out)] = level.slotOfUnknown[static_cast<size_t>(row)];
      rows.val[static_cast<size_t>(out++)] =
          row == u && a.rounded(e) && !rowSums.empty()
              ? a.diagonalFromRowSum(u, rowSums[static_cast<size_t>(u)])
              : a.value(e);
    }
  });
  assignInteriorNextToBoundary(level, a, system);
}

void factoriseBoundary(const GridLevel& level, LevelSystem& system) {
  const int nb = system.boundaryCount();
  if (nb == 0) return;
  const SlotCsr& rows = system.boundaryRows;
  const auto blockBegin = [&](int j) { return system.offBlockEnd[static_cast<size_t>(j)]; };
  const auto blockEnd = [&](int j) { return rows.ptr[static_cast<size_t>(j) + 1]; };
  int64_t total = 0;
  for (int j = 0; j < nb; ++j) total += blockEnd(j) - blockBegin(j);
  if (total > std::numeric_limits<int>::max())
    throw InvalidInputError("multigrid: the boundary block has more than 2^31 non-zeros");
  Eigen::SparseMatrix<double> bb(nb, nb);
  bb.resizeNonZeros(static_cast<Eigen::Index>(total));
  bb.outerIndexPtr()[0] = 0;
  for (int j = 0; j < nb; ++j)
    bb.outerIndexPtr()[j + 1] =
        bb.outerIndexPtr()[j] + static_cast<int>(blockEnd(j) - blockBegin(j));
  // Row j's A_bb entries are its boundary columns in the order of A's row, by increasing
  // unknown, as the compact indices are (classifyLevel): every column of the block comes out
  // sorted, as boundaryBlock's.
  tbb::parallel_for(0, nb, [&](int j) {
    int out = bb.outerIndexPtr()[j];
    for (int64_t e = blockBegin(j); e != blockEnd(j); ++e) {
      const int u = level.unknownOfSlot[static_cast<size_t>(rows.col[static_cast<size_t>(e)])];
      bb.innerIndexPtr()[out] = system.boundaryIndex.rank(u);
      bb.valuePtr()[out++] = rows.val[static_cast<size_t>(e)];
    }
  });
  system.boundarySolver.factorize(bb);
}

namespace {

/// Lattice rows per band of assignStencils: 1/64 of spot's at 4096².
constexpr int kStencilBandRows = 64;

/// The first unknown of `level` on lattice row y or above, for a level whose unknowns are
/// numbered row by row (level 0).
int firstUnknownFrom(const GridLevel& level, int y) {
  int lo = 0, hi = level.unknownCount();
  while (lo < hi) {
    const int mid = lo + (hi - lo) / 2;
    if (level.point(mid).y < y)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

}  // namespace

template <typename T>
void assignStencils(const GridLevel& level, const SparseSum& a, const LevelSystem& system,
                    PageArray<T>& stencils, bool ownPages,
                    const std::function<void(int)>& consumed) {
  // A new array fills page by page on pages of its own while `a` is released (consumed), else it
  // comes from the heap (where it may take a freed block's place); an update of the same size
  // refills the one it has.
  if (stencils.size() != static_cast<size_t>(system.stencilSize))
    stencils = PageArray<T>(static_cast<size_t>(system.stencilSize), ownPages);
  T* w = stencils.data();
  auto clearRow = [&](const SlotRow& row) {
    std::fill_n(w + row.coeffs, kStencilPlanes * (row.stored(0) + row.stored(1)), T(0));
  };
  // Row s of A at each interior slot s of `row`: its forward couplings and centre into its own
  // planes, and the other couplings into the neighbour's planes where that neighbour is not
  // interior (an interior neighbour stores them itself), so every coefficient has one writer.
  auto fillRow = [&](const SlotRow& above, const SlotRow& row) {
    for (int64_t s = row.begin; s < row.end; ++s) {
      if (system.kind[static_cast<size_t>(s)] != SlotKind::Interior) continue;
      const int u = level.unknownOfSlot[static_cast<size_t>(s)];
      const Neighbourhood around(level, u);
      T centre(0);
      for (int e = a.outer()[u]; e != a.outer()[u + 1]; ++e) {
        const int k = around.stencilIndex(a.inner()[e]);
        if (k < 0)
          throw InvalidInputError("multigrid: row " + std::to_string(u) +
                                  " of the matrix is not the stencil the set-up classified; an "
                                  "update needs the pattern of init");
        const T value = static_cast<T>(a.value(e));
        if (k == 4) {
          centre = value;
        } else if (k > 4 || system.kind[static_cast<size_t>(s + stencilOffset(k, row.width))] !=
                                SlotKind::Interior) {
          w[couplingAt(above, row, s, k)] = value;
        }
      }
      if (!(centre > T(0)))
        throw NumericalError("multigrid: diagonal entry of unknown " + std::to_string(u) +
                             " is not positive; the system matrix must be positive definite");
      w[row.coefficient(s, kCentre)] = centre;
      w[row.coefficient(s, kInverseDiagonal)] = T(1) / centre;
    }
  };
  // Every row with its lattice y, upward. A band's rows are cleared before any is filled: a row
  // writes into the row before it, which an earlier band or this one holds.
  std::vector<std::pair<int, size_t>> rows;
  for (size_t k = 0; k < system.boxRows.size(); ++k) rows.emplace_back(system.boxRows[k].y, k);
  std::sort(rows.begin(), rows.end());
  for (size_t first = 0; first < rows.size();) {
    const int end = rows[first].first + kStencilBandRows;
    size_t last = first;
    while (last < rows.size() && rows[last].first < end) ++last;
    tbb::parallel_for(first, last, [&](size_t r) { clearRow(system.boxRows[rows[r].second]); });
    tbb::parallel_for(first, last, [&](size_t r) {
      const size_t k = rows[r].second;
      const SlotRow& row = system.boxRows[k];
      if (row.begin != row.end) fillRow(system.boxRows[k - 1], row);
    });
    if (consumed)
      consumed(last == rows.size() ? level.unknownCount() : firstUnknownFrom(level, end));
    first = last;
  }
}

template void assignStencils<float>(const GridLevel&, const SparseSum&, const LevelSystem&,
                                    PageArray<float>&, bool, const std::function<void(int)>&);
template void assignStencils<double>(const GridLevel&, const SparseSum&, const LevelSystem&,
                                     PageArray<double>&, bool, const std::function<void(int)>&);

int64_t LevelSystem::storageBytes() const {
  return capacityBytes(kind, boxRows, bands, boundarySlots, offBlockEnd, fixupSlots) +
         boundaryIndex.storageBytes() +
         capacityBytes(boundaryRows.ptr, boundaryRows.col, interiorNextToBoundary.ptr,
                       interiorNextToBoundary.col) +
         capacityBytes(boundaryRows.val, interiorNextToBoundary.val) +
         boundarySolver.storageBytes();
}

}  // namespace texgrad::detail
