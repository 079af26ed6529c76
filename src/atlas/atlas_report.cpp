// analyzeAtlas: counts, per-chart sizes and every class of input problem texgrad knows about,
// each with the offending ids and one sentence on what it means for processing.
#include "texgrad/atlas/atlas_report.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <deque>
#include <numeric>

namespace texgrad {
namespace {

/// Union-find over int32 ids.
struct Sets {
  std::vector<int32_t> parent;
  explicit Sets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int32_t find(int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(int32_t a, int32_t b) { parent[find(a)] = find(b); }
};

double uvArea2(const TexturedMesh& m, int32_t f) {
  const Eigen::Vector2d& a = m.uvs[m.uvTriangles[f][0]];
  const Eigen::Vector2d e1 = m.uvs[m.uvTriangles[f][1]] - a, e2 = m.uvs[m.uvTriangles[f][2]] - a;
  return e1.x() * e2.y() - e1.y() * e2.x();
}

int64_t surfaceComponents(const TexturedMesh& m) {
  Sets sets(m.positions.size());
  std::vector<uint8_t> used(m.positions.size(), 0);
  for (const Triangle& t : m.triangles) {
    sets.join(t[0], t[1]);
    sets.join(t[1], t[2]);
    for (int32_t v : t) used[v] = 1;
  }
  int64_t count = 0;
  for (size_t v = 0; v < used.size(); ++v)
    count += used[v] && sets.find(static_cast<int32_t>(v)) == static_cast<int32_t>(v);
  return count;
}

/// Vertices whose incident faces form more than one edge-connected fan (bow-ties and vertices on
/// non-manifold edges): corners are joined across manifold edges and counted per vertex.
std::vector<int64_t> nonManifoldVertices(const TexturedMesh& m) {
  const auto faces = static_cast<int32_t>(m.faceCount());
  Sets corners(3 * m.faceCount());
  auto cornerOf = [&](int32_t f, int32_t v) {
    for (int k = 0; k < 3; ++k)
      if (m.triangles[f][k] == v) return 3 * f + k;
    return 3 * f;
  };
  auto joinAcross = [&](FaceEdge a, FaceEdge b) {
    for (int k = 0; k < 2; ++k) {
      const int32_t v = m.triangles[a.face][(a.corner + k) % 3];
      corners.join(cornerOf(a.face, v), cornerOf(b.face, v));
    }
  };
  // Manifold edges: every edge appearing in exactly two faces (seams and chart-interior edges).
  std::vector<std::pair<std::pair<int32_t, int32_t>, FaceEdge>> edges;
  for (int32_t f = 0; f < faces; ++f)
    for (int8_t c = 0; c < 3; ++c) {
      const int32_t a = m.triangles[f][c], b = m.triangles[f][(c + 1) % 3];
      if (a != b) edges.push_back({{std::min(a, b), std::max(a, b)}, {f, c}});
    }
  std::sort(edges.begin(), edges.end(), [](const auto& x, const auto& y) {
    return x.first < y.first || (x.first == y.first && x.second.face < y.second.face);
  });
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 2) joinAcross(edges[i].second, edges[i + 1].second);
    i = j;
  }
  std::vector<int32_t> firstRoot(m.positions.size(), -1);
  std::vector<bool> flagged(m.positions.size(), false);
  for (int32_t f = 0; f < faces; ++f)
    for (int k = 0; k < 3; ++k) {
      const int32_t v = m.triangles[f][k];
      const int32_t root = corners.find(3 * f + k);
      if (firstRoot[v] < 0) firstRoot[v] = root;
      else if (firstRoot[v] != root) flagged[v] = true;
    }
  std::vector<int64_t> ids;
  for (size_t v = 0; v < flagged.size(); ++v)
    if (flagged[v]) ids.push_back(static_cast<int64_t>(v));
  return ids;
}

void addIssue(AtlasReport& r, std::string kind, std::string meaning, std::vector<int64_t> ids,
              std::string idKind, bool blocking = false) {
  if (ids.empty()) return;
  r.issues.push_back({std::move(kind), std::move(meaning), std::move(ids), std::move(idKind),
                      blocking});
}

/// The UVs outside the unit square of their face's page: [0,1]^2 shifted to the face's UDIM
/// tile (k, l) when `pages` is given (a UDIM mesh keeps its UVs in their tiles), else [0,1]^2.
std::vector<int64_t> uvsOutsidePages(const TexturedMesh& m, const PageLayout* pages) {
  std::vector<char> outside(m.uvs.size(), 0);
  for (size_t f = 0; f < m.faceCount(); ++f) {
    Eigen::Vector2d tile = Eigen::Vector2d::Zero();
    if (pages) {
      const TexturePage& page = pages->pages[static_cast<size_t>(pages->facePage[f])];
      tile = Eigen::Vector2d(page.tileU, page.tileV);
    }
    for (int32_t t : m.uvTriangles[f]) {
      const Eigen::Vector2d uv = m.uvs[static_cast<size_t>(t)] - tile;
      if (uv.x() < 0.0 || uv.y() < 0.0 || uv.x() > 1.0 || uv.y() > 1.0)
        outside[static_cast<size_t>(t)] = 1;
    }
  }
  std::vector<int64_t> ids;
  for (size_t k = 0; k < outside.size(); ++k)
    if (outside[k]) ids.push_back(static_cast<int64_t>(k));
  return ids;
}

void meshIssues(const TexturedMesh& m, const Atlas& atlas, const PageLayout* pages,
                AtlasReport& r) {
  std::vector<int64_t> degenerate3d, degenerateUv, flipped;
  for (int32_t f = 0; f < static_cast<int32_t>(m.faceCount()); ++f) {
    const Triangle& t = m.triangles[f];
    const Eigen::Vector3d e1 = m.positions[t[1]] - m.positions[t[0]];
    const Eigen::Vector3d e2 = m.positions[t[2]] - m.positions[t[0]];
    const double scale = std::max({e1.squaredNorm(), e2.squaredNorm(), 1e-300});
    if (e1.cross(e2).norm() <= 1e-12 * scale) degenerate3d.push_back(f);
    const double a = uvArea2(m, f);
    if (a == 0.0) degenerateUv.push_back(f);
    if (a < 0.0) flipped.push_back(f);
  }
  addIssue(r, "degenerate-3d-triangles",
           "faces with (near) zero surface area; they carry no metric and are ignored by the "
           "operators",
           std::move(degenerate3d), "face");
  addIssue(r, "degenerate-uv-triangles",
           "faces with zero UV area; they cover no texels, so their surface gets no texture",
           std::move(degenerateUv), "face");
  addIssue(r, "flipped-uv-triangles",
           "faces with clockwise (mirrored) UVs; processed correctly, but a mirrored region "
           "shares texels with nothing else only if it does not overlap other charts",
           std::move(flipped), "face");
  addIssue(r, "uvs-outside-unit-square",
           "texture coordinates outside [0,1] (of their UDIM tile, for tiles); texels beyond the "
           "image edge are solved but cannot be stored, so the renderer's clamp/wrap decides "
           "what shows there",
           uvsOutsidePages(m, pages), "uv");
  std::vector<int64_t> nonManifoldEdgeFaces;
  for (const auto& group : atlas.nonManifoldEdges)
    for (const FaceEdge& e : group) nonManifoldEdgeFaces.push_back(e.face);
  addIssue(r, "non-manifold-edges",
           "edges shared by three or more faces; they never join charts or form seams, so the "
           "faces meeting there are treated as cut apart",
           std::move(nonManifoldEdgeFaces), "face");
  addIssue(r, "non-manifold-vertices",
           "vertices where separate fans of faces touch (bow-ties); harmless for texel processing",
           nonManifoldVertices(m), "vertex");
}

/// Minimum number of empty cells between two different charts (multi-source BFS over cells,
/// 8-connected), or nothing if the atlas has a single chart.
std::optional<double> minGutter(const TexelGrid& g) {
  const int cw = g.nx + 1, ch = g.ny + 1;
  std::vector<int32_t> label(g.cellChart.begin(), g.cellChart.end());
  std::vector<int32_t> dist(label.size(), -1);
  std::deque<int32_t> queue;
  for (size_t k = 0; k < label.size(); ++k)
    if (g.cellCoverage[k] != CellCoverage::Empty) {
      dist[k] = 0;
      queue.push_back(static_cast<int32_t>(k));
    } else {
      label[k] = -1;
    }
  std::optional<double> best;
  auto consider = [&](int64_t gutter) {
    if (!best || static_cast<double>(gutter) < *best) best = static_cast<double>(gutter);
  };
  if (!g.multiChartTexels.empty()) consider(0);
  while (!queue.empty()) {
    const int32_t k = queue.front();
    queue.pop_front();
    if (best && dist[k] > *best) break;
    const int x = k % cw, y = k / cw;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nxp = x + dx, nyp = y + dy;
        if ((dx == 0 && dy == 0) || nxp < 0 || nyp < 0 || nxp >= cw || nyp >= ch) continue;
        const int32_t n = nyp * cw + nxp;
        if (dist[n] < 0) {
          dist[n] = dist[k] + 1;
          label[n] = label[k];
          queue.push_back(n);
        } else if (label[n] != label[k]) {
          consider(dist[n] + dist[k]);
        }
      }
  }
  return best;
}

