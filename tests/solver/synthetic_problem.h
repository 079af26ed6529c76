// Solver tests: synthetic texel grids (rectangles, discs, L-shapes; Full, Partial and Empty cells)
// with bilinear-FEM mass and stiffness matrices, so solver tests need no mesh.
#pragma once

#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <utility>
#include <vector>

#include "texgrad/lattice/texel_grid.h"

namespace texgrad::test {

/// Coverage and chart of one cell.
struct CellInfo {
  CellCoverage coverage = CellCoverage::Empty;
  int chart = -1;
};

/// A texel grid with M (mass, scaled to unit total area) and S (stiffness), both n x n SPD/PSD.
struct SyntheticProblem {
  TexelGrid grid;
  Eigen::SparseMatrix<double> mass, stiffness;
  /// alpha M + S.
  Eigen::SparseMatrix<double> system(double alpha) const { return alpha * mass + stiffness; }
};

/// Covered area standing for a Partial cell: any area strictly between 0 and 1.
constexpr double kPartialCellArea = 0.5;

/// Builds an nx x ny grid whose cell (a, b) has cellAt(a, b)'s coverage and chart, classified by
/// the library's rule (classifyLattice), so solver tests see the texel classes and numbering
/// that buildTexelGrid gives an atlas with the same coverage.
inline TexelGrid makeGrid(int nx, int ny, const std::function<CellInfo(int, int)>& cellAt) {
  TexelGrid g;
  g.imageWidth = g.nx = nx;
  g.imageHeight = g.ny = ny;
  CellCover cover(g.cellCount());
  for (int b = -1; b < ny; ++b)
    for (int a = -1; a < nx; ++a) {
      const CellInfo c = cellAt(a, b);
      const auto k = static_cast<size_t>(g.cellIndex(a, b));
      cover.area[k] = c.coverage == CellCoverage::Full      ? 1.0
                      : c.coverage == CellCoverage::Partial ? kPartialCellArea
                                                            : 0.0;
      cover.chart[k] = c.coverage == CellCoverage::Empty ? -1 : c.chart;
    }
  classifyLattice(g, std::move(cover));
  return g;
}

/// Diffusion tensor diag(dx, dy) of cell (a, b).
using CellDiffusion = std::function<std::array<double, 2>(int, int)>;

/// Assembles bilinear-FEM mass and stiffness over covered cells (Partial cells weighted 1/2), with
/// diffusion tensor diffusion(a, b) in the stiffness of cell (a, b); mass scaled so the covered
/// area is 1.
inline SyntheticProblem assemble(TexelGrid grid, const CellDiffusion& diffusion) {
  const double mref[4][4] = {{4, 2, 2, 1}, {2, 4, 1, 2}, {2, 1, 4, 2}, {1, 2, 2, 4}};
  const int cx[4] = {0, 1, 0, 1}, cy[4] = {0, 0, 1, 1};
  double area = 0.0;
  for (int b = -1; b < grid.ny; ++b)
    for (int a = -1; a < grid.nx; ++a) {
      const CellCoverage c = grid.cellCoverage[static_cast<size_t>(grid.cellIndex(a, b))];
      area += c == CellCoverage::Full ? 1.0 : c == CellCoverage::Partial ? 0.5 : 0.0;
    }
  std::vector<Eigen::Triplet<double>> mt, st;
  for (int b = 0; b + 1 < grid.ny; ++b)
    for (int a = 0; a + 1 < grid.nx; ++a) {
      const CellCoverage c = grid.cellCoverage[static_cast<size_t>(grid.cellIndex(a, b))];
      if (c == CellCoverage::Empty) continue;
      const double w = c == CellCoverage::Full ? 1.0 : 0.5;
      const auto [dx, dy] = diffusion(a, b);
      int u[4];
      for (int i = 0; i < 4; ++i)
        u[i] = grid.unknownOfTexel[static_cast<size_t>(grid.texelIndex(a + cx[i], b + cy[i]))];
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          mt.emplace_back(u[i], u[j], w * mref[i][j] / 36.0 / area);
          const double sx = (cx[i] ? 1 : -1) * (cx[j] ? 1 : -1) * (cy[i] == cy[j] ? 1.0 / 3 : 1.0 / 6);
          const double sy = (cy[i] ? 1 : -1) * (cy[j] ? 1 : -1) * (cx[i] == cx[j] ? 1.0 / 3 : 1.0 / 6);
          st.emplace_back(u[i], u[j], w * (dx * sx + dy * sy));
        }
    }
  SyntheticProblem p;
  const int n = grid.unknownCount();
  p.grid = std::move(grid);
  p.mass.resize(n, n);
  p.stiffness.resize(n, n);
  p.mass.setFromTriplets(mt.begin(), mt.end());
  p.stiffness.setFromTriplets(st.begin(), st.end());
  return p;
}

/// assemble() with the same diffusion tensor diag(dx, dy) in every cell.
inline SyntheticProblem assemble(TexelGrid grid, double dx = 1.0, double dy = 1.0) {
  return assemble(std::move(grid), [dx, dy](int, int) { return std::array<double, 2>{dx, dy}; });
}

/// Couples texel pairs like a seam does (S += w (e_s - e_t)(e_s - e_t)ᵀ), giving boundary rows
/// far-away entries. The pattern gains the (s, t) entries.
inline void addSeams(SyntheticProblem& p, const std::vector<std::array<int, 2>>& pairs, double w) {
  std::vector<Eigen::Triplet<double>> t;
  for (const auto& [s, r] : pairs) {
    t.emplace_back(s, s, w);
    t.emplace_back(r, r, w);
    t.emplace_back(s, r, -w);
    t.emplace_back(r, s, -w);
  }
  Eigen::SparseMatrix<double> extra(p.stiffness.rows(), p.stiffness.cols());
  extra.setFromTriplets(t.begin(), t.end());
  p.stiffness += extra;
  Eigen::SparseMatrix<double> zero = 0.0 * extra;  // keep M's pattern equal to S's
  p.mass += zero;
}

