// Point evaluation of the texel basis (paper Sec. 4.1): point location in a face's clip (exact
// on face edges, where phi is steep across thin seam pieces), sampling of points and seam pairs.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "texgrad/core/error.h"
#include "texgrad/fem/texel_basis.h"

namespace texgrad::fem {

Eigen::Vector3d TexelBasis::barycentric(const SurfacePoint& point) const {
  const auto& c = corners_[point.face];
  Eigen::Matrix2d m;
  m.col(0) = c[1] - c[0];
  m.col(1) = c[2] - c[0];
  const Eigen::Vector2d st = m.inverse() * (point.grid - c[0]);
  return {1.0 - st.x() - st.y(), st.x(), st.y()};
}

Eigen::Vector3d TexelBasis::position(const SurfacePoint& point) const {
  const Eigen::Vector3d b = barycentric(point);
  const auto& tri = mesh_.triangles[point.face];
  return b[0] * mesh_.positions[tri[0]] + b[1] * mesh_.positions[tri[1]] +
         b[2] * mesh_.positions[tri[2]];
}

namespace {

/// A point within this many ulps of its coordinates' magnitude from a face edge is on the edge:
/// that is the rounding of a point computed as a + u (b - a).
constexpr double kOnEdgeUlps = 16.0;
/// Polygon edges shorter than this (texels) have no reliable direction for point location.
constexpr double kShortEdge = 1e-9;

/// Smallest signed distance of p to the edges of a CCW convex polygon (>= 0 inside); edges
/// shorter than kShortEdge are skipped (their direction is rounding noise).
double insideness(std::span<const PieceVertex> polygon, const Eigen::Vector2d& p) {
  double worst = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d a = polygon[i].p, b = polygon[(i + 1) % polygon.size()].p;
    const Eigen::Vector2d e = b - a;
    const double len = e.norm();
    if (len < kShortEdge) continue;
    worst = std::min(worst, (e.x() * (p.y() - a.y()) - e.y() * (p.x() - a.x())) / len);
  }
  return worst;
}

Eigen::Vector3d elementBarycentric(const std::array<Eigen::Vector2d, 3>& t,
                                   const Eigen::Vector2d& p) {
  Eigen::Matrix2d m;
  m.col(0) = t[1] - t[0];
  m.col(1) = t[2] - t[0];
  const Eigen::Vector2d st = m.inverse() * (p - t[0]);
  return {1.0 - st.x() - st.y(), st.x(), st.y()};
}

/// Parameter of the projection of p onto segment a-b, clamped to [0, 1].
double segmentParameter(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                        const Eigen::Vector2d& p) {
  const Eigen::Vector2d e = b - a;
  const double len2 = e.squaredNorm();
  return len2 > 0.0 ? std::clamp((p - a).dot(e) / len2, 0.0, 1.0) : 0.0;
}

}  // namespace

int TexelBasis::edgeOfPoint(const SurfacePoint& point) const {
  const auto& c = corners_[point.face];
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector2d a = c[e], b = c[(e + 1) % 3];
    const double scale = std::max({1.0, a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()});
    const Eigen::Vector2d d = b - a, r = point.grid - a;
    const double distance = std::abs(d.x() * r.y() - d.y() * r.x()) / d.norm();
    if (distance <= kOnEdgeUlps * std::numeric_limits<double>::epsilon() * scale) return e;
  }
  return -1;
}

TexelBasis::Location TexelBasis::locate(const SurfacePoint& point, const FaceClip& clip) const {
  Location out;
  const int edge = edgeOfPoint(point);
  if (edge >= 0) {
    // On a face edge: the polygon segment on that edge nearest to the point, parameter by
    // projection (the normal offset is rounding; across seams phi is steep in that direction).
    double best = std::numeric_limits<double>::infinity();
    for (const auto& piece : clip.pieces) {
      const auto poly = clip.polygon(piece);
      for (size_t i = 0; i < poly.size(); ++i) {
        const PieceVertex &v = poly[i], &w = poly[(i + 1) % poly.size()];
        if (!((v.edgeMask() & w.edgeMask()) >> edge & 1)) continue;
        const double s = segmentParameter(v.p, w.p, point.grid);
        const double d = (v.p + s * (w.p - v.p) - point.grid).norm();
        if (d < best) {
          best = d;
          out = {&piece, static_cast<int>(i), s};
        }
      }
    }
    if (out.piece) return out;
  }
  // Inside the face: the piece of the point's cell, else the piece it is deepest in.
  const int cx = static_cast<int>(std::floor(point.grid.x()));
  const int cy = static_cast<int>(std::floor(point.grid.y()));
  double bestInside = -std::numeric_limits<double>::infinity();
  for (const auto& piece : clip.pieces) {
    if (piece.cellX == cx && piece.cellY == cy) return {&piece, -1, 0.0};
    const double inside = insideness(clip.polygon(piece), point.grid);
    if (inside > bestInside) {
      bestInside = inside;
      out.piece = &piece;
    }
  }
  return out;
}

