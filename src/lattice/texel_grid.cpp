// classifyLattice: cell coverage from the charts' covered area, then texel classes, chart
// ownership and the unknown numbering (the rule stated in include/texgrad/lattice/texel_grid.h).
#include "texgrad/lattice/texel_grid.h"

#include <cmath>
#include <string>
#include <utility>

#include "texgrad/core/error.h"

namespace texgrad {
namespace {

/// Covered area within this of one cell counts as the whole cell: the area is a sum of clipped
/// polygon areas, each exact up to rounding.
constexpr double kAreaTolerance = 1e-9;

void classifyCells(TexelGrid& g, const CellCover& cover) {
  g.cellCoverage.assign(cover.area.size(), CellCoverage::Empty);
  g.overlapCells.clear();
  for (size_t k = 0; k < cover.area.size(); ++k) {
    if (cover.area[k] <= 0.0) continue;
    const bool full = !cover.severalCharts[k] && std::abs(cover.area[k] - 1.0) <= kAreaTolerance;
    g.cellCoverage[k] = full ? CellCoverage::Full : CellCoverage::Partial;
    if (cover.area[k] > 1.0 + kAreaTolerance) g.overlapCells.push_back(static_cast<int32_t>(k));
  }
}

void classifyTexels(TexelGrid& g, const PageVector<uint8_t>& severalChartsInCell) {
  const size_t texels = static_cast<size_t>(g.nx) * static_cast<size_t>(g.ny);
  g.texelClass.assign(texels, TexelClass::Inactive);
  g.texelOfUnknown.clear();
  g.chartOfUnknown.clear();
  g.multiChartTexels.clear();
  for (int y = 0; y < g.ny; ++y)
    for (int x = 0; x < g.nx; ++x) {
      int covered = 0, full = 0;
      int32_t chart = -1;
      bool severalCharts = false;
      for (int b = y - 1; b <= y; ++b)
        for (int a = x - 1; a <= x; ++a) {
          const int cell = g.cellIndex(a, b);
          if (g.cellCoverage[cell] == CellCoverage::Empty) continue;
          ++covered;
          full += g.cellCoverage[cell] == CellCoverage::Full;
          severalCharts |=
              severalChartsInCell[cell] != 0 || (chart >= 0 && chart != g.cellChart[cell]);
          if (chart < 0 || g.cellChart[cell] < chart) chart = g.cellChart[cell];
        }
      if (covered == 0) continue;
      const int t = g.texelIndex(x, y);
      g.texelClass[t] = full == 4 && !severalCharts ? TexelClass::Interior : TexelClass::Boundary;
      if (severalCharts) g.multiChartTexels.push_back(t);
      g.texelOfUnknown.push_back(t);
      g.chartOfUnknown.push_back(chart);
    }
  // Grown by push_back, up to twice their size: trimmed, as they live through the whole job.
  g.texelOfUnknown.shrink_to_fit();
  g.chartOfUnknown.shrink_to_fit();
  g.unknownOfTexel = TexelUnknowns(texels, g.texelOfUnknown);
}

}  // namespace

void classifyLattice(TexelGrid& grid, CellCover cover) {
  const size_t cells = grid.cellCount();
  if (cover.area.size() != cells || cover.chart.size() != cells ||
      cover.severalCharts.size() != cells)
    throw InvalidInputError("cell cover has " + std::to_string(cover.area.size()) + " cells, the " +
                            std::to_string(grid.nx) + "x" + std::to_string(grid.ny) +
                            " texel grid has " + std::to_string(cells));
  classifyCells(grid, cover);
  grid.cellChart = std::move(cover.chart);
  classifyTexels(grid, cover.severalCharts);
}

}  // namespace texgrad
