// Solver module (private): interior/boundary split of one level and its numeric assignment.
#include "solver/level_system.h"

#include <tbb/parallel_for.h>

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

void collectRows(const GridLevel& level, LevelSystem& system) {
  for (int p = 0; p < 2; ++p) system.rows[p].clear();
  for (const GridBox& box : level.boxes) {
    for (int r = 1; r + 1 < box.height; ++r) {
      const int64_t rowStart = box.offset + static_cast<int64_t>(r) * box.width;
      int64_t first = -1, last = -1;
      for (int64_t s = rowStart; s < rowStart + box.width; ++s) {
        if (system.kind[static_cast<size_t>(s)] != SlotKind::Interior) continue;
        if (first < 0) first = s;
        last = s;
      }
      if (first < 0) continue;
      const int x = box.x0 + static_cast<int>(first - rowStart);
      const int y = box.y0 + r;
      system.rows[y & 1].push_back({first, last + 1, box.width, x & 1});
    }
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

}  // namespace

Eigen::SparseMatrix<double> onesLike(const Eigen::SparseMatrix<double>& a) {
  Eigen::SparseMatrix<double> ones = a;
  ones.makeCompressed();
  std::fill(ones.valuePtr(), ones.valuePtr() + ones.nonZeros(), 1.0);
  return ones;
}

void classifyLevel(const GridLevel& level, const Eigen::SparseMatrix<double>& pattern,
                   LevelSystem& system) {
  const int n = level.unknownCount();
  if (pattern.rows() != n || pattern.cols() != n)
    throw InvalidInputError("multigrid: matrix is " + std::to_string(pattern.rows()) + " x " +
                            std::to_string(pattern.cols()) + " but the level has " +
                            std::to_string(n) + " unknowns");
  system.kind.assign(static_cast<size_t>(level.slotCount), SlotKind::Empty);
  system.boundaryOfUnknown.assign(static_cast<size_t>(n), -1);
  system.boundarySlots.clear();
  system.interiorUnknowns.clear();
  for (int u = 0; u < n; ++u) {
    const size_t su = static_cast<size_t>(u);
    const int64_t slot = level.slotOfUnknown[su];
    if (level.footprintInterior[su] && rowIsStencil(level, pattern, u)) {
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
  if (system.boundaryCount() > 0) system.boundarySolver.factorize(boundaryBlock(level, a, system));
}

template <typename T>
void assignStencils(const GridLevel& level, const Eigen::SparseMatrix<double>& a,
                    const LevelSystem& system, std::vector<T>& stencils) {
  stencils.resize(static_cast<size_t>(level.slotCount) * 9);
  tbb::parallel_for(0, system.interiorCount(), [&](int i) {
    const int u = system.interiorUnknowns[static_cast<size_t>(i)];
    T* w = stencils.data() + level.slotOfUnknown[static_cast<size_t>(u)] * 9;
    std::fill(w, w + 9, T(0));
    for (SparseIt it(a, u); it; ++it) w[stencilIndex(level, u, static_cast<int>(it.row()))] = static_cast<T>(it.value());
    if (!(w[4] > T(0)))
      throw NumericalError("multigrid: diagonal entry of unknown " + std::to_string(u) +
                           " is not positive; the system matrix must be positive definite");
  });
}

template void assignStencils<float>(const GridLevel&, const Eigen::SparseMatrix<double>&,
                                    const LevelSystem&, std::vector<float>&);
template void assignStencils<double>(const GridLevel&, const Eigen::SparseMatrix<double>&,
                                     const LevelSystem&, std::vector<double>&);

}  // namespace texgrad::detail
