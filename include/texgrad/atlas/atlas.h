// Atlas structure recovered from a TexturedMesh: charts, seam edge pairs, open/non-manifold edges.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Edge of a face: from corner `corner` to corner (corner + 1) % 3 of face `face`.
struct FaceEdge {
  int32_t face = -1;
  int8_t corner = -1;
  friend bool operator==(const FaceEdge&, const FaceEdge&) = default;
};

/// Two UV boundary edges that are the same 3-D edge (paper §3.1).
///
/// Seam equivalence: the point at parameter s along `a` (from its start corner to its end corner,
/// in UV) is the same surface point as the point at parameter s along `b` when `sameDirection`
/// is true, and at 1 - s otherwise (the usual case: neighbouring faces traverse it oppositely).
struct SeamPair {
  FaceEdge a;
  FaceEdge b;
  bool sameDirection = false;
};

/// One chart: a connected set of faces joined across edges whose both UV ends coincide.
struct Chart {
  std::vector<int32_t> faces;   ///< face indices in the chart
  double uvArea = 0.0;          ///< signed-area sum of its UV triangles (unit-square units)
  Eigen::Vector2d uvMin, uvMax; ///< UV bounding box
};

/// Connectivity of the atlas. Faces with 3-D-degenerate or UV-degenerate triangles still belong
/// to a chart; diagnostics about them live in AtlasReport.
struct Atlas {
  std::vector<int32_t> chartOfFace;     ///< per face: chart index
  std::vector<Chart> charts;            ///< charts, ordered by smallest face index
  std::vector<SeamPair> seams;          ///< 3-D edges cut by the atlas (UV ends differ)
  std::vector<FaceEdge> openBoundary;   ///< 3-D edges with a single face
  std::vector<std::vector<FaceEdge>> nonManifoldEdges;  ///< 3-D edges with 3+ faces
  /// Per face and edge (3 * face + corner): index into `seams` or -1.
  std::vector<int32_t> seamOfEdge;
};

/// Builds the atlas connectivity. Two faces are neighbours when they share a 3-D edge
/// (welded positions); they are in the same chart when, in addition, the UVs of both edge ends
/// coincide exactly. Non-manifold edges are never used to join charts or form seams.
Atlas buildAtlas(const TexturedMesh& mesh);

}  // namespace texgrad