/// Square chart of n x n Full cells with a ring of Partial cells around it.
inline SyntheticProblem squareProblem(int n, double dx = 1.0, double dy = 1.0) {
  return assemble(makeGrid(n + 3, n + 3, [n](int a, int b) -> CellInfo {
    if (a < 0 || b < 0 || a > n + 1 || b > n + 1) return {};
    if (a == 0 || b == 0 || a == n + 1 || b == n + 1) return {CellCoverage::Partial, 0};
    return {CellCoverage::Full, 0};
  }), dx, dy);
}

/// squareProblem(n) whose cells in the middle third of the rows diffuse `stretch` times more
/// strongly along x than along y (dx = 1, dy = 1 / stretch), or along y with alongY: the part
/// of a chart that its parameterisation stretches.
inline SyntheticProblem stretchedBandProblem(int n, double stretch, bool alongY = false) {
  return assemble(makeGrid(n + 3, n + 3, [n](int a, int b) -> CellInfo {
    if (a < 0 || b < 0 || a > n + 1 || b > n + 1) return {};
    if (a == 0 || b == 0 || a == n + 1 || b == n + 1) return {CellCoverage::Partial, 0};
    return {CellCoverage::Full, 0};
  }), [n, stretch, alongY](int a, int b) {
    const int across = alongY ? a : b;
    if (3 * across < n || 3 * across >= 2 * n) return std::array<double, 2>{1.0, 1.0};
    return alongY ? std::array<double, 2>{1.0 / stretch, 1.0} : std::array<double, 2>{1.0, 1.0 / stretch};
  });
}

/// Three charts (disc, rectangle, L-shape) in a (8s x 6s) grid with seams between their
/// boundaries; s scales the resolution.
inline SyntheticProblem multiChartProblem(int s) {
  const double r = 1.6 * s, cxd = 2.0 * s, cyd = 3.0 * s;
  auto inDisc = [&](double x, double y) { return (x - cxd) * (x - cxd) + (y - cyd) * (y - cyd) < r * r; };
  SyntheticProblem p = assemble(makeGrid(8 * s, 6 * s, [&](int a, int b) -> CellInfo {
    int inside = 0;
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) inside += inDisc(a + i, b + j);
    if (inside == 4) return {CellCoverage::Full, 0};
    if (inside > 0) return {CellCoverage::Partial, 0};
    const int x0 = 4 * s + 2, x1 = 8 * s - 3;
    if (a >= x0 && a < x1 && b >= 2 && b < 3 * s - 2)
      return {(a == x0 || b == 2) ? CellCoverage::Partial : CellCoverage::Full, 1};
    if (a >= x0 && a < x1 && b >= 3 * s + 1 && b < 6 * s - 3 && !(a >= 6 * s && b >= 5 * s))
      return {CellCoverage::Full, 2};
    return {};
  }));
  // Seams like real ones (continuous, density mismatch 1 : 2): the disc's right half, by y, is
  // glued to chart 1's left column; its left half, by y, to chart 2's bottom row, by x.
  auto collect = [&](auto keep, auto key) {
    std::vector<std::pair<int, int>> list;
    for (int u = 0; u < p.grid.unknownCount(); ++u) {
      const int t = p.grid.texelOfUnknown[static_cast<size_t>(u)];
      const int x = t % p.grid.nx, y = t / p.grid.nx;
      if (p.grid.texelClass[static_cast<size_t>(t)] == TexelClass::Boundary &&
          keep(p.grid.chartOfUnknown[static_cast<size_t>(u)], x, y))
        list.push_back({key(x, y), u});
    }
    std::sort(list.begin(), list.end());
    return list;
  };
  const int x0 = 4 * s + 2;
  const auto right = collect([&](int c, int x, int) { return c == 0 && x > cxd; }, [](int x, int y) { return y * 4096 + x; });
  const auto left = collect([&](int c, int x, int) { return c == 0 && x < cxd; }, [](int x, int y) { return y * 4096 + x; });
  const auto edge1 = collect([&](int c, int x, int) { return c == 1 && x == x0; }, [](int, int y) { return y; });
  const auto edge2 = collect([&](int c, int, int y) { return c == 2 && y == 3 * s + 1; }, [](int x, int) { return x; });
  std::vector<std::array<int, 2>> pairs;
  for (size_t i = 0; i < right.size(); ++i)
    pairs.push_back({right[i].second, edge1[i * edge1.size() / right.size()].second});
  for (size_t i = 0; i < left.size(); ++i)
    pairs.push_back({left[i].second, edge2[i * edge2.size() / left.size()].second});
  addSeams(p, pairs, 2.0);
  return p;
}

/// Deterministic pseudo-random n x k block in [-1, 1].
inline Eigen::MatrixXd randomBlock(Eigen::Index n, Eigen::Index k, unsigned seed = 1) {
  Eigen::MatrixXd m(n, k);
  unsigned state = seed * 2654435761u + 12345u;
  for (Eigen::Index j = 0; j < k; ++j)
    for (Eigen::Index i = 0; i < n; ++i) {
      state = state * 1664525u + 1013904223u;
      m(i, j) = (state >> 8) / double(1u << 24) * 2.0 - 1.0;
    }
  return m;
}

}  // namespace texgrad::test