std::vector<TexelWeight> TexelBasis::evaluate(const SurfacePoint& point) const {
  std::vector<TexelWeight> result;
  if (point.face < 0 || point.face >= faceCount() || !valid_[point.face]) return result;
  FaceClip clip;
  clipFace(point.face, clip);
  const Location at = locate(point, clip);
  if (!at.piece) return result;
  const auto polygon = clip.polygon(*at.piece);
  if (isPlain(point.face, polygon)) {
    const double fx = point.grid.x() - at.piece->cellX, fy = point.grid.y() - at.piece->cellY;
    const std::array<double, 4> w{(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy,
                                  fx * fy};
    const auto texels = cellTexels(at.piece->cellX, at.piece->cellY);
    for (int k = 0; k < 4; ++k)
      if (texels[k] >= 0) result.push_back({texels[k], w[k]});
    mergeWeights(result);
    return result;
  }
  PieceBasis basis;
  buildPieceBasis(point.face, polygon, basis);
  // Fan element i is (centre, polygon[i], polygon[i + 1]): a boundary point has b0 = 0 exactly.
  size_t element = at.segment >= 0 ? static_cast<size_t>(at.segment) : 0;
  Eigen::Vector3d bestB(0.0, 1.0 - at.parameter, at.parameter);
  if (at.segment < 0) {
    double bestMin = -std::numeric_limits<double>::infinity();
    for (size_t e = 0; e < basis.elements.size(); ++e) {
      const Eigen::Vector3d b = elementBarycentric(basis.elements[e], point.grid);
      if (b.allFinite() && b.minCoeff() > bestMin) {
        bestMin = b.minCoeff();
        bestB = b;
        element = e;
      }
    }
  }
  const auto shape = quadraticShape(bestB);
  for (size_t t = 0; t < basis.texels.size(); ++t) {
    double value = 0.0;
    for (int k = 0; k < 6; ++k)
      value += shape[k] * basis.coefficients(static_cast<Eigen::Index>(6 * element + k),
                                             static_cast<Eigen::Index>(t));
    result.push_back({basis.texels[t], value});
  }
  mergeWeights(result);
  return result;
}

double TexelBasis::evaluate(const SurfacePoint& point, const Eigen::VectorXd& x) const {
  double sum = 0.0;
  for (const auto& w : evaluate(point)) sum += w.weight * x[w.unknown];
  return sum;
}

SeamTrace TexelBasis::seamTrace(int seam) const {
  const SeamSplit& s = seams_.at(static_cast<size_t>(seam));
  SeamTrace out{s.edge, s.sameDirection, {0.0}};
  for (const EdgeEvent& e : s.side[0])
    out.breaks.push_back(std::clamp(e.t, out.breaks.back(), 1.0));
  out.breaks.push_back(1.0);
  return out;
}

SurfacePoint TexelBasis::randomPoint(std::mt19937_64& rng) const {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double target = unit(rng) * cumulativeArea_.back();
  int face =
      static_cast<int>(std::upper_bound(cumulativeArea_.begin(), cumulativeArea_.end(), target) -
                       cumulativeArea_.begin()) -
      1;
  face = std::clamp(face, 0, faceCount() - 1);
  while (!valid_[face]) face = (face + 1) % faceCount();
  double s = unit(rng), t = unit(rng);
  if (s + t > 1.0) {
    s = 1.0 - s;
    t = 1.0 - t;
  }
  const auto& c = corners_[face];
  return {face, c[0] + s * (c[1] - c[0]) + t * (c[2] - c[0])};
}

std::pair<SurfacePoint, SurfacePoint> TexelBasis::randomSeamPair(std::mt19937_64& rng) const {
  if (seams_.empty()) throw InvalidInputError("the atlas has no seams to sample");
  std::uniform_int_distribution<size_t> pick(0, seams_.size() - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const SeamSplit& s = seams_[pick(rng)];
  const double t = unit(rng);
  auto at = [&](const FaceEdge& e, double u) {
    const Eigen::Vector2d a = corners_[e.face][e.corner], b = corners_[e.face][(e.corner + 1) % 3];
    return SurfacePoint{e.face, a + u * (b - a)};
  };
  return {at(s.edge[0], t), at(s.edge[1], s.sameDirection ? t : 1.0 - t)};
}

}  // namespace texgrad::fem
