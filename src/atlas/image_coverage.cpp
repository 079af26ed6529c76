// requireUvsInImage: exact UV area of the faces inside [0, 1]^2 by clipping each UV triangle to
// the unit square (Sutherland-Hodgman), and the one error line for an atlas outside it.
#include "texgrad/atlas/image_coverage.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "texgrad/core/error.h"

namespace texgrad {
namespace {

/// Clips `polygon` to the closed half-plane sign * (p[axis] - line) >= 0. A crossing point is
/// added only where an edge passes strictly from one side to the other, so a face that only
/// touches the line from outside keeps just its corners on the line (exactly, no rounding).
void clipToHalfPlane(std::vector<Eigen::Vector2d>& polygon, std::vector<Eigen::Vector2d>& next,
                     int axis, double line, double sign) {
  next.clear();
  for (size_t k = 0; k < polygon.size(); ++k) {
    const Eigen::Vector2d& a = polygon[k];
    const Eigen::Vector2d& b = polygon[(k + 1) % polygon.size()];
    const double da = sign * (a[axis] - line), db = sign * (b[axis] - line);
    if (da >= 0.0) next.push_back(a);
    if ((da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0))
      next.push_back(a + (b - a) * (da / (da - db)));
  }
  polygon.swap(next);
}

/// Area of a polygon, measured from its first corner: exactly 0 when all corners lie on one
/// axis-parallel line (what a face touching the image only along its edge leaves).
double polygonArea(const std::vector<Eigen::Vector2d>& polygon) {
  double twice = 0.0;
  for (size_t k = 1; k + 1 < polygon.size(); ++k) {
    const Eigen::Vector2d a = polygon[k] - polygon[0], b = polygon[k + 1] - polygon[0];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::abs(twice);
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

}  // namespace

UvRange faceUvRange(const TexturedMesh& mesh) {
  if (mesh.uvTriangles.empty()) return {};
  UvRange range{mesh.uvs[mesh.uvTriangles[0][0]], mesh.uvs[mesh.uvTriangles[0][0]]};
  for (const Triangle& t : mesh.uvTriangles)
    for (int32_t k : t) {
      range.min = range.min.cwiseMin(mesh.uvs[k]);
      range.max = range.max.cwiseMax(mesh.uvs[k]);
    }
  return range;
}

double uvAreaInImage(const TexturedMesh& mesh) {
  double area = 0.0;
  std::vector<Eigen::Vector2d> polygon, scratch;
  for (const Triangle& t : mesh.uvTriangles) {
    polygon = {mesh.uvs[t[0]], mesh.uvs[t[1]], mesh.uvs[t[2]]};
    for (int axis = 0; axis < 2 && !polygon.empty(); ++axis) {
      clipToHalfPlane(polygon, scratch, axis, 0.0, 1.0);   // u (or v) >= 0
      clipToHalfPlane(polygon, scratch, axis, 1.0, -1.0);  // u (or v) <= 1
    }
    area += polygonArea(polygon);
  }
  return area;
}

void requireUvsInImage(const TexturedMesh& mesh) {
  if (mesh.uvTriangles.empty() || uvAreaInImage(mesh) > 0.0) return;
  const UvRange r = faceUvRange(mesh);
  const std::string where = mesh.sourcePath.empty() ? "" : mesh.sourcePath.string() + ": ";
  throw InvalidInputError(
      where + "UVs span u [" + number(r.min.x()) + ", " + number(r.max.x()) + "] x v [" +
      number(r.min.y()) + ", " + number(r.max.y()) +
      "], outside the image [0, 1]^2, so no texel would change; a texture that wraps is read "
      "there once wrapTextureCoordinates moves its tiles into the image (the command line's "
      "--wrap), tiled (UDIM) atlases are not supported yet: move the UVs into [0, 1]^2 (e.g. "
      "subtract their integer part)");
}

}  // namespace texgrad
