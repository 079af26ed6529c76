// Solver module: per-chart multiresolution texel grids and bilinear prolongations (paper §6.1).
// Built from the atlas TexelGrid alone; knows nothing about meshes.
#pragma once

#include <Eigen/SparseCore>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "texgrad/lattice/texel_grid.h"

namespace texgrad {

/// Kind of a lattice slot of a hierarchy level.
enum class SlotKind : uint8_t {
  Empty = 0,     ///< no unknown here
  Interior = 1,  ///< relaxed by Gauss–Seidel with a regular 9-point stencil (Fig. 8, R.3/P.6)
  Boundary = 2,  ///< solved directly with interior values locked (Fig. 8, R.5/P.4)
};

/// Rectangle of lattice slots holding one chart's texels at one level, with a one-slot empty ring.
struct GridBox {
  int chart = -1;             ///< chart whose texels live in this box
  int x0 = 0, y0 = 0;         ///< level-lattice coordinates of the box's slot (0, 0)
  int width = 0, height = 0;  ///< size in slots, ring included
  int64_t offset = 0;         ///< index of slot (0, 0) in the level's slot arrays
  /// ceil(2^64 / width), set by GridHierarchy with the box: divides by the width with two
  /// multiplications (GridLevel::pointOfSlot).
  uint64_t widthReciprocal = 0;
  /// Slot index of level-lattice position (x, y), which must lie in the box.
  int64_t slot(int x, int y) const {
    return offset + static_cast<int64_t>(y - y0) * width + (x - x0);
  }
  /// True if level-lattice position (x, y) lies in the box.
  bool contains(int x, int y) const {
    return x >= x0 && y >= y0 && x < x0 + width && y < y0 + height;
  }
};

/// A slot's box (index into GridLevel::boxes) and level-lattice position.
struct LatticePoint {
  int box = -1;
  int x = 0, y = 0;
};

/// Texels of one level. Level-l lattice position (x, y) is fine grid texel (2^l x, 2^l y); the
/// chart origin of every chart is grid texel (0, 0). Unknowns are numbered as in the TexelGrid at
/// level 0 and in slot order at coarser levels. Per unknown only its slot is stored; its box,
/// chart and position follow from the slot (docs/memory.md: 16 bytes per unknown fewer).
struct GridLevel {
  std::vector<GridBox> boxes;          ///< one box per chart present, in increasing offset
  std::vector<int32_t> boxOfChart;     ///< per chart: index into boxes, -1 if absent
  /// Slots per page of boxOfSlotPage, as a power of two.
  static constexpr int kSlotPageBits = 10;
  /// Per page of 2^kSlotPageBits slots: the box (index into boxes) of its first slot; set by
  /// GridHierarchy with the boxes (pointOfSlot reads it).
  std::vector<int32_t> boxOfSlotPage;
  int64_t slotCount = 0;               ///< total slots over all boxes (< 2^31)
  /// Per slot: unknown index or -1 (the inverse of slotOfUnknown). Only a set-up reads it: a
  /// MultigridSolver's hierarchy frees it after each set-up (GridHierarchy::releaseUnknownOfSlot).
  std::vector<int32_t> unknownOfSlot;
  std::vector<int32_t> slotOfUnknown;  ///< per unknown: slot index
  /// Per unknown: footprint [-2^l, 2^l]^2 entirely made of Full cells of its chart (paper §6.1).
  std::vector<uint8_t> footprintInterior;
  /// Number of unknowns at this level.
  int unknownCount() const { return static_cast<int>(slotOfUnknown.size()); }
  /// Box and lattice position of slot s (from its page's box on: boxOfSlotPage).
  LatticePoint pointOfSlot(int64_t s) const;
  /// Box and lattice position of unknown u.
  LatticePoint point(int u) const { return pointOfSlot(slotOfUnknown[static_cast<size_t>(u)]); }
  /// Chart of unknown u.
  int chartOf(int u) const { return boxes[static_cast<size_t>(point(u).box)].chart; }
  /// Box of a chart present at this level.
  const GridBox& boxOfChartAt(int chart) const {
    return boxes[static_cast<size_t>(boxOfChart[static_cast<size_t>(chart)])];
  }
};

/// Coarse parents of a fine lattice coordinate with their bilinear weights (1, or 1/2 twice).
struct LatticeParents {
  int count = 0;
  std::array<int, 2> index{};
  std::array<double, 2> weight{};
};

/// The coarse coordinates whose bilinear hat covers fine coordinate `fine` (paper §6.1).
inline LatticeParents latticeParents(int fine) {
  if (fine % 2 == 0) return {1, {fine / 2, 0}, {1.0, 0.0}};
  return {2, {(fine - 1) / 2, (fine + 1) / 2}, {0.5, 0.5}};
}

/// Per-chart grid hierarchy: levels 0..L. The prolongations P^l (n_l x n_{l+1}) follow from the
/// lattice positions: bilinear up-sampling weights 1, 1/2, 1/4 restricted to texels of the same
/// chart (paper §6.1).
class GridHierarchy {
 public:
  /// Builds levels 0..L from the texel classes of `grid`, with L <= maxLevels; coarsening stops
  /// early when a level has fewer than minCoarseUnknowns unknowns or no footprint-interior texel.
  static GridHierarchy build(const TexelGrid& grid, int maxLevels, int minCoarseUnknowns);

  /// Number of levels including level 0 (L + 1).
  int levelCount() const { return static_cast<int>(levels_.size()); }
  /// Level l (0 = finest, the TexelGrid's unknowns).
  const GridLevel& level(int l) const { return levels_[static_cast<size_t>(l)]; }
  /// Prolongation P^l from level l + 1 to level l, n_l x n_{l+1}; R^l = (P^l)ᵀ. Built on
  /// each call (also after releaseUnknownOfSlot): the solver applies P from the lattice positions
  /// and never stores it.
  Eigen::SparseMatrix<double> prolongation(int l) const;
  /// Number of charts (boxes at level 0 are indexed by chart).
  int chartCount() const { return chartCount_; }
  /// Bytes held by the levels' arrays (their capacity; docs/memory.md).
  int64_t storageBytes() const;
  /// Frees every level's unknownOfSlot, which no V-cycle reads (4 bytes per slot: 8 per active
  /// texel at spot 4096², docs/memory.md), for a solver done with its set-up.
  void releaseUnknownOfSlot();
  /// Rebuilds every freed unknownOfSlot from slotOfUnknown, for a set-up.
  void restoreUnknownOfSlot();

 private:
  std::vector<GridLevel> levels_;
  int chartCount_ = 0;
};

}  // namespace texgrad
