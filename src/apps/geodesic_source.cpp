// Apps layer: snapping geodesic sources (vertex, UV point, 3-D point) onto the atlas domain M.
#include "texgrad/apps/geodesic_source.h"

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "apps/closest_point.h"
#include "texgrad/core/error.h"

namespace texgrad {
namespace {

fem::SurfacePoint pointAt(const fem::TexelBasis& basis, int face, const Eigen::Vector3d& b) {
  const auto& c = basis.faceCorners(face);
  return {face, b[0] * c[0] + b[1] * c[1] + b[2] * c[2]};
}

/// One corner per fan of valid faces around `vertex` (faces joined by a 3-D edge through it),
/// the fan of `face` first.
std::vector<fem::SurfacePoint> vertexSheets(const TexelDomain& domain, int32_t vertex, int face) {
  const TexturedMesh& mesh = domain.mesh();
  const fem::TexelBasis& basis = domain.operators().basis();
  std::vector<int> faces{face};  // the faces at the vertex, `face` first
  for (int f = 0; f < basis.faceCount(); ++f)
    if (f != face && basis.faceValid(f) &&
        std::find(mesh.triangles[f].begin(), mesh.triangles[f].end(), vertex) !=
            mesh.triangles[f].end())
      faces.push_back(f);
  auto sharesEdge = [&](int f, int g) {  // a 3-D edge (vertex, w) of both faces
    for (int32_t w : mesh.triangles[f])
      if (w != vertex && std::find(mesh.triangles[g].begin(), mesh.triangles[g].end(), w) !=
                             mesh.triangles[g].end())
        return true;
    return false;
  };
  std::vector<int> fan(faces.size(), -1);
  std::vector<fem::SurfacePoint> sheets;
  for (size_t seed = 0; seed < faces.size(); ++seed) {
    if (fan[seed] >= 0) continue;
    fan[seed] = static_cast<int>(sheets.size());
    std::vector<size_t> queue{seed};
    for (size_t head = 0; head < queue.size(); ++head)
      for (size_t other = 0; other < faces.size(); ++other)
        if (fan[other] < 0 && sharesEdge(faces[queue[head]], faces[other])) {
          fan[other] = fan[seed];
          queue.push_back(other);
        }
    const auto& t = mesh.triangles[static_cast<size_t>(faces[seed])];
    const auto corner = std::find(t.begin(), t.end(), vertex) - t.begin();
    sheets.push_back({faces[seed], basis.faceCorners(faces[seed])[static_cast<size_t>(corner)]});
  }
  return sheets;
}

ResolvedSource finish(const TexelDomain& domain, const fem::SurfacePoint& point, double snap) {
  const fem::TexelBasis& basis = domain.operators().basis();
  ResolvedSource r{point, domain.grid().toUv(point.grid), basis.position(point), snap, {point}};
  // Snapping puts a point that lands on a corner exactly there.
  for (size_t c = 0; c < 3; ++c)
    if (point.grid == basis.faceCorners(point.face)[c])  // on a mesh vertex: every sheet there
      r.sheets = vertexSheets(domain, domain.mesh().triangles[point.face][c], point.face);
  return r;
}

ResolvedSource resolveVertex(const TexelDomain& domain, int64_t vertex) {
  const TexturedMesh& mesh = domain.mesh();
  if (vertex < 0 || vertex >= static_cast<int64_t>(mesh.positions.size()))
    throw InvalidInputError("source vertex " + std::to_string(vertex) +
                            " is out of range; the mesh has " +
                            std::to_string(mesh.positions.size()) + " vertices (0-based indices)");
  const fem::TexelBasis& basis = domain.operators().basis();
  for (int f = 0; f < basis.faceCount(); ++f) {
    if (!basis.faceValid(f)) continue;
    for (int c = 0; c < 3; ++c)
      if (mesh.triangles[f][c] == vertex) {
        Eigen::Vector3d b = Eigen::Vector3d::Zero();
        b[c] = 1.0;
        ResolvedSource r = finish(domain, pointAt(basis, f, b), 0.0);
        r.position = mesh.positions[static_cast<size_t>(vertex)];
        return r;
      }
  }
  throw InvalidInputError("source vertex " + std::to_string(vertex) +
                          " belongs to no face with texture coordinates of positive area; pick "
                          "another vertex or a UV / 3-D source");
}

ResolvedSource resolveUv(const TexelDomain& domain, const Eigen::Vector2d& uv) {
  if (!uv.allFinite()) throw InvalidInputError("source UV point is not finite");
  const fem::TexelBasis& basis = domain.operators().basis();
  const TexelGrid& grid = domain.grid();
  const Eigen::Vector2d p = grid.toGrid(uv);
  const Eigen::Vector2d toUv(1.0 / grid.imageWidth, 1.0 / grid.imageHeight);
  double best = std::numeric_limits<double>::infinity();
  fem::SurfacePoint point;
  for (int f = 0; f < basis.faceCount() && best > 0.0; ++f) {
    if (!basis.faceValid(f)) continue;
    const auto& c = basis.faceCorners(f);
    const Eigen::Vector3d b = closestBarycentric(p, c[0], c[1], c[2]);
    const fem::SurfacePoint candidate = pointAt(basis, f, b);
    const double d = (candidate.grid - p).cwiseProduct(toUv).norm();
    if (d < best) {
      best = d;
      point = candidate;
    }
  }
  if (point.face < 0) throw InvalidInputError("the mesh has no face with positive UV area");
  return finish(domain, point, best);
}

ResolvedSource resolvePoint(const TexelDomain& domain, const Eigen::Vector3d& target) {
  if (!target.allFinite()) throw InvalidInputError("source 3-D point is not finite");
  const TexturedMesh& mesh = domain.mesh();
  const fem::TexelBasis& basis = domain.operators().basis();
  double best = std::numeric_limits<double>::infinity();
  fem::SurfacePoint point;
  for (int f = 0; f < basis.faceCount() && best > 0.0; ++f) {
    if (!basis.faceValid(f)) continue;
    const auto& t = mesh.triangles[f];
    const Eigen::Vector3d &a = mesh.positions[t[0]], &b = mesh.positions[t[1]],
                          &c = mesh.positions[t[2]];
    const Eigen::Vector3d bary = closestBarycentric(target, a, b, c);
    const double d = (bary[0] * a + bary[1] * b + bary[2] * c - target).norm();
    if (d < best) {
      best = d;
      point = pointAt(basis, f, bary);
    }
  }
  if (point.face < 0) throw InvalidInputError("the mesh has no face with positive UV area");
  return finish(domain, point, best);
}

}  // namespace

ResolvedSource resolveSource(const TexelDomain& domain, const GeodesicSource& source) {
  switch (source.kind) {
    case GeodesicSource::Kind::Vertex:
      return resolveVertex(domain, source.vertex);
    case GeodesicSource::Kind::Uv:
      return resolveUv(domain, source.uv);
    case GeodesicSource::Kind::Point:
      return resolvePoint(domain, source.point);
  }
  throw InvalidInputError("unknown geodesic source kind");
}

}  // namespace texgrad
