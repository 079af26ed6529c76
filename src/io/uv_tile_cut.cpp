// Cutting faces at integer UV lines (cutAtTileBorders): each face's tile span, the 3-D points made
// on cut edges (shared by every face on the edge), each piece clipped and triangulated.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <unordered_map>

#include "texgrad/io/uv_tiles.h"
#include "uv_tile_keys.h"

namespace texgrad {
namespace {

using uv_tiles::lineAt;
using uv_tiles::NewUvKey;
using uv_tiles::NewUvKeyHash;

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

/// Cut points on one edge whose parameters differ by less than this (a fraction of the edge) are
/// one point. Two faces across a seam can be cut at the same 3-D point by lines on both sides;
/// their parameters then differ only by rounding, and two points that close would leave
/// zero-area slivers between them. Small enough that the kept point lies within
/// kTileBorderTolerance of the other face's line on any edge shorter than 10^5 tiles, so each
/// face still sees its own cut on its line.
constexpr double kEdgeParameterMerge = 1e-12;

/// Tiles that faces crossing a tile border may reach into beyond their first before the cut is
/// refused: each becomes at least one more triangle (about 100 bytes with its new points), so
/// this bounds the cut to a few hundred MiB. A floor repeating its texture 100 x 100 times over
/// two triangles reaches into 2 x 10^4 tiles.
constexpr int64_t kMaxExtraTiles = int64_t{1} << 22;

/// -1, 0 or +1: x below `line`, on it (within kTileBorderTolerance) or above it.
int side(double x, int32_t line) {
  const double d = x - line;
  if (std::abs(d) <= kTileBorderTolerance) return 0;
  return d < 0.0 ? -1 : 1;
}

/// The tiles [lo, hi] one face covers along an axis, from its corners' coordinates: a corner on
/// line L touches tiles L - 1 and L without reaching into either, so it leaves the range to the
/// other corners; a face with every corner on one line is in the tile above it.
struct TileSpan {
  int32_t lo = 0, hi = 0;
};
TileSpan faceSpan(const std::array<double, 3>& x) {
  int32_t lo = std::numeric_limits<int32_t>::max(), hi = std::numeric_limits<int32_t>::min();
  for (double c : x) {
    if (const std::optional<int32_t> line = lineAt(c)) {
      lo = std::min(lo, *line);
      hi = std::max(hi, *line - 1);
    } else {
      const auto tile = static_cast<int32_t>(std::floor(c));
      lo = std::min(lo, tile);
      hi = std::max(hi, tile);
    }
  }
  return {lo, std::max(lo, hi)};
}

std::string uvText(const Vec2& uv) {
  char text[64];
  std::snprintf(text, sizeof text, "(%.9g, %.9g)", uv.x(), uv.y());
  return text;
}

/// Undirected 3-D edge as one number (smaller position index in the high half).
uint64_t edgeKey(int32_t a, int32_t b) {
  const auto lo = static_cast<uint32_t>(std::min(a, b)), hi = static_cast<uint32_t>(std::max(a, b));
  return (uint64_t{lo} << 32) | hi;
}

/// A corner of a face's piece: where it lies in the face, in UV and in 3-D, and which UV it
/// takes: an original UV index, or a new UV per (position, owner, tile).
struct CutVertex {
  Vec3 bary = Vec3::Zero();  ///< barycentric coordinates in the parent face
  Vec2 uv = Vec2::Zero();
  int32_t position = -1;
  int32_t uvIndex = -1;  ///< >= 0: an original UV index (a face corner)
  uint64_t owner = 0;    ///< new points: the UV edge they lie on, or kInteriorOwner
};
using Polygon = std::vector<CutVertex>;
constexpr uint64_t kInteriorOwner = ~uint64_t{0};

/// The cut of one mesh: the 3-D points made on edges, and the faces being rebuilt.
class Cutter {
 public:
  Cutter(TexturedMesh& mesh, bool alongU, bool alongV)
      : mesh_(mesh), along_{alongU, alongV}, faceCount_(mesh.faceCount()) {}

  /// Every face's tile spans; true if any face crosses a line.
  bool findSpans();
  /// The cut; fills `result`'s tiles and parents.
  void cut(TileCut& result);

