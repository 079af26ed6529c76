// Apps layer: where a geodesic source lies (vertex, UV point or 3-D point) and its snapping onto
// the atlas domain M.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "texgrad/apps/texel_domain.h"
#include "texgrad/fem/texel_basis.h"

namespace texgrad {

/// Where a distance source lies: a mesh vertex, a UV point or a 3-D point (model units).
struct GeodesicSource {
  enum class Kind : uint8_t { Vertex, Uv, Point };
  Kind kind = Kind::Vertex;
  int64_t vertex = -1;                              ///< Kind::Vertex: index into positions
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();     ///< Kind::Uv: texture coordinates
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< Kind::Point: 3-D position

  static GeodesicSource atVertex(int64_t index) { return {Kind::Vertex, index, {}, {}}; }
  static GeodesicSource atUv(const Eigen::Vector2d& uv) { return {Kind::Uv, -1, uv, {}}; }
  static GeodesicSource atPoint(const Eigen::Vector3d& p) { return {Kind::Point, -1, {}, p}; }
};

/// A source snapped onto the atlas domain M.
struct ResolvedSource {
  fem::SurfacePoint point;                             ///< face and grid coordinates
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();        ///< texture coordinates of the point
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< 3-D position (model units)
  /// How far the request was moved to reach M: UV units for UV sources, model units for 3-D
  /// points, 0 for vertices.
  double snapDistance = 0.0;
  /// The point on every sheet of the surface that meets there: one corner per fan of faces
  /// (faces joined by 3-D edges through the vertex) around a source at a mesh vertex, which
  /// is more than one at a non-manifold vertex (two cones touching at the apex); {point}
  /// elsewhere. The seam-continuous basis needs only one corner per fan.
  std::vector<fem::SurfacePoint> sheets;
};

/// Snaps a source to the nearest point of M (faces with zero UV area are not part of M): a vertex
/// to one of its corners, a UV point to the nearest point of a UV triangle, a 3-D point to the
/// nearest point of a 3-D triangle; a source that lands on a mesh vertex gets one point per sheet
/// there (ResolvedSource::sheets). Throws InvalidInputError for a vertex index out of range or a
/// vertex that only touches UV-degenerate faces.
ResolvedSource resolveSource(const TexelDomain& domain, const GeodesicSource& source);

}  // namespace texgrad
