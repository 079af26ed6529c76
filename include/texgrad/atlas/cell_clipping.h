// Step 1-2 of the function space (paper Sec. 4.1): split face edges where they cross lattice
// lines (and at seam points), then clip each UV triangle into convex pieces T ∩ cell.
#pragma once

#include <Eigen/Core>
#include <array>
#include <climits>
#include <cstdint>
#include <span>
#include <vector>

namespace texgrad {

/// Marks "lies on no lattice line" in EdgeEvent::onX / onY.
inline constexpr int32_t kNoLine = INT32_MIN;

/// A split point strictly inside a face edge, in grid coordinates (texel centres on integers).
struct EdgeEvent {
  double t = 0.0;           ///< parameter along the edge, 0 at its start corner, 1 at its end
  Eigen::Vector2d p;        ///< position; exactly on the lattice line(s) it is tagged with
  int32_t onX = kNoLine;    ///< k if the point lies on the vertical line x = k
  int32_t onY = kNoLine;    ///< j if the point lies on the horizontal line y = j
};

/// Lattice crossings strictly inside the segment from `from` to `to`, sorted from `from` to `to`.
/// Computed in a canonical frame (lexicographically smaller end first) so the two faces sharing an
/// edge get bit-identical points; a crossing through a lattice point is one event on both lines,
/// and coordinates are made monotone between tagged lines so later clipping is consistent.
std::vector<EdgeEvent> latticeCrossings(const Eigen::Vector2d& from, const Eigen::Vector2d& to);

/// Clamps the untagged coordinates of an ordered event list between the neighbouring tagged lines
/// (and the end points) so that the order along the edge agrees with every lattice comparison.
void makeMonotone(const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                  std::vector<EdgeEvent>& events);

/// A vertex of a clipped piece: a face corner, an edge event, or a point on lattice lines inside
/// the face.
struct PieceVertex {
  Eigen::Vector2d p;
  int8_t corner = -1;  ///< face corner 0..2, or -1
  int8_t edge = -1;    ///< face edge 0..2 whose event this is (edge e joins corners e, e+1), or -1
  int32_t event = -1;  ///< index into that edge's event list, or -1
  /// Bit e set if the vertex lies on face edge e (corners lie on two edges).
  uint8_t edgeMask() const {
    if (corner >= 0) return static_cast<uint8_t>((1u << corner) | (1u << ((corner + 2) % 3)));
    return edge >= 0 ? static_cast<uint8_t>(1u << edge) : uint8_t{0};
  }
};

/// One convex piece T ∩ cell, counter-clockwise in grid coordinates.
struct FacePiece {
  int cellX = 0, cellY = 0;  ///< cell (a, b) = [a, a+1] x [b, b+1]
  int begin = 0, end = 0;    ///< range in FaceClip::vertices
  bool full = false;         ///< the piece is the whole cell
};

/// All pieces of one face; reusable scratch buffers make repeated clipping allocation-free.
struct FaceClip {
  std::vector<PieceVertex> vertices;
  std::vector<FacePiece> pieces;
  int unexpectedCrossings = 0;  ///< polygon edges that crossed a line away from a known event
  std::vector<PieceVertex> scratch[4];
  /// Vertices of piece i.
  std::span<const PieceVertex> polygon(const FacePiece& piece) const {
    return {vertices.data() + piece.begin, static_cast<size_t>(piece.end - piece.begin)};
  }
};

/// Clips the triangle with grid-space corners `corners` (either orientation, positive area) and
/// per-edge events (edge e from corner e to corner (e+1)%3, sorted along it) into pieces T ∩ cell
/// of positive area, replacing `out`'s pieces. Pieces are counter-clockwise.
void clipTriangleToCells(const std::array<Eigen::Vector2d, 3>& corners,
                         const std::array<std::span<const EdgeEvent>, 3>& events, FaceClip& out);

/// Signed area of a polygon (shoelace), positive for counter-clockwise.
double polygonArea(std::span<const PieceVertex> polygon);

}  // namespace texgrad