 private:
  std::array<double, 3> cornerCoordinates(size_t face, int axis) const {
    const Triangle& t = mesh_.uvTriangles[face];
    return {mesh_.uvs[t[0]][axis], mesh_.uvs[t[1]][axis], mesh_.uvs[t[2]][axis]};
  }
  bool crosses(size_t face) const {
    return spans_[face][0].lo != spans_[face][0].hi || spans_[face][1].lo != spans_[face][1].hi;
  }
  /// Corner order of face edge e in the canonical direction of its 3-D edge (from the smaller
  /// position index; by UV index when both ends are one position), so that every face on the
  /// edge computes bit-identical parameters.
  std::pair<int, int> canonicalEnds(size_t face, int e) const;
  void collectEdgeCuts();
  void makeEdgePoints();
  Polygon facePolygon(size_t face) const;
  CutVertex crossing(size_t face, const CutVertex& a, const CutVertex& b, int axis, int32_t line);
  void splitPolygon(size_t face, const Polygon& polygon, int axis, int32_t line, Polygon& below,
                    Polygon& above);
  std::vector<std::pair<Polygon, UvTile>> pieces(size_t face);
  void emit(size_t face, const Polygon& piece, UvTile tile, bool first, TileCut& result);
  void snapToLines(Vec2& uv) const {
    for (int axis = 0; axis < 2; ++axis)
      if (along_[axis])
        if (const std::optional<int32_t> line = lineAt(uv[axis])) uv[axis] = *line;
  }

