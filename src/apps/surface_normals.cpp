// Surface quantities at texel centres; see the header.
#include "texgrad/apps/surface_normals.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/LU>

namespace texgrad {
namespace {

/// Barycentric slack when testing whether a texel centre lies in a UV triangle.
constexpr double kInsideTolerance = 1e-9;

/// Area-weighted vertex normals (|cross| weights), unnormalised.
std::vector<Eigen::Vector3d> vertexNormals(const TexturedMesh& mesh) {
  std::vector<Eigen::Vector3d> normals(mesh.positions.size(), Eigen::Vector3d::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3d& p0 = mesh.positions[static_cast<size_t>(t[0])];
    const Eigen::Vector3d n = (mesh.positions[static_cast<size_t>(t[1])] - p0)
                                  .cross(mesh.positions[static_cast<size_t>(t[2])] - p0);
    for (int32_t v : t) normals[static_cast<size_t>(v)] += n;
  }
  return normals;
}

/// Calls f(unknown, face, barycentrics) for every texel centre inside a valid UV triangle, the
/// first face in index order winning where UVs overlap.
template <typename F>
void forEachCentre(const TexelGrid& grid, const fem::TexelBasis& basis, F&& f) {
  std::vector<uint8_t> seen(static_cast<size_t>(grid.unknownCount()), 0);
  for (int face = 0; face < basis.faceCount(); ++face) {
    if (!basis.faceValid(face)) continue;
    const auto& c = basis.faceCorners(face);
    Eigen::Matrix2d e;
    e.col(0) = c[1] - c[0];
    e.col(1) = c[2] - c[0];
    const Eigen::Matrix2d inverse = e.inverse();
    const Eigen::Vector2d lo = c[0].cwiseMin(c[1]).cwiseMin(c[2]);
    const Eigen::Vector2d hi = c[0].cwiseMax(c[1]).cwiseMax(c[2]);
    for (int y = std::max(0, static_cast<int>(std::ceil(lo.y())));
         y <= std::min(grid.ny - 1, static_cast<int>(std::floor(hi.y()))); ++y)
      for (int x = std::max(0, static_cast<int>(std::ceil(lo.x())));
           x <= std::min(grid.nx - 1, static_cast<int>(std::floor(hi.x()))); ++x) {
        const int32_t u = grid.unknownOfTexel[static_cast<size_t>(grid.texelIndex(x, y))];
        if (u < 0 || seen[static_cast<size_t>(u)]) continue;
        const Eigen::Vector2d st = inverse * (Eigen::Vector2d(x, y) - c[0]);
        if (st.minCoeff() < -kInsideTolerance || st.sum() > 1.0 + kInsideTolerance) continue;
        seen[static_cast<size_t>(u)] = 1;
        f(u, face, Eigen::Vector3d(1.0 - st.sum(), st.x(), st.y()));
      }
  }
}

}  // namespace

std::vector<int32_t> texelCentreFaces(const TexelDomain& domain) {
  std::vector<int32_t> faces(static_cast<size_t>(domain.grid().unknownCount()), -1);
  const fem::TexelBasis& basis = domain.operators().basis();
  forEachCentre(domain.grid(), basis, [&](int32_t u, int face, const Eigen::Vector3d&) {
    faces[static_cast<size_t>(u)] = face;
  });
  return faces;
}

Eigen::MatrixX3d texelNormals(const TexelDomain& domain) {
  return texelNormals(domain, domain.operators());
}

Eigen::MatrixX3d texelNormals(const TexelDomain& domain, const TexelOperators& operators) {
  const TexturedMesh& mesh = domain.mesh();
  const std::vector<Eigen::Vector3d> vertex = vertexNormals(mesh);
  const auto n = static_cast<Eigen::Index>(domain.grid().unknownCount());
  Eigen::MatrixX3d normals = Eigen::MatrixX3d::Zero(n, 3);
  std::vector<uint8_t> known(static_cast<size_t>(n), 0);
  const fem::TexelBasis& basis = operators.basis();
  forEachCentre(domain.grid(), basis, [&](int32_t u, int face, const Eigen::Vector3d& w) {
    const Triangle& t = mesh.triangles[static_cast<size_t>(face)];
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k)
      v += w[k] * vertex[static_cast<size_t>(t[static_cast<size_t>(k)])].normalized();
    if (v.norm() > 0.0) {
      normals.row(u) = v.normalized().transpose();
      known[static_cast<size_t>(u)] = 1;
    }
  });
  const SparseViewd s = operators.stiffness();
  for (Eigen::Index u = 0; u < n; ++u) {
    if (known[static_cast<size_t>(u)]) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (SparseViewd::InnerIterator it(s, u); it; ++it)
      if (known[static_cast<size_t>(it.row())]) sum += normals.row(it.row()).transpose();
    if (sum.norm() > 0.0) normals.row(u) = sum.normalized().transpose();
  }
  return normals;
}

}  // namespace texgrad
