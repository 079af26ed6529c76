// buildAtlas: groups face edges by their welded 3-D endpoints, then joins faces into charts
// across edges whose UV ends coincide and records the other two-face edges as seams.
#include "texgrad/atlas/atlas.h"

#include <algorithm>
#include <limits>
#include <numeric>

namespace texgrad {
namespace {

/// A face edge keyed by its unordered 3-D endpoints, for grouping by sort.
struct KeyedEdge {
  int32_t lo, hi;
  FaceEdge edge;
};

/// Union-find over faces with path halving.
class DisjointSets {
 public:
  explicit DisjointSets(size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int32_t find(int32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void join(int32_t a, int32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<int32_t> parent_;
};

std::vector<KeyedEdge> sortedEdges(const TexturedMesh& mesh) {
  std::vector<KeyedEdge> edges;
  edges.reserve(3 * mesh.faceCount());
  for (int32_t f = 0; f < static_cast<int32_t>(mesh.faceCount()); ++f)
    for (int8_t c = 0; c < 3; ++c) {
      const int32_t a = mesh.triangles[f][c], b = mesh.triangles[f][(c + 1) % 3];
      if (a == b) continue;  // collapsed edge of a degenerate triangle: joins nothing
      edges.push_back({std::min(a, b), std::max(a, b), {f, c}});
    }
  std::sort(edges.begin(), edges.end(), [](const KeyedEdge& x, const KeyedEdge& y) {
    if (x.lo != y.lo) return x.lo < y.lo;
    if (x.hi != y.hi) return x.hi < y.hi;
    if (x.edge.face != y.edge.face) return x.edge.face < y.edge.face;
    return x.edge.corner < y.edge.corner;
  });
  return edges;
}

int32_t vertexAt(const TexturedMesh& m, FaceEdge e, int k) {
  return m.triangles[e.face][(e.corner + k) % 3];
}
const Eigen::Vector2d& uvAt(const TexturedMesh& m, FaceEdge e, int k) {
  return m.uvs[m.uvTriangles[e.face][(e.corner + k) % 3]];
}

/// Classifies a two-face edge: joins the faces' charts or records a seam pair.
void pairEdge(const TexturedMesh& mesh, FaceEdge a, FaceEdge b, DisjointSets& sets, Atlas& atlas) {
  const bool same = vertexAt(mesh, a, 0) == vertexAt(mesh, b, 0);
  const bool coincide = same ? (uvAt(mesh, a, 0) == uvAt(mesh, b, 0) &&
                                uvAt(mesh, a, 1) == uvAt(mesh, b, 1))
                             : (uvAt(mesh, a, 0) == uvAt(mesh, b, 1) &&
                                uvAt(mesh, a, 1) == uvAt(mesh, b, 0));
  if (coincide) {
    sets.join(a.face, b.face);
    return;
  }
  const auto seam = static_cast<int32_t>(atlas.seams.size());
  atlas.seamOfEdge[3 * a.face + a.corner] = seam;
  atlas.seamOfEdge[3 * b.face + b.corner] = seam;
  atlas.seams.push_back({a, b, same});
}

void collectCharts(const TexturedMesh& mesh, DisjointSets& sets, Atlas& atlas) {
  const auto faces = static_cast<int32_t>(mesh.faceCount());
  std::vector<int32_t> chartOfRoot(faces, -1);
  atlas.chartOfFace.resize(faces);
  for (int32_t f = 0; f < faces; ++f) {
    int32_t& chart = chartOfRoot[sets.find(f)];
    if (chart < 0) {
      chart = static_cast<int32_t>(atlas.charts.size());
      Chart fresh;
      fresh.uvMin = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
      fresh.uvMax = -fresh.uvMin;
      atlas.charts.push_back(fresh);
    }
    atlas.chartOfFace[f] = chart;
    Chart& c = atlas.charts[chart];
    c.faces.push_back(f);
    const Eigen::Vector2d& p0 = mesh.uvs[mesh.uvTriangles[f][0]];
    const Eigen::Vector2d e1 = mesh.uvs[mesh.uvTriangles[f][1]] - p0;
    const Eigen::Vector2d e2 = mesh.uvs[mesh.uvTriangles[f][2]] - p0;
    c.uvArea += 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
    for (int k = 0; k < 3; ++k) {
      c.uvMin = c.uvMin.cwiseMin(mesh.uvs[mesh.uvTriangles[f][k]]);
      c.uvMax = c.uvMax.cwiseMax(mesh.uvs[mesh.uvTriangles[f][k]]);
    }
  }
}

}  // namespace

Atlas buildAtlas(const TexturedMesh& mesh) {
  Atlas atlas;
  atlas.seamOfEdge.assign(3 * mesh.faceCount(), -1);
  DisjointSets sets(mesh.faceCount());
  const std::vector<KeyedEdge> edges = sortedEdges(mesh);
  for (size_t begin = 0; begin < edges.size();) {
    size_t end = begin + 1;
    while (end < edges.size() && edges[end].lo == edges[begin].lo &&
           edges[end].hi == edges[begin].hi)
      ++end;
    if (end - begin == 1) {
      atlas.openBoundary.push_back(edges[begin].edge);
    } else if (end - begin == 2) {
      pairEdge(mesh, edges[begin].edge, edges[begin + 1].edge, sets, atlas);
    } else {
      std::vector<FaceEdge> group;
      for (size_t k = begin; k < end; ++k) group.push_back(edges[k].edge);
      atlas.nonManifoldEdges.push_back(std::move(group));
    }
    begin = end;
  }
  collectCharts(mesh, sets, atlas);
  return atlas;
}

}  // namespace texgrad