TexelStats texelStats(const TexelGrid& g) {
  TexelStats s;
  s.width = g.imageWidth;
  s.height = g.imageHeight;
  std::vector<uint8_t> touches;
  for (int32_t t : g.texelOfUnknown) {
    ++s.active;
    if (g.texelClass[t] == TexelClass::Interior) ++s.interior;
    else ++s.boundary;
    const int x = t % g.nx, y = t / g.nx;
    const int i = x + g.x0, j = y + g.y0;
    const bool outside = !g.inImage(x, y);
    s.texelsOutsideImage += outside;
    const int32_t chart = g.chartOfTexel(static_cast<size_t>(t));
    if (outside || i == 0 || j == 0 || i == g.imageWidth - 1 || j == g.imageHeight - 1) {
      if (touches.size() <= static_cast<size_t>(chart)) touches.resize(chart + 1, 0);
      touches[chart] = 1;
    }
  }
  for (size_t c = 0; c < touches.size(); ++c)
    if (touches[c]) s.chartsTouchingBorder.push_back(static_cast<int32_t>(c));
  s.multiChartTexels = static_cast<int64_t>(g.multiChartTexels.size());
  s.minGutterTexels = minGutter(g);
  return s;
}

void texelIssues(const TexelGrid& g, const TexelStats& s, AtlasReport& r) {
  std::vector<int64_t> multi(g.multiChartTexels.begin(), g.multiChartTexels.end());
  addIssue(r, "texels-meeting-two-charts",
           "texels whose footprint meets two charts (gutter under 2 texels); their value is shared "
           "by both charts, which couples them",
           std::move(multi), "texel");
  std::vector<int64_t> overlap(g.overlapCells.begin(), g.overlapCells.end());
  addIssue(r, "overlapping-uv-regions",
           "cells covered by UV triangles more than once (stacked or folded UVs): several surface "
           "points share these texels, so they cannot hold different values",
           std::move(overlap), "cell");
  std::vector<int64_t> border(s.chartsTouchingBorder.begin(), s.chartsTouchingBorder.end());
  addIssue(r, "charts-touching-image-border",
           "charts whose texels reach the image edge; texels beyond it are solved but not stored",
           std::move(border), "chart");
}

}  // namespace

AtlasReport analyzeAtlas(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid* grid,
                         const PageLayout* pages) {
  AtlasReport r;
  r.vertices = static_cast<int64_t>(mesh.positions.size());
  r.uvVertices = static_cast<int64_t>(mesh.uvs.size());
  r.faces = static_cast<int64_t>(mesh.faceCount());
  r.charts = static_cast<int64_t>(atlas.charts.size());
  r.seamEdges = static_cast<int64_t>(atlas.seams.size());
  r.boundaryEdges = static_cast<int64_t>(atlas.openBoundary.size());
  r.nonManifoldEdges = static_cast<int64_t>(atlas.nonManifoldEdges.size());
  r.connectedComponents = surfaceComponents(mesh);
  for (const Chart& c : atlas.charts) {
    r.chartFaceCounts.push_back(static_cast<int64_t>(c.faces.size()));
    r.chartUvAreas.push_back(c.uvArea);
  }
  meshIssues(mesh, atlas, pages, r);
  if (grid) {
    r.texels = texelStats(*grid);
    texelIssues(*grid, *r.texels, r);
  }
  return r;
}

}  // namespace texgrad
