// The texel lattice: cells between texel centres, their coverage by the charts, and the one rule
// that turns cell coverage into texel classes, chart ownership and the unknown numbering. Knows
// no mesh: atlas/ rasterises a mesh into cell coverage, solver/ reads the classes.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

#include "texgrad/core/page_allocator.h"
#include "texgrad/lattice/texel_unknowns.h"

namespace texgrad {

/// Class of a texel by how its footprint (the 2 x 2 cells around it) meets the atlas domain M.
enum class TexelClass : uint8_t {
  Inactive = 0,  ///< footprint does not meet M (area 0)
  Interior = 1,  ///< footprint inside a single chart
  Boundary = 2,  ///< footprint meets M but is not inside one chart
};

/// Coverage of one lattice cell (unit square between four texel centres) by the atlas.
enum class CellCoverage : uint8_t {
  Empty = 0,    ///< no chart overlaps the cell with positive area
  Partial = 1,  ///< at least one chart overlaps it, but it is not entirely inside one chart
  Full = 2,     ///< the cell lies entirely inside a single chart
};

/// Distance in texels within which a grid coordinate of the mesh is taken to lie on its lattice
/// line. UVs that an exporter snapped to texel centres are off the lattice by their rounding (up
/// to ~1e-3 texel for float UVs at 16K, ~1e-13 for doubles at sizes that are not powers of two);
/// left there, every chart edge on a lattice line cuts sliver pieces as thin as that offset,
/// whose texels have near-zero mass and whose seam nodes make the basis ramp across the sliver,
/// so the solution jumps by orders of magnitude between the aligned mesh and the same mesh moved
/// by 1e-4 texel. Moving such coordinates onto the line moves the surface by at most this much
/// in the texture and makes the discretisation continuous there.
inline constexpr double kLatticeSnapTexels = 1.0 / 256.0;

/// Grid coordinate c moved onto the nearest lattice line (integer) if within kLatticeSnapTexels.
inline double snapToLattice(double c) {
  const double line = std::nearbyint(c);
  return std::abs(c - line) <= kLatticeSnapTexels ? line : c;
}

/// Texel lattice for a W x H texture. Continuous texel coordinates p = (u W - 0.5, v H - 0.5)
/// put texel centres on the integer lattice; cell (a, b) is the square [a, a+1] x [b, b+1].
///
/// The grid spans every texel any chart can touch, so it may extend beyond the image when UVs
/// leave [0, 1] or charts touch the border: grid texel (x, y) is image texel (x + x0, y + y0).
/// Texels outside the image are solved like any other but are not stored in output images.
struct TexelGrid {
  int imageWidth = 0, imageHeight = 0;  ///< W, H of the texture
  int x0 = 0, y0 = 0;                   ///< image coordinates of grid texel (0, 0)
  int nx = 0, ny = 0;                   ///< grid size in texels

  /// Per grid texel (y * nx + x): class.
  std::vector<TexelClass> texelClass;
  /// Per grid texel: unknown index (active texels numbered in row-major grid order) or -1.
  TexelUnknowns unknownOfTexel;
  /// Per unknown: grid texel index (y * nx + x).
  std::vector<int32_t> texelOfUnknown;
  /// Per unknown: owning chart; for a texel whose footprint meets several charts, the chart
  /// with the smallest index (listed in multiChartTexels). Per unknown, not per grid texel: half
  /// the bytes at 50% coverage (docs/memory.md).
  std::vector<int32_t> chartOfUnknown;
  /// Grid texels whose footprint meets two or more charts (the paper assumes none).
  std::vector<int32_t> multiChartTexels;

  /// Cells: cell (a, b) of the grid is stored at (b + 1) * (nx + 1) + (a + 1), a in [-1, nx-1].
  /// Per cell: coverage, and the chart covering it (-1 if empty; smallest index if several).
  std::vector<CellCoverage> cellCoverage;
  /// (Pages of its own: a one-shot run frees it right after the classification, docs/memory.md.)
  PageVector<int32_t> cellChart;
  /// Cells whose covered area exceeds the cell (stacked or folded UVs: several surface points
  /// per texel), as cell indices.
  std::vector<int32_t> overlapCells;

  /// Number of active texels (unknowns).
  int unknownCount() const { return static_cast<int>(texelOfUnknown.size()); }
  /// Number of cells, (nx + 1) * (ny + 1).
  size_t cellCount() const { return static_cast<size_t>(nx + 1) * static_cast<size_t>(ny + 1); }
  /// Linear index of grid texel (x, y).
  int texelIndex(int x, int y) const { return y * nx + x; }
  /// Owning chart of grid texel t (chartOfUnknown), -1 if it is inactive.
  int32_t chartOfTexel(size_t t) const {
    const int32_t u = unknownOfTexel[t];
    return u < 0 ? -1 : chartOfUnknown[static_cast<size_t>(u)];
  }
  /// Linear index of grid cell (a, b), a in [-1, nx - 1], b in [-1, ny - 1].
  int cellIndex(int a, int b) const { return (b + 1) * (nx + 1) + (a + 1); }
  /// Converts a UV point to continuous grid coordinates (texel centres at integers); coordinates
  /// within kLatticeSnapTexels of a lattice line are put on it (all mesh corners pass here).
  Eigen::Vector2d toGrid(const Eigen::Vector2d& uv) const {
    return {snapToLattice(uv.x() * imageWidth - 0.5) - x0,
            snapToLattice(uv.y() * imageHeight - 0.5) - y0};
  }
  /// Converts continuous grid coordinates back to UV.
  Eigen::Vector2d toUv(const Eigen::Vector2d& p) const {
    return {(p.x() + x0 + 0.5) / imageWidth, (p.y() + y0 + 0.5) / imageHeight};
  }
  /// True if grid texel (x, y) lies inside the image.
  bool inImage(int x, int y) const {
    const int i = x + x0, j = y + y0;
    return i >= 0 && j >= 0 && i < imageWidth && j < imageHeight;
  }
};

/// What the charts put into each cell of a grid, indexed like TexelGrid cells (cellIndex). It
/// lives only while the grid is built, so its arrays have pages of their own (PageVector): in a
/// heap that keeps freed memory, 13 bytes per image texel would stay resident, unused, below
/// everything allocated after them (docs/memory.md).
struct CellCover {
  /// Per cell: area covered by the charts, in cells (above 1 where UVs stack or fold).
  PageVector<double> area;
  /// Per cell: smallest index of a chart overlapping the cell with positive area, -1 if none.
  PageVector<int32_t> chart;
  /// Per cell: 1 if two or more charts overlap the cell with positive area.
  PageVector<uint8_t> severalCharts;

  /// An all-empty cover of `cells` cells.
  explicit CellCover(size_t cells) : area(cells, 0.0), chart(cells, -1), severalCharts(cells, 0) {}
};

/// Classifies the lattice of `grid` (whose size and image placement are set) from the charts'
/// cover of its cells, which must hold grid.cellCount() cells. A cell is Full when one chart
/// covers all of it, Partial when charts cover part of it (or several charts share it), Empty
/// otherwise. A texel is active when a footprint cell is not Empty, Interior when its four
/// footprint cells are Full in one chart, Boundary otherwise; it belongs to the smallest chart
/// meeting its footprint. Active texels are numbered in row-major grid order. Sets every
/// per-cell and per-texel field of `grid`; throws InvalidInputError if the cover's size is wrong.
void classifyLattice(TexelGrid& grid, CellCover cover);

}  // namespace texgrad
