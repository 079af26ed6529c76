// Solver module (private): interior/boundary split of one level and its numeric assignment.
#include "solver/level_system.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "texgrad/core/error.h"

namespace texgrad::detail {
namespace {

using SparseIt = Eigen::SparseMatrix<double>::InnerIterator;

/// Stencil index of the entry (u, v), or -1 when v is not a 3 x 3 lattice neighbour of u in u's chart.
int stencilIndex(const GridLevel& level, int u, int v) {
  const size_t su = static_cast<size_t>(u), sv = static_cast<size_t>(v);
  if (level.chartOfUnknown[su] != level.chartOfUnknown[sv]) return -1;
  const int dx = level.xOfUnknown[sv] - level.xOfUnknown[su];
  const int dy = level.yOfUnknown[sv] - level.yOfUnknown[su];
  if (std::abs(dx) > 1 || std::abs(dy) > 1) return -1;
  return (dy + 1) * 3 + (dx + 1);
}

bool rowIsStencil(const GridLevel& level, const Eigen::SparseMatrix<double>& pattern, int u) {
  for (SparseIt it(pattern, u); it; ++it)
    if (stencilIndex(level, u, static_cast<int>(it.row())) < 0) return false;
  return true;
}

/// Interior run of box row r (an empty run if the row has no interior slot).
SlotRow interiorRun(const GridBox& box, int r, const LevelSystem& system) {
  const int64_t rowStart = box.offset + static_cast<int64_t>(r) * box.width;
  int64_t first = -1, last = -1;
  for (int64_t s = rowStart; s < rowStart + box.width; ++s) {
    if (system.kind[static_cast<size_t>(s)] != SlotKind::Interior) continue;
    if (first < 0) first = s;
    last = s;
  }
  const int y = box.y0 + r;
  if (first < 0) return {0, 0, box.width, 0, y & 1, 0};
  const int x = box.x0 + static_cast<int>(first - rowStart);
  return {first, last + 1, box.width, x & 1, y & 1, system.stencilSize};
}

/// Splits box rows [first, end) into bands of about kBandRows rows.
void addBands(int64_t first, int64_t end, LevelSystem& system) {
  const int64_t count = std::max<int64_t>(1, (end - first) / kBandRows);
  for (int64_t b = 0; b < count; ++b)
    system.bands.push_back({first + (end - first) * b / count,
                            first + (end - first) * (b + 1) / count, b > 0, b + 1 < count});
}

void collectRows(const GridLevel& level, LevelSystem& system) {
  for (int p = 0; p < 2; ++p) system.rows[p].clear();
  system.boxRows.clear();
  system.bands.clear();
  system.stencilSize = 0;
  for (const GridBox& box : level.boxes) {
    const int64_t boxFirst = static_cast<int64_t>(system.boxRows.size());
    int64_t boxEnd = boxFirst;
    for (int r = 1; r + 1 < box.height; ++r) {
      const SlotRow row = interiorRun(box, r, system);
      if (row.begin == row.end && boxEnd == boxFirst) continue;  // before the first interior row
      system.boxRows.push_back(row);
      if (row.begin == row.end) continue;
      boxEnd = static_cast<int64_t>(system.boxRows.size());
      system.stencilSize += kStencilPlanes * (row.runLength(0) + row.runLength(1));
      system.rows[row.yParity].push_back(row);
    }
    system.boxRows.resize(static_cast<size_t>(boxEnd));  // drop rows after the last interior row
    if (boxEnd > boxFirst) addBands(boxFirst, boxEnd, system);
  }
}

Eigen::SparseMatrix<double> boundaryBlock(const GridLevel& level,
                                          const Eigen::SparseMatrix<double>& a,
                                          const LevelSystem& system) {
  std::vector<Eigen::Triplet<double>> triplets;
  for (int j = 0; j < system.boundaryCount(); ++j) {
    const int u = level.unknownOfSlot[static_cast<size_t>(system.boundarySlots[static_cast<size_t>(j)])];
    for (SparseIt it(a, u); it; ++it) {
      const int jb = system.boundaryOfUnknown[static_cast<size_t>(it.row())];
      if (jb >= 0) triplets.emplace_back(jb, j, it.value());
    }
  }
  Eigen::SparseMatrix<double> bb(system.boundaryCount(), system.boundaryCount());
  bb.setFromTriplets(triplets.begin(), triplets.end());
  return bb;
}

/// Fills interiorNextToBoundary and fixupSlots from the columns of `a` at interior unknowns
/// (A is symmetric, so column u holds row u).
void assignInteriorNextToBoundary(const GridLevel& level, const Eigen::SparseMatrix<double>& a,
                                  LevelSystem& system) {
  SlotCsr& fix = system.interiorNextToBoundary;
  fix = {};
  fix.ptr.push_back(0);
  system.fixupSlots.clear();
  // Few interior unknowns touch the boundary: find them on all cores, then fill in order.
  const std::vector<int32_t>& interior = system.interiorUnknowns;
  std::vector<uint8_t> touches(interior.size(), 0);
  tbb::parallel_for(size_t(0), interior.size(), [&](size_t k) {
    for (SparseIt it(a, interior[k]); it; ++it)
      if (system.boundaryOfUnknown[static_cast<size_t>(it.row())] >= 0) {
        touches[k] = 1;
        return;
      }
  });
  for (size_t k = 0; k < interior.size(); ++k) {
    if (!touches[k]) continue;
    const int u = interior[k];
    for (SparseIt it(a, u); it; ++it) {
      const int jb = system.boundaryOfUnknown[static_cast<size_t>(it.row())];
      if (jb < 0) continue;
      fix.col.push_back(jb);
      fix.val.push_back(it.value());
    }
    fix.ptr.push_back(static_cast<int64_t>(fix.col.size()));
    system.fixupSlots.push_back(level.slotOfUnknown[static_cast<size_t>(u)]);
  }
}

}  // namespace

void classifyLevel(const GridLevel& level, const Eigen::SparseMatrix<double>& pattern,
                   LevelSystem& system) {
  const int n = level.unknownCount();
  if (pattern.rows() != n || pattern.cols() != n)
    throw InvalidInputError("multigrid: matrix is " + std::to_string(pattern.rows()) + " x " +
                            std::to_string(pattern.cols()) + " but the level has " +
                            std::to_string(n) + " unknowns");
  std::vector<uint8_t> interior(static_cast<size_t>(n), 0);
  tbb::parallel_for(0, n, [&](int u) {
    const size_t su = static_cast<size_t>(u);
    interior[su] = level.footprintInterior[su] && rowIsStencil(level, pattern, u);
  });
  system.kind.assign(static_cast<size_t>(level.slotCount), SlotKind::Empty);
  system.boundaryOfUnknown.assign(static_cast<size_t>(n), -1);
  system.boundarySlots.clear();
  system.interiorUnknowns.clear();
  for (int u = 0; u < n; ++u) {
    const size_t su = static_cast<size_t>(u);
    const int64_t slot = level.slotOfUnknown[su];
    if (interior[su]) {
      system.kind[static_cast<size_t>(slot)] = SlotKind::Interior;
      system.interiorUnknowns.push_back(u);
    } else {
      system.kind[static_cast<size_t>(slot)] = SlotKind::Boundary;
      system.boundaryOfUnknown[su] = static_cast<int32_t>(system.boundarySlots.size());
      system.boundarySlots.push_back(slot);
    }
  }
  collectRows(level, system);
  system.nonZeros = pattern.nonZeros();
  const Eigen::SparseMatrix<double> bb = boundaryBlock(level, pattern, system);
  system.boundaryNonZeros = bb.nonZeros();
  if (system.boundaryCount() > 0) system.boundarySolver.analyzePattern(bb);
}

void assignBoundary(const GridLevel& level, const Eigen::SparseMatrix<double>& a,
                    LevelSystem& system) {
  SlotCsr& off = system.offBlock;
  SlotCsr& full = system.fullRows;
  off = {};
  full = {};
  off.ptr.push_back(0);
  full.ptr.push_back(0);
  for (int j = 0; j < system.boundaryCount(); ++j) {
    const int u = level.unknownOfSlot[static_cast<size_t>(system.boundarySlots[static_cast<size_t>(j)])];
    for (SparseIt it(a, u); it; ++it) {
      const int64_t slot = level.slotOfUnknown[static_cast<size_t>(it.row())];
      full.col.push_back(slot);
      full.val.push_back(it.value());
      if (system.boundaryOfUnknown[static_cast<size_t>(it.row())] < 0) {
        off.col.push_back(slot);
        off.val.push_back(it.value());
      }
    }
    off.ptr.push_back(static_cast<int64_t>(off.col.size()));
    full.ptr.push_back(static_cast<int64_t>(full.col.size()));
  }
  assignInteriorNextToBoundary(level, a, system);
  if (system.boundaryCount() > 0) system.boundarySolver.factorize(boundaryBlock(level, a, system));
}

template <typename T>
void assignStencils(const GridLevel& level, const Eigen::SparseMatrix<double>& a,
                    const LevelSystem& system, std::vector<T>& stencils) {
  stencils.assign(static_cast<size_t>(system.stencilSize), T(0));
  auto fillRun = [&](const SlotRow& row, int q) {
    const int64_t n = row.runLength(q);
    T* w = stencils.data() + row.coeffsOf(q);
    for (int64_t i = 0; i < n; ++i) {
      const int64_t s = row.begin + q + 2 * i;
      if (system.kind[static_cast<size_t>(s)] != SlotKind::Interior) continue;
      const int u = level.unknownOfSlot[static_cast<size_t>(s)];
      for (SparseIt it(a, u); it; ++it)
        w[stencilIndex(level, u, static_cast<int>(it.row())) * n + i] = static_cast<T>(it.value());
      const T centre = w[4 * n + i];
      if (!(centre > T(0)))
        throw NumericalError("multigrid: diagonal entry of unknown " + std::to_string(u) +
                             " is not positive; the system matrix must be positive definite");
      w[kInverseDiagonal * n + i] = T(1) / centre;
    }
  };
  for (const std::vector<SlotRow>& rows : system.rows)
    tbb::parallel_for(size_t(0), rows.size(), [&](size_t r) {
      for (int q = 0; q < 2; ++q) fillRun(rows[r], q);
    });
}

template void assignStencils<float>(const GridLevel&, const Eigen::SparseMatrix<double>&,
                                    const LevelSystem&, std::vector<float>&);
template void assignStencils<double>(const GridLevel&, const Eigen::SparseMatrix<double>&,
                                     const LevelSystem&, std::vector<double>&);

}  // namespace texgrad::detail
