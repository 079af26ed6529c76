// Solver module (private): line Gauss–Seidel on the interior texels of a level whose stencils
// couple far more strongly along one lattice axis than across it (charts stretched by their
// parameterisation). Point Gauss–Seidel does not smooth errors that vary across such lines; a
// block solve of each line does (the standard remedy for anisotropic operators, e.g. Trottenberg,
// Oosterlee & Schüller, "Multigrid", §5.1). The paper's solver (§6.2) relaxes texels one by one.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "texgrad/solver/grid_hierarchy.h"
#include "texgrad/solver/sparse_sum.h"

namespace texgrad::detail {

struct LevelSystem;

/// Coefficients per line slot: the 6 stencil weights off the line (order of kOffLine), the
/// weights of the previous and the next slot along the line, then the Thomas factors c'_i and
/// 1 / (w_centre - w_prev c'_{i-1}) of the line's tridiagonal block.
constexpr int kLinePlanes = 10;

/// Consecutive interior slots first + i stride (i < count) along one lattice axis.
struct SlotLine {
  int64_t first = 0;
  int32_t count = 0;
  int32_t stride = 1;     ///< 1 along x, the box width along y
  int32_t width = 0;      ///< box width (row stride in slots)
  int64_t coeffs = 0;     ///< offset of slot 0's kLinePlanes coefficients
};

/// The lines of one level, by axis (0: x, 1: y) and by the parity of their lattice coordinate
/// across the axis (zebra order: lines of one parity only read lines of the other).
struct LineSet {
  std::array<std::array<std::vector<SlotLine>, 2>, 2> lines;
  int64_t slotCount = 0;  ///< slots on lines (coefficients: kLinePlanes per slot)
  bool empty() const { return slotCount == 0; }
};

/// Numeric phase: finds the lines of `system` (maximal runs of at least two interior slots whose
/// coupling along the axis exceeds `ratio` times the coupling across it) from the rows of `a`,
/// and fills their coefficients (Thomas factorisation of each line's block, in double).
/// ratio = 0 leaves the set empty.
template <typename T>
void assignLines(const GridLevel& level, const SparseSum& a, const LevelSystem& system,
                 double ratio, LineSet& lines, std::vector<T>& coeffs);

/// One zebra pass of line Gauss–Seidel over every line with the other slots locked: x lines then
/// y lines, even parity first (forward) or the exact reverse (backward, the adjoint), on each of
/// the k channel planes of `plane` slots. The result does not depend on the thread count.
template <typename T>
void relaxLines(const LineSet& lines, const T* coeffs, const T* b, T* x, int k, int64_t plane,
                bool forward);

}  // namespace texgrad::detail