  TexturedMesh& mesh_;
  std::array<bool, 2> along_;
  size_t faceCount_;
  std::vector<std::array<TileSpan, 2>> spans_;
  /// Per 3-D edge: parameters of the cuts (canonical direction), then (parameter, position).
  std::unordered_map<uint64_t, std::vector<double>> edgeCuts_;
  std::unordered_map<uint64_t, std::vector<std::pair<double, int32_t>>> edgePoints_;
  /// Points made inside a face, by (face, chord ends, axis, line).
  std::map<std::tuple<size_t, int32_t, int32_t, int, int32_t>, CutVertex> interiorPoints_;
  std::unordered_map<NewUvKey, int32_t, NewUvKeyHash> newUvs_;
};

bool Cutter::findSpans() {
  spans_.resize(faceCount_);
  int64_t extraTiles = 0;
  bool any = false;
  for (size_t f = 0; f < faceCount_; ++f) {
    for (int axis = 0; axis < 2; ++axis) {
      const std::array<double, 3> x = cornerCoordinates(f, axis);
      for (int c = 0; c < 3; ++c)
        if (along_[axis] && !(std::abs(x[c]) <= kMaxTileCoordinate))
          throw InvalidInputError("face " + std::to_string(f) + " has texture coordinates " +
                                  uvText(mesh_.uvs[mesh_.uvTriangles[f][c]]) +
                                  " beyond +-1e6 tiles; wrapping needs UVs within that range "
                                  "(move the charts nearer the image, or sample the texture "
                                  "with ClampToEdge)");
      spans_[f][axis] = along_[axis] ? faceSpan(x) : TileSpan{};
    }
    const int64_t columns = spans_[f][0].hi - spans_[f][0].lo + 1;
    const int64_t rows = spans_[f][1].hi - spans_[f][1].lo + 1;
    extraTiles += columns * rows - 1;
    any = any || crosses(f);
  }
  if (extraTiles > kMaxExtraTiles)
    throw InvalidInputError("faces crossing unit UV tile borders reach into " +
                            std::to_string(extraTiles) +
                            " more tiles; cutting them there is "
                            "limited to " +
                            std::to_string(kMaxExtraTiles) +
                            " (sample the texture with ClampToEdge, or repeat it fewer times)");
  return any;
}

std::pair<int, int> Cutter::canonicalEnds(size_t face, int e) const {
  const int a = e, b = (e + 1) % 3;
  const Triangle& p = mesh_.triangles[face];
  const Triangle& t = mesh_.uvTriangles[face];
  if (p[a] != p[b]) return p[a] < p[b] ? std::pair{a, b} : std::pair{b, a};
  return t[a] <= t[b] ? std::pair{a, b} : std::pair{b, a};
}

void Cutter::collectEdgeCuts() {
  for (size_t f = 0; f < faceCount_; ++f) {
    if (!crosses(f)) continue;
    for (int e = 0; e < 3; ++e) {
      const auto [a, b] = canonicalEnds(f, e);
      const Vec2& ua = mesh_.uvs[mesh_.uvTriangles[f][a]];
      const Vec2& ub = mesh_.uvs[mesh_.uvTriangles[f][b]];
      for (int axis = 0; axis < 2; ++axis)
        for (int32_t line = spans_[f][axis].lo + 1; line <= spans_[f][axis].hi; ++line)
          if (side(ua[axis], line) * side(ub[axis], line) < 0)
            edgeCuts_[edgeKey(mesh_.triangles[f][a], mesh_.triangles[f][b])].push_back(
                (line - ua[axis]) / (ub[axis] - ua[axis]));
    }
  }
}

void Cutter::makeEdgePoints() {
  for (auto& [key, cuts] : edgeCuts_) {
    std::sort(cuts.begin(), cuts.end());
    const auto lo = static_cast<int32_t>(key >> 32), hi = static_cast<int32_t>(key & 0xFFFFFFFFu);
    auto& points = edgePoints_[key];
    for (double t : cuts) {
      if (!points.empty() && t - points.back().first < kEdgeParameterMerge) continue;
      const Vec3 p = (1.0 - t) * mesh_.positions[lo] + t * mesh_.positions[hi];
      points.emplace_back(t, static_cast<int32_t>(mesh_.positions.size()));
      mesh_.positions.push_back(p);
    }
  }
}

Polygon Cutter::facePolygon(size_t face) const {
  const Triangle& p = mesh_.triangles[face];
  const Triangle& t = mesh_.uvTriangles[face];
  Polygon polygon;
  for (int e = 0; e < 3; ++e) {
    CutVertex corner;
    corner.bary[e] = 1.0;
    corner.uv = mesh_.uvs[t[e]];
    corner.position = p[e];
    corner.uvIndex = t[e];
    polygon.push_back(corner);
    const auto found = edgePoints_.find(edgeKey(p[e], p[(e + 1) % 3]));
    if (found == edgePoints_.end()) continue;
    const auto [a, b] = canonicalEnds(face, e);
    const bool forward = a == e;
    const Vec2 &ua = mesh_.uvs[t[a]], &ub = mesh_.uvs[t[b]];
    const uint64_t owner = edgeKey(t[a], t[b]);
    const size_t n = found->second.size();
    for (size_t i = 0; i < n; ++i) {
      const auto& [param, position] = found->second[forward ? i : n - 1 - i];
      CutVertex point;
      point.bary[a] = 1.0 - param;
      point.bary[b] = param;
      point.uv = (1.0 - param) * ua + param * ub;
      snapToLines(point.uv);
      point.position = position;
      point.owner = owner;
      polygon.push_back(point);
    }
  }
  return polygon;
}

CutVertex Cutter::crossing(size_t face, const CutVertex& a, const CutVertex& b, int axis,
                           int32_t line) {
  // The same chord is met from both of its sides: compute it once, from its lower position.
  const CutVertex& lo = a.position < b.position ? a : b;
  const CutVertex& hi = a.position < b.position ? b : a;
  const auto key = std::make_tuple(face, lo.position, hi.position, axis, line);
  const auto found = interiorPoints_.find(key);
  if (found != interiorPoints_.end()) return found->second;
  const double s = (line - lo.uv[axis]) / (hi.uv[axis] - lo.uv[axis]);
  CutVertex point;
  point.bary = (1.0 - s) * lo.bary + s * hi.bary;
  point.uv = (1.0 - s) * lo.uv + s * hi.uv;
  point.uv[axis] = line;
  snapToLines(point.uv);
  const Triangle& p = mesh_.triangles[face];
  point.position = static_cast<int32_t>(mesh_.positions.size());
  mesh_.positions.push_back(point.bary[0] * mesh_.positions[p[0]] +
                            point.bary[1] * mesh_.positions[p[1]] +
                            point.bary[2] * mesh_.positions[p[2]]);
  point.owner = kInteriorOwner;
  return interiorPoints_.emplace(key, point).first->second;
}

/// Sutherland-Hodgman against one line, keeping both sides: corners on the line go to both, and
/// a new point is made only where an edge passes strictly from one side to the other (inside
/// the face: the face's own edges were cut before). A side with no corner strictly in it is a
/// segment on the line, not a piece, and comes back empty.
void Cutter::splitPolygon(size_t face, const Polygon& polygon, int axis, int32_t line,
                          Polygon& below, Polygon& above) {
  below.clear();
  above.clear();
  bool strictlyBelow = false, strictlyAbove = false;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const CutVertex& a = polygon[i];
    const CutVertex& b = polygon[(i + 1) % polygon.size()];
    const int sa = side(a.uv[axis], line), sb = side(b.uv[axis], line);
    if (sa <= 0) below.push_back(a);
    if (sa >= 0) above.push_back(a);
    strictlyBelow = strictlyBelow || sa < 0;
    strictlyAbove = strictlyAbove || sa > 0;
    if (sa * sb < 0) {
      const CutVertex x = crossing(face, a, b, axis, line);
      below.push_back(x);
      above.push_back(x);
    }
  }
  if (!strictlyBelow || below.size() < 3) below.clear();
  if (!strictlyAbove || above.size() < 3) above.clear();
}

std::vector<std::pair<Polygon, UvTile>> Cutter::pieces(size_t face) {
  std::vector<std::pair<Polygon, UvTile>> out;
  const TileSpan su = spans_[face][0], sv = spans_[face][1];
  Polygon rest = facePolygon(face), below, above, strip, rowBelow, rowAbove;
  for (int32_t k = su.lo; k <= su.hi; ++k) {
    if (k < su.hi) {
      splitPolygon(face, rest, 0, k + 1, below, above);
      strip.swap(below);
      rest.swap(above);
    } else {
      strip.swap(rest);
    }
    for (int32_t l = sv.lo; l <= sv.hi && !strip.empty(); ++l) {
      if (l < sv.hi) {
        splitPolygon(face, strip, 1, l + 1, rowBelow, rowAbove);
        if (!rowBelow.empty()) out.emplace_back(rowBelow, UvTile{k, l});
        strip.swap(rowAbove);
      } else {
        out.emplace_back(strip, UvTile{k, l});
      }
    }
    if (rest.empty()) break;
  }
  return out;
}

/// Twice the signed area of a triangle of piece corners, in the face's barycentric plane (where
/// every piece has the face's orientation, even on a face with no UV or 3-D area).
double baryArea(const CutVertex& a, const CutVertex& b, const CutVertex& c) {
  const Eigen::Vector2d ab(b.bary[1] - a.bary[1], b.bary[2] - a.bary[2]);
  const Eigen::Vector2d ac(c.bary[1] - a.bary[1], c.bary[2] - a.bary[2]);
  return ab.x() * ac.y() - ab.y() * ac.x();
}

/// Triangles of a convex piece (corner triples): ears cut one at a time, each time the ear whose
/// smaller part (the ear or what remains) is largest. A fan from one corner would make
/// zero-area triangles where that corner's sides carry cut points; this never does while a
/// non-degenerate choice exists.
std::vector<std::array<size_t, 3>> triangulate(const Polygon& piece) {
  std::vector<size_t> ring(piece.size());
  for (size_t i = 0; i < ring.size(); ++i) ring[i] = i;
  double remaining = 0.0;
  for (size_t i = 1; i + 1 < ring.size(); ++i)
    remaining += baryArea(piece[0], piece[i], piece[i + 1]);
  std::vector<std::array<size_t, 3>> triangles;
  while (ring.size() > 3) {
    size_t best = 0;
    double bestScore = -std::numeric_limits<double>::infinity(), bestArea = 0.0;
    for (size_t i = 0; i < ring.size(); ++i) {
      const size_t prev = ring[(i + ring.size() - 1) % ring.size()],
                   next = ring[(i + 1) % ring.size()];
      const double ear = baryArea(piece[prev], piece[ring[i]], piece[next]);
      const double score = std::min(ear, remaining - ear);
      if (score > bestScore) {
        bestScore = score;
        bestArea = ear;
        best = i;
      }
    }
    triangles.push_back(
        {ring[(best + ring.size() - 1) % ring.size()], ring[best], ring[(best + 1) % ring.size()]});
    ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(best));
    remaining -= bestArea;
  }
  triangles.push_back({ring[0], ring[1], ring[2]});
  return triangles;
}

