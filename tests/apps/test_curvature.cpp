// Principal curvature estimator (vector_field.h, used by `texgrad lic --curvature`): directions
// and curvatures against closed forms on a procedural ellipsoid and a tilted cylinder.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "texgrad/apps/vector_field.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

/// Largest angle allowed between an estimated and a true principal direction (issue 6).
constexpr double kMaxAngleDegrees = 5.0;
/// A face is "away from umbilics" when its true principal curvatures differ by at least this
/// fraction of the larger one: there the directions are well defined.
constexpr double kMinRelativeGap = 0.1;

/// Principal directions and curvatures of the exact surface at one point.
struct TruePrincipal {
  Eigen::Vector3d dirMajor, dirMinor;
  double kMajor = 0.0, kMinor = 0.0;
};

/// Angle in degrees between the lines spanned by a and b (orientation ignored).
double lineAngleDegrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::min(1.0, std::abs(a.normalized().dot(b.normalized())));
  return std::acos(c) * 180.0 / std::numbers::pi;
}

/// Unit normal of face f of `mesh`.
Eigen::Vector3d faceNormal(const TexturedMesh& mesh, size_t f) {
  const Triangle& t = mesh.triangles[f];
  const Eigen::Vector3d& a = mesh.positions[t[0]];
  return (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).normalized();
}

/// Centroid of face f of `mesh`.
Eigen::Vector3d faceCentroid(const TexturedMesh& mesh, size_t f) {
  const Triangle& t = mesh.triangles[f];
  return (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
}

/// `d` projected onto the plane of normal n (estimated directions live in the face plane).
Eigen::Vector3d inPlane(const Eigen::Vector3d& d, const Eigen::Vector3d& n) {
  return d - d.dot(n) * n;
}

/// Closed-form principal frame of the ellipsoid x^T H x = 1, H = diag(1/a^2, 1/b^2, 1/c^2), at
/// the point radially above `x`: with unit normal n = H p / |H p| and an orthonormal tangent
/// basis T, the shape operator is T^T H T / |H p| (second fundamental form of a quadric).
TruePrincipal ellipsoidPrincipal(const Eigen::Vector3d& axes, const Eigen::Vector3d& x) {
  const Eigen::Matrix3d h = axes.cwiseInverse().cwiseAbs2().asDiagonal();
  const Eigen::Vector3d p = x / std::sqrt(x.dot(h * x));
  const Eigen::Vector3d gradient = h * p;
  const Eigen::Vector3d n = gradient.normalized();
  Eigen::Matrix<double, 3, 2> tangent;
  tangent.col(0) = n.unitOrthogonal();
  tangent.col(1) = n.cross(tangent.col(0));
  const Eigen::Matrix2d shape = tangent.transpose() * h * tangent / gradient.norm();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(shape);  // ascending, both > 0
  return {tangent * eig.eigenvectors().col(1), tangent * eig.eigenvectors().col(0),
          eig.eigenvalues()(1), eig.eigenvalues()(0)};
}

/// Worst errors of the estimate over the faces the predicate keeps.
struct Errors {
  double majorDegrees = 0.0, minorDegrees = 0.0;
  double kMajorRelative = 0.0, kMinorRelative = 0.0;  ///< relative to |true k_major|
  int faces = 0;
};

template <typename Truth>
Errors compare(const TexturedMesh& mesh, const PrincipalCurvatures& k, const Truth& truth) {
  Errors e;
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const TruePrincipal t = truth(faceCentroid(mesh, f));
    if (std::abs(t.kMajor - t.kMinor) < kMinRelativeGap * std::abs(t.kMajor)) continue;
    const Eigen::Vector3d n = faceNormal(mesh, f);
    ++e.faces;
    e.majorDegrees =
        std::max(e.majorDegrees, lineAngleDegrees(k.dirMajor[f], inPlane(t.dirMajor, n)));
    e.minorDegrees =
        std::max(e.minorDegrees, lineAngleDegrees(k.dirMinor[f], inPlane(t.dirMinor, n)));
    e.kMajorRelative =
        std::max(e.kMajorRelative, std::abs(k.kMajor[f] - t.kMajor) / std::abs(t.kMajor));
    e.kMinorRelative =
        std::max(e.kMinorRelative, std::abs(k.kMinor[f] - t.kMinor) / std::abs(t.kMajor));
  }
  return e;
}

