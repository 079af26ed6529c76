// Surface normals at texel centres: on a sphere they are the radial directions.
#include <gtest/gtest.h>

#include "texgrad/apps/surface_normals.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

TEST(SurfaceNormals, CubeSphereNormalsAreRadialAndUnit) {
  const TexelDomain domain(procedural::cubeSphere(16), 128, 128);
  const Eigen::MatrixX3d normals = texelNormals(domain);
  const std::vector<int32_t> faces = texelCentreFaces(domain);
  const TexturedMesh& mesh = domain.mesh();
  ASSERT_EQ(normals.rows(), domain.unknowns());
  int centred = 0;
  for (Eigen::Index u = 0; u < normals.rows(); ++u) {
    EXPECT_NEAR(normals.row(u).norm(), 1.0, 1e-9) << "unknown " << u;
    const int32_t f = faces[static_cast<size_t>(u)];
    if (f < 0) continue;
    ++centred;
    // The unit sphere's normal is the position; compare with the face centroid's direction
    // (faces span under 6 degrees at 16 subdivisions).
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int32_t v : mesh.triangles[static_cast<size_t>(f)])
      centroid += mesh.positions[static_cast<size_t>(v)];
    EXPECT_GT(normals.row(u).dot(centroid.normalized().transpose()), 0.99) << "unknown " << u;
  }
  EXPECT_GT(centred, domain.unknowns() * 9 / 10);
}

}  // namespace
}  // namespace texgrad
