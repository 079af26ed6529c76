// Seam-continuous texel basis: node coefficients (1/|n~|) sum_{n in n~} B_t(n) (paper Sec. 4.1)
// on a centroid fan of every piece that touches a seam; plain pieces are exactly bilinear.
#include "texgrad/fem/texel_basis.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>

#include "texgrad/core/error.h"

namespace texgrad::fem {
namespace {

/// Seam parameters closer than this are one point (a few ulps of parameters in [0, 1]), for an
/// edge whose lattice coordinates are no larger than its length.
constexpr double kSameParameter = 64.0 * std::numeric_limits<double>::epsilon();

/// kSameParameter for the two sides of a seam: a crossing's parameter (line - from) / (to - from)
/// carries the rounding of the coordinates, about epsilon times their magnitude over the edge's
/// length, so an edge far from the lattice origin (a large image, a texture page at a large
/// column offset) gets a proportionally wider tolerance.
double sameParameterTolerance(const std::array<Eigen::Vector2d, 2>& from,
                              const std::array<Eigen::Vector2d, 2>& to) {
  double scale = 1.0;
  for (int s = 0; s < 2; ++s) {
    const double length = (to[s] - from[s]).lpNorm<Eigen::Infinity>();
    const double magnitude =
        std::max(from[s].lpNorm<Eigen::Infinity>(), to[s].lpNorm<Eigen::Infinity>());
    if (length > 0.0) scale = std::max(scale, magnitude / length);
  }
  return kSameParameter * scale;
}

}  // namespace

void TexelBasisOptions::validate() const {
  if (kind != BasisKind::SeamContinuous && kind != BasisKind::Bilinear)
    throw InvalidInputError("TexelBasisOptions.kind is not a known basis kind");
}

void mergeWeights(std::vector<TexelWeight>& weights) {
  std::stable_sort(weights.begin(), weights.end(),
                   [](const TexelWeight& a, const TexelWeight& b) { return a.unknown < b.unknown; });
  size_t out = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    if (out > 0 && weights[out - 1].unknown == weights[i].unknown)
      weights[out - 1].weight += weights[i].weight;
    else
      weights[out++] = weights[i];
  }
  weights.resize(out);
  std::erase_if(weights, [](const TexelWeight& w) { return w.weight == 0.0; });
}

std::array<double, 6> quadraticShape(const Eigen::Vector3d& b) {
  return {b[0] * (2.0 * b[0] - 1.0), b[1] * (2.0 * b[1] - 1.0), b[2] * (2.0 * b[2] - 1.0),
          4.0 * b[0] * b[1],         4.0 * b[1] * b[2],         4.0 * b[2] * b[0]};
}

TexelBasis::TexelBasis(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& grid,
                       const TexelBasisOptions& options)
    : mesh_(mesh), grid_(grid), options_(options) {
  options_.validate();
  const int faces = static_cast<int>(mesh.faceCount());
  corners_.resize(faces);
  valid_.assign(faces, 0);
  cumulativeArea_.assign(faces + 1, 0.0);
  for (int f = 0; f < faces; ++f) {
    for (int c = 0; c < 3; ++c) corners_[f][c] = grid.toGrid(mesh.uvs[mesh.uvTriangles[f][c]]);
    const Eigen::Vector2d e1 = corners_[f][1] - corners_[f][0];
    const Eigen::Vector2d e2 = corners_[f][2] - corners_[f][0];
    const double area = 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
    valid_[f] = area != 0.0;
    if (!valid_[f]) ++report_.uvDegenerateFaces;
    cumulativeArea_[f + 1] = cumulativeArea_[f] + std::abs(area);
  }
  seamSideOfEdge_.assign(3 * static_cast<size_t>(faces), -1);
  buildSeams(atlas);
  buildVertexClasses();
}

