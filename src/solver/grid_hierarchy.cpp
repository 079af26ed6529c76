// Solver module: builds the per-chart multiresolution texel grids of paper §6.1.
#include "texgrad/solver/grid_hierarchy.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "texgrad/core/error.h"
#include "texgrad/core/storage_bytes.h"

namespace texgrad {
namespace {

/// The high 64 bits of a 64 x 64-bit product (a GCC/Clang extension type, as -Wpedantic wants).
__extension__ using Wide = unsigned __int128;
uint64_t highBits(uint64_t a, uint64_t b) {
  return static_cast<uint64_t>((static_cast<Wide>(a) * b) >> 64);
}

/// Lays out boxes given per-chart inclusive content bounds; charts with empty bounds get no box.
void layoutBoxes(GridLevel& level, const std::vector<std::array<int, 4>>& bounds) {
  level.boxOfChart.assign(bounds.size(), -1);
  int64_t offset = 0;
  for (size_t c = 0; c < bounds.size(); ++c) {
    const auto& [xmin, ymin, xmax, ymax] = bounds[c];
    if (xmin > xmax) continue;
    GridBox box;
    box.chart = static_cast<int>(c);
    box.x0 = xmin - 1;
    box.y0 = ymin - 1;
    box.width = xmax - xmin + 3;
    box.height = ymax - ymin + 3;
    box.offset = offset;
    box.widthReciprocal =
        std::numeric_limits<uint64_t>::max() / static_cast<uint64_t>(box.width) + 1;  // width >= 3
    offset += static_cast<int64_t>(box.width) * box.height;
    level.boxOfChart[c] = static_cast<int32_t>(level.boxes.size());
    level.boxes.push_back(box);
  }
  if (offset > std::numeric_limits<int32_t>::max())
    throw InvalidInputError("GridHierarchy: a level needs " + std::to_string(offset) +
                            " slots, more than 2^31 - 1");
  level.slotCount = offset;
  level.unknownOfSlot.assign(static_cast<size_t>(offset), -1);
  // The box of every page's first slot: boxes follow one another in slot order.
  level.boxOfSlotPage.assign(static_cast<size_t>((offset >> GridLevel::kSlotPageBits) + 1), 0);
  for (size_t k = 0, b = 0; k < level.boxOfSlotPage.size(); ++k) {
    const auto first = static_cast<int64_t>(k) << GridLevel::kSlotPageBits;
    while (b + 1 < level.boxes.size() && level.boxes[b + 1].offset <= first) ++b;
    level.boxOfSlotPage[k] = static_cast<int32_t>(b);
  }
}

std::array<int, 4> emptyBounds() {
  constexpr int kMax = std::numeric_limits<int>::max(), kMin = std::numeric_limits<int>::min();
  return {kMax, kMax, kMin, kMin};
}

void growBounds(std::array<int, 4>& b, int x, int y) {
  b = {std::min(b[0], x), std::min(b[1], y), std::max(b[2], x), std::max(b[3], y)};
}

/// Sizes the per-unknown arrays for `n` unknowns up front (no growth slack stays allocated).
void reserveUnknowns(GridLevel& level, size_t n) {
  level.slotOfUnknown.reserve(n);
  level.footprintInterior.reserve(n);
}

void pushUnknown(GridLevel& level, int64_t slot, bool interior) {
  level.unknownOfSlot[static_cast<size_t>(slot)] = level.unknownCount();
  level.slotOfUnknown.push_back(static_cast<int32_t>(slot));  // < 2^31: layoutBoxes checks
  level.footprintInterior.push_back(interior ? 1 : 0);
}

GridLevel buildFinestLevel(const TexelGrid& grid, int chartCount) {
  GridLevel level;
  std::vector<std::array<int, 4>> bounds(static_cast<size_t>(chartCount), emptyBounds());
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const int t = grid.texelOfUnknown[static_cast<size_t>(u)];
    growBounds(bounds[static_cast<size_t>(grid.chartOfUnknown[static_cast<size_t>(u)])], t % grid.nx,
               t / grid.nx);
  }
  layoutBoxes(level, bounds);
  reserveUnknowns(level, static_cast<size_t>(grid.unknownCount()));
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const size_t t = static_cast<size_t>(grid.texelOfUnknown[static_cast<size_t>(u)]);
    const int chart = grid.chartOfUnknown[static_cast<size_t>(u)];
    const int x = static_cast<int>(t) % grid.nx, y = static_cast<int>(t) / grid.nx;
    const GridBox& box = level.boxes[static_cast<size_t>(level.boxOfChart[static_cast<size_t>(chart)])];
    pushUnknown(level, box.slot(x, y), grid.texelClass[t] == TexelClass::Interior);
  }
  return level;
}