void print(const char* name, const Errors& e, size_t faces) {
  std::printf(
      "%s: %d of %zu faces away from umbilics; max angle major %.2f deg, minor %.2f deg; "
      "max |dk| / |k_major|: major %.3f, minor %.3f\n",
      name, e.faces, faces, e.majorDegrees, e.minorDegrees, e.kMajorRelative, e.kMinorRelative);
}

/// The cube-sphere scaled to an ellipsoid with three distinct semi-axes (four umbilics).
TexturedMesh ellipsoid(const Eigen::Vector3d& axes, int subdivisions) {
  TexturedMesh mesh = procedural::cubeSphere(subdivisions);
  for (Eigen::Vector3d& p : mesh.positions) p = p.cwiseProduct(axes);
  return mesh;
}

TEST(Curvature, EllipsoidPrincipalDirectionsWithinFiveDegrees) {
  const Eigen::Vector3d axes(1.0, 0.7, 0.45);
  const TexturedMesh mesh = ellipsoid(axes, 32);
  const PrincipalCurvatures k = principalCurvatures(mesh);
  const Errors e =
      compare(mesh, k, [&](const Eigen::Vector3d& x) { return ellipsoidPrincipal(axes, x); });
  print("ellipsoid 1 : 0.7 : 0.45", e, mesh.faceCount());
  // Most of the surface is away from its four umbilics.
  EXPECT_GT(e.faces, static_cast<int>(0.8 * static_cast<double>(mesh.faceCount())));
  EXPECT_LT(e.majorDegrees, kMaxAngleDegrees);
  EXPECT_LT(e.minorDegrees, kMaxAngleDegrees);
  EXPECT_LT(e.kMajorRelative, 0.1);
  EXPECT_LT(e.kMinorRelative, 0.1);
}

TEST(Curvature, TiltedCylinderPrincipalDirectionsWithinFiveDegrees) {
  // A rigid rotation must not matter: the estimator has no preferred axes.
  const Eigen::Matrix3d rotation =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, 0.5).normalized())).toRotationMatrix();
  const double radius = 0.5 / std::numbers::pi;  // procedural::cylinder: circumference 1
  TexturedMesh mesh = procedural::cylinder(48, 20);
  for (Eigen::Vector3d& p : mesh.positions) p = rotation * p;
  const Eigen::Vector3d axis = rotation.col(2);
  const PrincipalCurvatures k = principalCurvatures(mesh);
  const Errors e = compare(mesh, k, [&](const Eigen::Vector3d& x) {
    // Around the axis the normal turns at 1 / radius; along it the surface is straight.
    const Eigen::Vector3d radial = (x - x.dot(axis) * axis).normalized();
    return TruePrincipal{axis.cross(radial), axis, 1.0 / radius, 0.0};
  });
  print("tilted cylinder", e, mesh.faceCount());
  EXPECT_EQ(e.faces, static_cast<int>(mesh.faceCount()));
  EXPECT_LT(e.majorDegrees, kMaxAngleDegrees);
  EXPECT_LT(e.minorDegrees, kMaxAngleDegrees);
  EXPECT_LT(e.kMajorRelative, 0.05);
  EXPECT_LT(e.kMinorRelative, 0.05);
}

TEST(Curvature, DirectionErrorFallsWithRefinement) {
  // A consistent estimator: each halving of the edge length shrinks the worst direction error
  // (built on area-weighted vertex normals it stalls above 10 degrees).
  const Eigen::Vector3d axes(1.0, 0.7, 0.45);
  double previous = 180.0;
  for (int subdivisions : {8, 16, 32}) {
    const TexturedMesh mesh = ellipsoid(axes, subdivisions);
    const Errors e = compare(mesh, principalCurvatures(mesh),
                             [&](const Eigen::Vector3d& x) { return ellipsoidPrincipal(axes, x); });
    const double worst = std::max(e.majorDegrees, e.minorDegrees);
    std::printf("ellipsoid n = %d: max angle %.2f deg\n", subdivisions, worst);
    EXPECT_LT(worst, 0.75 * previous) << subdivisions;
    previous = worst;
  }
}

}  // namespace
}  // namespace texgrad