void TexelBasis::buildSeams(const Atlas& atlas) {
  for (const SeamPair& pair : atlas.seams) {
    if (!valid_[pair.a.face] || !valid_[pair.b.face]) {
      ++report_.skippedSeams;
      continue;
    }
    SeamSplit split;
    split.edge = {pair.a, pair.b};
    split.sameDirection = pair.sameDirection;
    std::array<Eigen::Vector2d, 2> from, to;
    std::array<std::vector<EdgeEvent>, 2> own;
    for (int s = 0; s < 2; ++s) {
      const FaceEdge& e = split.edge[s];
      from[s] = corners_[e.face][e.corner];
      to[s] = corners_[e.face][(e.corner + 1) % 3];
      own[s] = latticeCrossings(from[s], to[s]);
    }
    // Merge both sides' crossings into one parameter sequence along side a (paper Sec. 4.1).
    const double sameParameter = sameParameterTolerance(from, to);
    const bool same = pair.sameDirection;
    std::vector<std::tuple<double, int, int>> merged;  // (t along a, index in own[0], own[1])
    const size_t nb = own[1].size();
    size_t i = 0, j = 0;
    auto bIndex = [&](size_t k) { return same ? k : nb - 1 - k; };
    auto bParam = [&](size_t k) { return same ? own[1][bIndex(k)].t : 1.0 - own[1][bIndex(k)].t; };
    // Crossings within sameParameter are one event (e.g. both sides crossing the same lattice
    // line at the same parameter up to rounding): two events there would give zero-length
    // polygon edges and degenerate fan elements.
    while (i < own[0].size() || j < nb) {
      if (j == nb || (i < own[0].size() && own[0][i].t < bParam(j) - sameParameter)) {
        merged.emplace_back(own[0][i].t, static_cast<int>(i), -1);
        ++i;
      } else if (i == own[0].size() || bParam(j) < own[0][i].t - sameParameter) {
        merged.emplace_back(bParam(j), -1, static_cast<int>(bIndex(j)));
        ++j;
      } else {
        merged.emplace_back(own[0][i].t, static_cast<int>(i), static_cast<int>(bIndex(j)));
        ++i;
        ++j;
      }
    }
    for (int s = 0; s < 2; ++s) {
      std::vector<EdgeEvent>& events = split.side[s];
      events.reserve(merged.size());
      for (size_t k = 0; k < merged.size(); ++k) {
        const auto& [ta, ia, ib] = merged[s == 0 || same ? k : merged.size() - 1 - k];
        const int src = s == 0 ? ia : ib;
        if (src >= 0) {
          events.push_back(own[s][src]);
        } else {
          EdgeEvent e;
          e.t = (s == 0 || same) ? ta : 1.0 - ta;
          e.p = from[s] + e.t * (to[s] - from[s]);
          events.push_back(e);
        }
      }
      makeMonotone(from[s], to[s], events);
    }
    const int index = static_cast<int>(seams_.size());
    for (int s = 0; s < 2; ++s)
      seamSideOfEdge_[3 * split.edge[s].face + split.edge[s].corner] = 2 * index + s;
    seams_.push_back(std::move(split));
  }
}

void TexelBasis::buildVertexClasses() {
  const int faces = faceCount();
  classOfCorner_.assign(3 * static_cast<size_t>(faces), -1);
  if (options_.kind != BasisKind::SeamContinuous || seams_.empty()) return;
  // Nodes: distinct (3-D vertex, UV point) pairs among the corners of valid faces.
  std::vector<int32_t> order;
  for (int k = 0; k < 3 * faces; ++k)
    if (valid_[k / 3]) order.push_back(k);
  auto key = [&](int k) {
    const Eigen::Vector2d& uv = mesh_.uvs[mesh_.uvTriangles[k / 3][k % 3]];
    return std::make_tuple(mesh_.triangles[k / 3][k % 3], uv.x(), uv.y());
  };
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return key(a) < key(b) || (key(a) == key(b) && a < b);
  });
  std::vector<int32_t> nodeOfCorner(3 * static_cast<size_t>(faces), -1), firstCorner;
  for (size_t k = 0; k < order.size(); ++k) {
    if (k == 0 || key(order[k]) != key(order[k - 1]))
      firstCorner.push_back(order[k]);
    nodeOfCorner[order[k]] = static_cast<int32_t>(firstCorner.size()) - 1;
  }
  std::vector<int32_t> parent(firstCorner.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  auto unite = [&](int32_t x, int32_t y) {
    x = find(x);
    y = find(y);
    if (x != y) parent[std::max(x, y)] = std::min(x, y);
  };
  for (const SeamSplit& s : seams_) {
    const FaceEdge &a = s.edge[0], &b = s.edge[1];
    const int a0 = nodeOfCorner[3 * a.face + a.corner];
    const int a1 = nodeOfCorner[3 * a.face + (a.corner + 1) % 3];
    const int b0 = nodeOfCorner[3 * b.face + b.corner];
    const int b1 = nodeOfCorner[3 * b.face + (b.corner + 1) % 3];
    unite(a0, s.sameDirection ? b0 : b1);
    unite(a1, s.sameDirection ? b1 : b0);
  }
  std::vector<std::vector<int32_t>> members(firstCorner.size());
  for (int32_t n = 0; n < static_cast<int32_t>(firstCorner.size()); ++n)
    members[find(n)].push_back(n);
  std::vector<int32_t> classOfRoot(firstCorner.size(), -1);
  classBegin_.assign(1, 0);
  std::vector<TexelWeight> weights;
  for (size_t root = 0; root < members.size(); ++root) {
    if (members[root].size() < 2) continue;
    weights.clear();
    const double share = 1.0 / static_cast<double>(members[root].size());
    for (int32_t n : members[root])
      bilinearWeights(corners_[firstCorner[n] / 3][firstCorner[n] % 3], weights, share);
    mergeWeights(weights);
    classOfRoot[root] = static_cast<int32_t>(classBegin_.size()) - 1;
    classWeights_.insert(classWeights_.end(), weights.begin(), weights.end());
    classBegin_.push_back(static_cast<int32_t>(classWeights_.size()));
  }
  report_.seamVertexClasses = static_cast<int>(classBegin_.size()) - 1;
  for (int k = 0; k < 3 * faces; ++k)
    if (nodeOfCorner[k] >= 0) classOfCorner_[k] = classOfRoot[find(nodeOfCorner[k])];
}