/// Level l + 1: coarse lattice nodes that are bilinear parents of a level-l texel of the same chart
/// (equivalently, whose doubled footprint meets the chart).
GridLevel buildCoarseLevel(const GridLevel& fine) {
  GridLevel coarse;
  std::vector<std::array<int, 4>> bounds(fine.boxOfChart.size(), emptyBounds());
  for (const GridBox& b : fine.boxes) {
    bounds[static_cast<size_t>(b.chart)] = {(b.x0 + 1) / 2, (b.y0 + 1) / 2,
                                            (b.x0 + b.width - 1) / 2, (b.y0 + b.height - 1) / 2};
  }
  layoutBoxes(coarse, bounds);
  std::vector<uint8_t> used(static_cast<size_t>(coarse.slotCount), 0);
  for (int u = 0; u < fine.unknownCount(); ++u) {
    const LatticePoint p = fine.point(u);
    const GridBox& box = coarse.boxOfChartAt(fine.boxes[static_cast<size_t>(p.box)].chart);
    const LatticeParents px = latticeParents(p.x), py = latticeParents(p.y);
    for (int j = 0; j < py.count; ++j)
      for (int i = 0; i < px.count; ++i)
        used[static_cast<size_t>(box.slot(px.index[static_cast<size_t>(i)],
                                          py.index[static_cast<size_t>(j)]))] = 1;
  }
  reserveUnknowns(coarse, static_cast<size_t>(std::count(used.begin(), used.end(), uint8_t{1})));
  for (const GridBox& box : coarse.boxes) {
    const GridBox& fbox = fine.boxes[static_cast<size_t>(fine.boxOfChart[static_cast<size_t>(box.chart)])];
    for (int y = box.y0; y < box.y0 + box.height; ++y) {
      for (int x = box.x0; x < box.x0 + box.width; ++x) {
        const int64_t s = box.slot(x, y);
        if (!used[static_cast<size_t>(s)]) continue;
        bool interior = true;  // all 9 children exist and are footprint-interior
        for (int dy = -1; dy <= 1 && interior; ++dy)
          for (int dx = -1; dx <= 1 && interior; ++dx) {
            const int fx = 2 * x + dx, fy = 2 * y + dy;
            const int fu = fbox.contains(fx, fy)
                               ? fine.unknownOfSlot[static_cast<size_t>(fbox.slot(fx, fy))]
                               : -1;
            interior = fu >= 0 && fine.footprintInterior[static_cast<size_t>(fu)];
          }
        pushUnknown(coarse, s, interior);
      }
    }
  }
  return coarse;
}

/// The inverse of level.slotOfUnknown: per slot, its unknown or -1.
std::vector<int32_t> unknownsOfSlots(const GridLevel& level) {
  std::vector<int32_t> inverse(static_cast<size_t>(level.slotCount), -1);
  for (int u = 0; u < level.unknownCount(); ++u)
    inverse[static_cast<size_t>(level.slotOfUnknown[static_cast<size_t>(u)])] = u;
  return inverse;
}

/// P from `coarse` (whose unknown at each slot is unknownOfCoarseSlot) to `fine`.
Eigen::SparseMatrix<double> buildProlongation(const GridLevel& fine, const GridLevel& coarse,
                                              const std::vector<int32_t>& unknownOfCoarseSlot) {
  // Row-major first: every fine row has at most four parents, known in advance; the column-major
  // copy at the end is one linear pass (setFromTriplets would sort millions of entries).
  using RowMajor = Eigen::SparseMatrix<double, Eigen::RowMajor>;
  const int n = fine.unknownCount();
  RowMajor rows(n, coarse.unknownCount());
  std::vector<int> start(static_cast<size_t>(n) + 1, 0);
  for (int u = 0; u < n; ++u) {
    const size_t su = static_cast<size_t>(u);
    const LatticePoint p = fine.point(u);
    start[su + 1] = start[su] + latticeParents(p.x).count * latticeParents(p.y).count;
  }
  rows.resizeNonZeros(start.back());
  std::copy(start.begin(), start.end(), rows.outerIndexPtr());
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int u = r.begin(); u != r.end(); ++u) {
      const LatticePoint p = fine.point(u);
      const GridBox& box = coarse.boxOfChartAt(fine.boxes[static_cast<size_t>(p.box)].chart);
      const LatticeParents px = latticeParents(p.x), py = latticeParents(p.y);
      int k = start[static_cast<size_t>(u)];
      for (int j = 0; j < py.count; ++j)  // slot order = increasing coarse index
        for (int i = 0; i < px.count; ++i, ++k) {
          const int64_t slot =
              box.slot(px.index[static_cast<size_t>(i)], py.index[static_cast<size_t>(j)]);
          rows.innerIndexPtr()[k] = unknownOfCoarseSlot[static_cast<size_t>(slot)];
          rows.valuePtr()[k] =
              px.weight[static_cast<size_t>(i)] * py.weight[static_cast<size_t>(j)];
        }
    }
  });
  return Eigen::SparseMatrix<double>(rows);
}

}  // namespace

