// Test fixtures for fem/ and operators/: small procedural meshes with known geometry.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <tuple>
#include <vector>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/cell_clipping.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad::test {

/// B_t(p): the bilinear hat of unknown `unknown` at grid point p (texel centres at integers).
inline double bilinear(const TexelGrid& g, int unknown, const Eigen::Vector2d& p) {
  const int t = g.texelOfUnknown[static_cast<size_t>(unknown)];
  const double dx = std::abs(p.x() - t % g.nx), dy = std::abs(p.y() - t / g.nx);
  return std::max(0.0, 1.0 - dx) * std::max(0.0, 1.0 - dy);
}

/// Flat unit square (z = 0) as n x n quads split in two, UV = (u0 + su x, v0 + sv y).
inline TexturedMesh gridSquare(int n, double su = 1.0, double sv = 1.0, double u0 = 0.0,
                               double v0 = 0.0) {
  TexturedMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = double(i) / n, y = double(j) / n;
      m.positions.emplace_back(x, y, 0.0);
      m.uvs.emplace_back(u0 + su * x, v0 + sv * y);
    }
  auto id = [&](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Triangle t0{id(i, j), id(i + 1, j), id(i + 1, j + 1)};
      const Triangle t1{id(i, j), id(i + 1, j + 1), id(i, j + 1)};
      m.triangles.push_back(t0);
      m.uvTriangles.push_back(t0);
      m.triangles.push_back(t1);
      m.uvTriangles.push_back(t1);
    }
  return m;
}

/// Flat unit square cut at x = 1/2 into two charts with different texel densities (ratio
/// `density`), so one seam side receives many points from the other.
inline TexturedMesh twoChartSquare(int n, double density = 0.37) {
  TexturedMesh m;
  auto leftUv = [](double x, double y) {
    return Eigen::Vector2d(0.0537 + 0.8 * x, 0.0611 + 0.8 * y);
  };
  auto rightUv = [&](double x, double y) {
    return Eigen::Vector2d(0.5731 + density * 0.8 * (x - 0.5), 0.0913 + density * 0.8 * y);
  };
  const int half = n;  // quads per half along x
  std::map<std::pair<int, int>, int> pos;
  auto position = [&](int i, int j) {  // i in [0, 2 half], j in [0, n]
    auto [it, added] = pos.try_emplace({i, j}, int(m.positions.size()));
    if (added) m.positions.emplace_back(0.5 * i / half, double(j) / n, 0.0);
    return it->second;
  };
  for (int side = 0; side < 2; ++side) {
    const int base = int(m.uvs.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= half; ++i) {
        const double x = 0.5 * (i + side * half) / half, y = double(j) / n;
        m.uvs.push_back(side == 0 ? leftUv(x, y) : rightUv(x, y));
      }
    auto uv = [&](int i, int j) { return base + j * (half + 1) + i; };
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < half; ++i) {
        const int gi = i + side * half;
        m.triangles.push_back({position(gi, j), position(gi + 1, j), position(gi + 1, j + 1)});
        m.uvTriangles.push_back({uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)});
        m.triangles.push_back({position(gi, j), position(gi + 1, j + 1), position(gi, j + 1)});
        m.uvTriangles.push_back({uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)});
      }
  }
  return m;
}

/// Unit sphere as a projected cube, one chart per cube face in a 3 x 2 atlas with gutters.
inline TexturedMesh cubeSphere(int n) {
  TexturedMesh m;
  std::map<std::array<int, 3>, int> pos;
  const double gutter = 0.03;
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    const bool plus = f % 2 == 0;
    // U x V = outward normal.
    const std::array<std::array<int, 2>, 6> uvAxes{
        {{1, 2}, {2, 1}, {2, 0}, {0, 2}, {0, 1}, {1, 0}}};
    const int au = uvAxes[f][0], av = uvAxes[f][1];
    const int base = int(m.uvs.size());
    const double cu = (f % 3) / 3.0, cv = (f / 3) / 2.0;
    std::vector<int> vid((n + 1) * (n + 1));
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        std::array<int, 3> key{};
        key[axis] = plus ? n : 0;
        key[au] = i;
        key[av] = j;
        auto [it, added] = pos.try_emplace(key, int(m.positions.size()));
        if (added) {
          Eigen::Vector3d c(2.0 * key[0] / n - 1.0, 2.0 * key[1] / n - 1.0, 2.0 * key[2] / n - 1.0);
          m.positions.push_back(c.normalized());
        }
        vid[j * (n + 1) + i] = it->second;
        m.uvs.emplace_back(cu + gutter + (1.0 / 3.0 - 2 * gutter) * i / n,
                           cv + gutter + (0.5 - 2 * gutter) * j / n);
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        auto k = [&](int a, int b) { return b * (n + 1) + a; };
        m.triangles.push_back({vid[k(i, j)], vid[k(i + 1, j)], vid[k(i + 1, j + 1)]});
        m.uvTriangles.push_back({base + k(i, j), base + k(i + 1, j), base + k(i + 1, j + 1)});
        m.triangles.push_back({vid[k(i, j)], vid[k(i + 1, j + 1)], vid[k(i, j + 1)]});
        m.uvTriangles.push_back({base + k(i, j), base + k(i + 1, j + 1), base + k(i, j + 1)});
      }
  }
  return m;
}

}  // namespace texgrad::test