void Cutter::emit(size_t face, const Polygon& piece, UvTile tile, bool first, TileCut& result) {
  bool replaced = !first;
  for (const auto& corners : triangulate(piece)) {
    Triangle positions{}, uvs{};
    for (int c = 0; c < 3; ++c) {
      const CutVertex& v = piece[corners[c]];
      positions[c] = v.position;
      if (v.uvIndex >= 0) {
        uvs[c] = v.uvIndex;
        continue;
      }
      const auto [it, added] = newUvs_.try_emplace(NewUvKey{v.position, v.owner, tile},
                                                   static_cast<int32_t>(mesh_.uvs.size()));
      if (added) mesh_.uvs.push_back(v.uv);
      uvs[c] = it->second;
    }
    if (!replaced) {  // the face's first triangle keeps its index
      mesh_.triangles[face] = positions;
      mesh_.uvTriangles[face] = uvs;
      result.faceTile[face] = tile;
      replaced = true;
      continue;
    }
    mesh_.triangles.push_back(positions);
    mesh_.uvTriangles.push_back(uvs);
    if (!mesh_.faceMaterial.empty()) {
      const int32_t material = mesh_.faceMaterial[face];
      mesh_.faceMaterial.push_back(material);
    }
    result.faceTile.push_back(tile);
    result.parentFace.push_back(static_cast<int32_t>(face));
  }
}