LatticePoint GridLevel::pointOfSlot(int64_t s) const {
  // The boxes' slot ranges are consecutive: the box of s is the last one starting at or before s,
  // searched for between the boxes of s's page's first slot and of the next page's (most pages
  // lie in one box; a page of a coarse level can span many small ones).
  const auto page = static_cast<size_t>(s >> kSlotPageBits);
  const auto first = boxes.begin() + boxOfSlotPage[page];
  const auto last =
      page + 1 < boxOfSlotPage.size() ? boxes.begin() + boxOfSlotPage[page + 1] + 1 : boxes.end();
  const auto after = std::upper_bound(
      first, last, s, [](int64_t slot, const GridBox& box) { return slot < box.offset; });
  const auto b = static_cast<size_t>(after - 1 - boxes.begin());
  const GridBox& box = boxes[b];
  // Quotient and remainder of the slot's place in its box by the box's width through the
  // width's reciprocal, exact for 32-bit operands (Lemire, Kaser & Kurz, "Faster remainder by
  // direct computation", 2019): the set-up asks for the point of every lattice neighbour of
  // every unknown, and a division instruction costs several times the two multiplications.
  const auto local = static_cast<uint32_t>(s - box.offset);  // slots < 2^31
  const uint64_t fraction = box.widthReciprocal * local;     // modulo 2^64
  const auto row = static_cast<int>(highBits(box.widthReciprocal, local));
  const auto column = static_cast<int>(highBits(fraction, static_cast<uint64_t>(box.width)));
  return {static_cast<int>(b), box.x0 + column, box.y0 + row};
}

GridHierarchy GridHierarchy::build(const TexelGrid& grid, int maxLevels, int minCoarseUnknowns) {
  if (maxLevels < 0)
    throw InvalidInputError("GridHierarchy: maxLevels is " + std::to_string(maxLevels) +
                            ", expected >= 0");
  if (static_cast<int>(grid.texelOfUnknown.size()) != grid.unknownCount() ||
      grid.chartOfUnknown.size() != grid.texelOfUnknown.size() ||
      grid.texelClass.size() != static_cast<size_t>(grid.nx) * static_cast<size_t>(grid.ny))
    throw InvalidInputError("GridHierarchy: TexelGrid arrays do not match its nx x ny size");
  GridHierarchy h;
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const int t = grid.texelOfUnknown[static_cast<size_t>(u)];
    const int chart = grid.chartOfUnknown[static_cast<size_t>(u)];
    if (chart < 0)
      throw InvalidInputError("GridHierarchy: active texel " + std::to_string(t) +
                              " has no chart in the TexelGrid");
    h.chartCount_ = std::max(h.chartCount_, chart + 1);
  }
  h.levels_.push_back(buildFinestLevel(grid, h.chartCount_));
  while (h.levelCount() <= maxLevels) {
    const GridLevel& fine = h.levels_.back();
    const bool anyInterior = std::any_of(fine.footprintInterior.begin(),
                                         fine.footprintInterior.end(), [](uint8_t v) { return v; });
    if (fine.unknownCount() < minCoarseUnknowns || !anyInterior) break;
    GridLevel coarse = buildCoarseLevel(fine);
    h.levels_.push_back(std::move(coarse));
  }
  return h;
}

Eigen::SparseMatrix<double> GridHierarchy::prolongation(int l) const {
  if (l < 0 || l + 1 >= levelCount())
    throw InvalidInputError("GridHierarchy::prolongation: level " + std::to_string(l) +
                            " has no coarser level (levels: " + std::to_string(levelCount()) + ")");
  const GridLevel& coarse = level(l + 1);
  if (!coarse.unknownOfSlot.empty())
    return buildProlongation(level(l), coarse, coarse.unknownOfSlot);
  return buildProlongation(level(l), coarse, unknownsOfSlots(coarse));
}

void GridHierarchy::releaseUnknownOfSlot() {
  for (GridLevel& g : levels_) std::vector<int32_t>().swap(g.unknownOfSlot);
}

void GridHierarchy::restoreUnknownOfSlot() {
  for (GridLevel& g : levels_)
    if (g.unknownOfSlot.empty() && g.slotCount > 0) g.unknownOfSlot = unknownsOfSlots(g);
}

int64_t GridHierarchy::storageBytes() const {
  int64_t bytes = capacityBytes(levels_);
  for (const GridLevel& g : levels_)
    bytes += capacityBytes(g.boxes, g.boxOfChart, g.boxOfSlotPage, g.unknownOfSlot, g.slotOfUnknown,
                           g.footprintInterior);
  return bytes;
}

}  // namespace texgrad
