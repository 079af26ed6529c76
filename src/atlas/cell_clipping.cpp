// Canonical lattice crossings of edges and strip-wise Sutherland-Hodgman clipping of triangles
// into cell pieces: vertical lines first, then horizontal lines inside each strip.
#include "texgrad/atlas/cell_clipping.h"

#include <algorithm>
#include <cmath>

namespace texgrad {
namespace {

bool lexLess(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
}

int32_t tagOf(const EdgeEvent& e, int axis) { return axis == 0 ? e.onX : e.onY; }

/// -1 below the line coordinate[axis] = value, 0 on it, +1 above.
int sideOf(const PieceVertex& v, int axis, double value) {
  return v.p[axis] < value ? -1 : (v.p[axis] > value ? 1 : 0);
}

PieceVertex crossing(const PieceVertex& v, const PieceVertex& w, int axis, double value,
                     int& unexpected) {
  PieceVertex x;
  const int other = 1 - axis;
  x.p[axis] = value;
  if (v.p[other] == w.p[other]) {
    x.p[other] = v.p[other];  // along a lattice line of the other family: an exact lattice point
  } else {
    ++unexpected;  // only reachable through inconsistent input; interpolate and snap
    const double s = (value - v.p[axis]) / (w.p[axis] - v.p[axis]);
    x.p[other] = v.p[other] + s * (w.p[other] - v.p[other]);
  }
  return x;
}

/// Splits a convex polygon by the line p[axis] = value; vertices on the line go to both sides.
void split(const std::vector<PieceVertex>& in, int axis, double value,
           std::vector<PieceVertex>& below, std::vector<PieceVertex>& above, int& unexpected) {
  below.clear();
  above.clear();
  const size_t n = in.size();
  for (size_t i = 0; i < n; ++i) {
    const PieceVertex& v = in[i];
    const PieceVertex& w = in[(i + 1) % n];
    const int sv = sideOf(v, axis, value), sw = sideOf(w, axis, value);
    if (sv <= 0) below.push_back(v);
    if (sv >= 0) above.push_back(v);
    if (sv * sw < 0) {
      const PieceVertex x = crossing(v, w, axis, value, unexpected);
      below.push_back(x);
      above.push_back(x);
    }
  }
}

/// Removes consecutive (cyclic) duplicate points, keeping the most informative vertex.
void dedupe(std::vector<PieceVertex>& poly) {
  if (poly.empty()) return;
  size_t out = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    if (out > 0 && poly[out - 1].p == poly[i].p) {
      if (poly[out - 1].corner < 0 && (poly[i].corner >= 0 || poly[out - 1].event < 0))
        poly[out - 1] = poly[i];
      continue;
    }
    poly[out++] = poly[i];
  }
  poly.resize(out);
  while (poly.size() > 1 && poly.front().p == poly.back().p) {
    if (poly.front().corner < 0 && (poly.back().corner >= 0 || poly.front().event < 0))
      poly.front() = poly.back();
    poly.pop_back();
  }
}

bool isWholeCell(std::span<const PieceVertex> poly, double area) {
  if (poly.size() != 4 || area != 1.0) return false;
  for (const auto& v : poly)
    if (v.p.x() != std::floor(v.p.x()) || v.p.y() != std::floor(v.p.y())) return false;
  return true;
}

void emitPieces(std::vector<PieceVertex>& strip, int a, FaceClip& out) {
  dedupe(strip);
  if (strip.size() < 3) return;
  double lo = strip[0].p.y(), hi = lo;
  for (const auto& v : strip) {
    lo = std::min(lo, v.p.y());
    hi = std::max(hi, v.p.y());
  }
  const int b0 = static_cast<int>(std::floor(lo));
  const int b1 = std::max(b0, static_cast<int>(std::ceil(hi)) - 1);
  std::vector<PieceVertex>& rest = out.scratch[2];
  std::vector<PieceVertex>& next = out.scratch[3];
  std::vector<PieceVertex>& piece = out.scratch[1];
  rest = strip;
  for (int b = b0; b <= b1; ++b) {
    if (b < b1) {
      split(rest, 1, b + 1.0, piece, next, out.unexpectedCrossings);
      std::swap(rest, next);
    } else {
      piece = rest;
    }
    dedupe(piece);
    if (piece.size() < 3) continue;
    const double area = polygonArea(piece);
    if (!(area > 0.0)) continue;
    FacePiece fp;
    fp.cellX = a;
    fp.cellY = b;
    fp.begin = static_cast<int>(out.vertices.size());
    out.vertices.insert(out.vertices.end(), piece.begin(), piece.end());
    fp.end = static_cast<int>(out.vertices.size());
    fp.full = isWholeCell(piece, area);
    out.pieces.push_back(fp);
  }
}

}  // namespace

