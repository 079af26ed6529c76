// A chart straddling the UV tile border u = 1, and the same surface built directly as its two
// halves joined by a seam: the reference of the wrapped-texture and UDIM-tile cuts (tests/apps,
// tests/cli).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "texgrad/io/textured_mesh.h"

namespace texgrad::test {

/// A bent strip over x, y in [0, 1] whose UVs (0.75 + 0.5 x, 0.1 + 0.8 y) straddle u = 1 (x =
/// 0.5): two faces cross that line through one corner on it and meet at their shared edge's
/// crossing X = (0.5, 0.5), so the cut pieces are triangles and can be built directly.
struct StraddlingStrip {
  std::vector<Eigen::Vector2d> xy{
      {0, 0},   {0.5, 0}, {1, 0},   {0, 0.5}, {0.25, 0.5}, {0.75, 0.5},
      {1, 0.5}, {0, 1},   {0.5, 1}, {1, 1},   {0.5, 0.5}};  // the last is X
  /// Faces (counter-clockwise in x, y); the two crossing faces are 2 and 7.
  std::vector<Triangle> faces{{0, 1, 4}, {0, 4, 3}, {1, 5, 4}, {1, 2, 5}, {2, 6, 5},
                              {3, 4, 7}, {4, 8, 7}, {4, 5, 8}, {5, 9, 8}, {5, 6, 9}};
  /// The pieces of faces 2 and 7: left of u = 1, then right of it.
  std::vector<Triangle> left{{1, 10, 4}, {4, 10, 8}}, right{{1, 5, 10}, {10, 5, 8}};

  Eigen::Vector3d position(int i) const {
    if (i == 10) return 0.5 * (position(4) + position(5));  // on the edge it cuts
    const Eigen::Vector2d& p = xy[static_cast<size_t>(i)];
    return {p.x(), p.y(), 0.3 * p.x() * p.y() + 0.2 * p.x() * p.x()};
  }
  /// Appends face `t` with u shifted by du (each corner its own UV).
  void add(TexturedMesh& m, const Triangle& t, double du) const {
    Triangle uv{};
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector2d& p = xy[static_cast<size_t>(t[c])];
      uv[c] = static_cast<int32_t>(m.uvs.size());
      m.uvs.emplace_back(0.75 + 0.5 * p.x() + du, 0.1 + 0.8 * p.y());
    }
    m.triangles.push_back(t);
    m.uvTriangles.push_back(uv);
  }
  TexturedMesh withPositions() const {
    TexturedMesh m;
    for (int i = 0; i < static_cast<int>(xy.size()); ++i) m.positions.push_back(position(i));
    return m;
  }
  /// One chart: faces joined where their UVs coincide (UVs are per corner, equal by value).
  TexturedMesh straddling() const {
    TexturedMesh m = withPositions();
    for (const Triangle& t : faces) add(m, t, 0.0);
    return m;
  }
  /// The two halves as separate charts: x <= 0.5 at u in [0.75, 1], x >= 0.5 at u in
  /// [1 + rightShift, 1.25 + rightShift] (-1: wrapped into the image; 0: in the next tile).
  TexturedMesh halves(double rightShift) const {
    TexturedMesh m = withPositions();
    for (size_t f : {0, 1, 5, 6}) add(m, faces[f], 0.0);
    for (const Triangle& t : left) add(m, t, 0.0);
    for (size_t f : {3, 4, 8, 9}) add(m, faces[f], rightShift);
    for (const Triangle& t : right) add(m, t, rightShift);
    return m;
  }
};

}  // namespace texgrad::test