void Cutter::cut(TileCut& result) {
  result.faceTile.resize(faceCount_);
  result.parentFace.resize(faceCount_);
  for (size_t f = 0; f < faceCount_; ++f) {
    result.faceTile[f] = {spans_[f][0].lo, spans_[f][1].lo};
    result.parentFace[f] = static_cast<int32_t>(f);
  }
  collectEdgeCuts();
  makeEdgePoints();
  for (size_t f = 0; f < faceCount_; ++f) {
    const Triangle& p = mesh_.triangles[f];
    const bool split = crosses(f) || edgePoints_.contains(edgeKey(p[0], p[1])) ||
                       edgePoints_.contains(edgeKey(p[1], p[2])) ||
                       edgePoints_.contains(edgeKey(p[2], p[0]));
    if (!split) continue;
    bool first = true;
    for (const auto& [piece, tile] : pieces(f)) {
      emit(f, piece, tile, first, result);
      first = false;
    }
  }
}

/// Each texture's face count after the cut: the faces of its materials, or every face when it
/// covered every face before.
void recountTextureFaces(TexturedMesh& mesh, size_t facesBefore) {
  for (TextureRef& texture : mesh.textures) {
    if (texture.faces == facesBefore) {
      texture.faces = mesh.faceCount();
    } else if (!texture.materials.empty() && !mesh.faceMaterial.empty()) {
      texture.faces = static_cast<size_t>(
          std::count_if(mesh.faceMaterial.begin(), mesh.faceMaterial.end(), [&](int32_t m) {
            return std::find(texture.materials.begin(), texture.materials.end(), m) !=
                   texture.materials.end();
          }));
    }
  }
}

}  // namespace

TileCut cutAtTileBorders(TexturedMesh mesh, bool alongU, bool alongV) {
  TileCut result;
  const size_t facesBefore = mesh.faceCount();
  Cutter cutter(mesh, alongU, alongV);
  result.cut = cutter.findSpans();
  cutter.cut(result);  // when no face crosses: tiles and parents only, nothing is rebuilt
  if (result.cut) recountTextureFaces(mesh, facesBefore);
  result.mesh = std::move(mesh);
  return result;
}

}  // namespace texgrad