double polygonArea(std::span<const PieceVertex> polygon) {
  double twice = 0.0;
  const size_t n = polygon.size();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& a = polygon[i].p;
    const Eigen::Vector2d& b = polygon[(i + 1) % n].p;
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * twice;
}

void makeMonotone(const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                  std::vector<EdgeEvent>& events) {
  const size_t n = events.size();
  std::vector<double> next(n);
  for (int axis = 0; axis < 2; ++axis) {
    double upcoming = to[axis];
    for (size_t i = n; i-- > 0;) {
      next[i] = upcoming;
      if (tagOf(events[i], axis) != kNoLine) upcoming = tagOf(events[i], axis);
    }
    double previous = from[axis];
    for (size_t i = 0; i < n; ++i) {
      const int32_t tag = tagOf(events[i], axis);
      if (tag != kNoLine) {
        previous = tag;
        continue;
      }
      const double lo = std::min(previous, next[i]), hi = std::max(previous, next[i]);
      events[i].p[axis] = std::clamp(events[i].p[axis], lo, hi);
    }
  }
}

std::vector<EdgeEvent> latticeCrossings(const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  const bool swapped = lexLess(to, from);
  const Eigen::Vector2d& lo = swapped ? to : from;
  const Eigen::Vector2d& hi = swapped ? from : to;
  const Eigen::Vector2d d = hi - lo;
  std::vector<EdgeEvent> xs, ys, events;
  for (double k = std::floor(lo.x()) + 1.0; k < hi.x(); k += 1.0) {
    EdgeEvent e;
    e.t = (k - lo.x()) / d.x();
    e.p = {k, lo.y() + e.t * d.y()};
    e.onX = static_cast<int32_t>(k);
    xs.push_back(e);
  }
  const double ylo = std::min(lo.y(), hi.y()), yhi = std::max(lo.y(), hi.y());
  for (double j = std::floor(ylo) + 1.0; j < yhi; j += 1.0) {
    EdgeEvent e;
    e.t = (j - lo.y()) / d.y();
    e.p = {lo.x() + e.t * d.x(), j};
    e.onY = static_cast<int32_t>(j);
    ys.push_back(e);
  }
  if (d.y() < 0.0) std::reverse(ys.begin(), ys.end());
  events.reserve(xs.size() + ys.size());
  size_t i = 0, j = 0;
  while (i < xs.size() || j < ys.size()) {
    if (j == ys.size() || (i < xs.size() && xs[i].t < ys[j].t)) {
      events.push_back(xs[i++]);
    } else if (i == xs.size() || ys[j].t < xs[i].t) {
      events.push_back(ys[j++]);
    } else {  // through a lattice point: one event on both lines
      EdgeEvent e = xs[i++];
      e.onY = ys[j++].onY;
      e.p = {static_cast<double>(e.onX), static_cast<double>(e.onY)};
      events.push_back(e);
    }
  }
  makeMonotone(lo, hi, events);
  if (swapped) {
    std::reverse(events.begin(), events.end());
    for (auto& e : events) e.t = 1.0 - e.t;
  }
  return events;
}

void clipTriangleToCells(const std::array<Eigen::Vector2d, 3>& corners,
                         const std::array<std::span<const EdgeEvent>, 3>& events, FaceClip& out) {
  out.vertices.clear();
  out.pieces.clear();
  out.unexpectedCrossings = 0;
  std::vector<PieceVertex>& ring = out.scratch[0];
  ring.clear();
  for (int e = 0; e < 3; ++e) {
    PieceVertex c;
    c.p = corners[e];
    c.corner = static_cast<int8_t>(e);
    ring.push_back(c);
    for (size_t i = 0; i < events[e].size(); ++i) {
      PieceVertex v;
      v.p = events[e][i].p;
      v.edge = static_cast<int8_t>(e);
      v.event = static_cast<int32_t>(i);
      ring.push_back(v);
    }
  }
  if (polygonArea(ring) < 0.0) std::reverse(ring.begin(), ring.end());
  double lo = corners[0].x(), hi = lo;
  for (const auto& c : corners) {
    lo = std::min(lo, c.x());
    hi = std::max(hi, c.x());
  }
  const int a0 = static_cast<int>(std::floor(lo));
  const int a1 = std::max(a0, static_cast<int>(std::ceil(hi)) - 1);
  std::vector<PieceVertex> rest = ring, next, strip;
  for (int a = a0; a <= a1; ++a) {
    if (a < a1) {
      split(rest, 0, a + 1.0, strip, next, out.unexpectedCrossings);
      std::swap(rest, next);
    } else {
      strip = rest;
    }
    emitPieces(strip, a, out);
  }
}

}  // namespace texgrad