std::array<int32_t, 4> TexelBasis::cellTexels(int a, int b) const {
  std::array<int32_t, 4> out{-1, -1, -1, -1};
  for (int k = 0; k < 4; ++k) {
    const int x = a + (k & 1), y = b + (k >> 1);
    if (x >= 0 && y >= 0 && x < grid_.nx && y < grid_.ny)
      out[k] = grid_.unknownOfTexel[grid_.texelIndex(x, y)];
  }
  return out;
}

void TexelBasis::bilinearWeights(const Eigen::Vector2d& p, std::vector<TexelWeight>& out,
                                 double scale) const {
  const double fa = std::floor(p.x()), fb = std::floor(p.y());
  const int a = static_cast<int>(fa), b = static_cast<int>(fb);
  const double fx = p.x() - fa, fy = p.y() - fb;
  const std::array<double, 4> w{(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy,
                                fx * fy};
  const std::array<int32_t, 4> texels = cellTexels(a, b);
  for (int k = 0; k < 4; ++k)
    if (w[k] != 0.0 && texels[k] >= 0) out.push_back({texels[k], scale * w[k]});
}

void TexelBasis::clipFace(int face, FaceClip& clip) const {
  if (!valid_[face]) {
    clip.vertices.clear();
    clip.pieces.clear();
    return;
  }
  std::array<std::vector<EdgeEvent>, 3> own;
  std::array<std::span<const EdgeEvent>, 3> events;
  for (int e = 0; e < 3; ++e) {
    const int side = seamSide(face, e);
    if (side >= 0) {
      events[e] = seams_[side / 2].side[side % 2];
    } else {
      own[e] = latticeCrossings(corners_[face][e], corners_[face][(e + 1) % 3]);
      events[e] = own[e];
    }
  }
  clipTriangleToCells(corners_[face], events, clip);
}

Eigen::Vector2d TexelBasis::partnerPoint(int side, int index) const {
  const SeamSplit& s = seams_[side / 2];
  const int other = 1 - side % 2;
  const int n = static_cast<int>(s.side[other].size());
  const int k = s.sameDirection ? index : n - 1 - index;
  const FaceEdge& e = s.edge[other];
  if (k < 0) return corners_[e.face][e.corner];
  if (k >= n) return corners_[e.face][(e.corner + 1) % 3];
  return s.side[other][k].p;
}

int TexelBasis::edgeIndex(int face, const PieceVertex& v, int edge) const {
  if (v.corner == edge) return -1;
  if (v.corner >= 0) {
    const int side = seamSide(face, edge);
    return static_cast<int>(seams_[side / 2].side[side % 2].size());
  }
  return v.event;
}

void TexelBasis::vertexWeights(int face, const PieceVertex& v,
                               std::vector<TexelWeight>& out) const {
  if (v.corner >= 0) {
    const int cls = classOfCorner_[3 * face + v.corner];
    if (cls >= 0) {
      out.insert(out.end(), classWeights_.begin() + classBegin_[cls],
                 classWeights_.begin() + classBegin_[cls + 1]);
      return;
    }
  } else if (v.edge >= 0 && seamSide(face, v.edge) >= 0) {
    bilinearWeights(v.p, out, 0.5);
    bilinearWeights(partnerPoint(seamSide(face, v.edge), v.event), out, 0.5);
    return;
  }
  bilinearWeights(v.p, out);
}

void TexelBasis::midpointWeights(int face, const PieceVertex& v, const PieceVertex& w,
                                 std::vector<TexelWeight>& out) const {
  const Eigen::Vector2d mid = 0.5 * (v.p + w.p);
  const uint8_t common = v.edgeMask() & w.edgeMask();
  for (int e = 0; e < 3; ++e) {
    const int side = (common >> e) & 1 ? seamSide(face, e) : -1;
    if (side < 0) continue;
    const Eigen::Vector2d partner =
        0.5 * (partnerPoint(side, edgeIndex(face, v, e)) + partnerPoint(side, edgeIndex(face, w, e)));
    bilinearWeights(mid, out, 0.5);
    bilinearWeights(partner, out, 0.5);
    return;
  }
  bilinearWeights(mid, out);
}

bool TexelBasis::isPlain(int face, std::span<const PieceVertex> polygon) const {
  if (options_.kind == BasisKind::Bilinear) return true;
  const size_t n = polygon.size();
  for (size_t i = 0; i < n; ++i) {
    const PieceVertex& v = polygon[i];
    if (v.corner >= 0 && classOfCorner_[3 * face + v.corner] >= 0) return false;
    if (v.corner < 0 && v.edge >= 0 && seamSide(face, v.edge) >= 0) return false;
    const uint8_t common = v.edgeMask() & polygon[(i + 1) % n].edgeMask();
    for (int e = 0; e < 3; ++e)
      if (((common >> e) & 1) && seamSide(face, e) >= 0) return false;
  }
  return true;
}

void TexelBasis::buildPieceBasis(int face, std::span<const PieceVertex> polygon,
                                 PieceBasis& out) const {
  const size_t n = polygon.size();
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const auto& v : polygon) centre += v.p;
  centre /= static_cast<double>(n);
  // Node weight lists: centre, polygon vertices, centre-vertex midpoints, boundary midpoints.
  std::vector<std::vector<TexelWeight>> nodes(1 + 3 * n);
  bilinearWeights(centre, nodes[0]);
  for (size_t i = 0; i < n; ++i) {
    vertexWeights(face, polygon[i], nodes[1 + i]);
    bilinearWeights(0.5 * (centre + polygon[i].p), nodes[1 + n + i]);
    midpointWeights(face, polygon[i], polygon[(i + 1) % n], nodes[1 + 2 * n + i]);
  }
  out.texels.clear();
  for (auto& node : nodes) {
    mergeWeights(node);
    for (const auto& w : node) out.texels.push_back(w.unknown);
  }
  std::sort(out.texels.begin(), out.texels.end());
  out.texels.erase(std::unique(out.texels.begin(), out.texels.end()), out.texels.end());
  out.elements.resize(n);
  out.coefficients.setZero(static_cast<Eigen::Index>(6 * n),
                           static_cast<Eigen::Index>(out.texels.size()));
  auto fill = [&](Eigen::Index row, const std::vector<TexelWeight>& node) {
    for (const auto& w : node) {
      const auto col = std::lower_bound(out.texels.begin(), out.texels.end(), w.unknown) -
                       out.texels.begin();
      out.coefficients(row, col) = w.weight;
    }
  };
  for (size_t i = 0; i < n; ++i) {
    const size_t j = (i + 1) % n;
    out.elements[i] = {centre, polygon[i].p, polygon[j].p};
    const auto r = static_cast<Eigen::Index>(6 * i);
    fill(r + 0, nodes[0]);
    fill(r + 1, nodes[1 + i]);
    fill(r + 2, nodes[1 + j]);
    fill(r + 3, nodes[1 + n + i]);
    fill(r + 4, nodes[1 + 2 * n + i]);
    fill(r + 5, nodes[1 + n + j]);
  }
}

}  // namespace texgrad::fem
