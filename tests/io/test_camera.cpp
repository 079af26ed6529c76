// The camera model: COLMAP's distortion formulas against hand-computed values, the principal
// point, the camera centre and the image bounds.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "texgrad/io/camera.h"

namespace texgrad {
namespace {

constexpr double kExact = 1e-15;  // hand-computed values below are exact to rounding

/// A normalised point off both axes, so every term of the distortion formulas is non-zero.
const Eigen::Vector2d kPoint(0.3, -0.2);  // r² = 0.13

TEST(CameraModel, NoDistortionIsIdentity) {
  EXPECT_EQ(LensDistortion{}.apply(kPoint), kPoint);
}

TEST(CameraModel, SimpleRadialMatchesColmap) {
  LensDistortion d;
  d.model = DistortionModel::SimpleRadial;
  d.k1 = 0.1;
  d.k2 = 7;                                     // unused by the model
  const Eigen::Vector2d out = d.apply(kPoint);  // factor 1 + 0.1 * 0.13 = 1.013
  EXPECT_NEAR(out.x(), 0.3039, kExact);
  EXPECT_NEAR(out.y(), -0.2026, kExact);
}

TEST(CameraModel, RadialMatchesColmap) {
  LensDistortion d;
  d.model = DistortionModel::Radial;
  d.k1 = 0.1;
  d.k2 = -0.05;
  d.p1 = 3;  // unused by the model
  // factor 1 + 0.1 * 0.13 - 0.05 * 0.0169 = 1.012155
  const Eigen::Vector2d out = d.apply(kPoint);
  EXPECT_NEAR(out.x(), 0.3036465, kExact);
  EXPECT_NEAR(out.y(), -0.202431, kExact);
}

TEST(CameraModel, OpenCVMatchesColmap) {
  LensDistortion d;
  d.model = DistortionModel::OpenCV;
  d.k1 = 0.1;
  d.k2 = -0.05;
  d.p1 = 0.01;
  d.p2 = -0.02;
  // COLMAP OpenCVCameraModel::Distortion: du = u radial + 2 p1 u v + p2 (r² + 2 u²),
  // dv = v radial + 2 p2 u v + p1 (r² + 2 v²), radial = 1.012155 as above:
  // x' = 0.3036465 - 0.0012 - 0.0062, y' = -0.202431 + 0.0024 + 0.0021.
  const Eigen::Vector2d out = d.apply(kPoint);
  EXPECT_NEAR(out.x(), 0.2962465, kExact);
  EXPECT_NEAR(out.y(), -0.197931, kExact);
}

Camera distortedCamera() {
  Camera c;
  c.width = 640;
  c.height = 480;
  c.fx = 500;
  c.fy = 520;
  c.cx = 322.5;
  c.cy = 238.25;
  c.R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  c.t = {0.5, -1, 4};
  c.distortion.model = DistortionModel::OpenCV;
  c.distortion.k1 = -0.2;
  c.distortion.k2 = 0.05;
  c.distortion.p1 = 0.001;
  c.distortion.p2 = -0.002;
  return c;
}

TEST(CameraModel, OpticalAxisProjectsToThePrincipalPoint) {
  const Camera c = distortedCamera();
  const Eigen::Vector3d onAxis = c.R.transpose() * (Eigen::Vector3d(0, 0, 3) - c.t);
  const std::optional<Eigen::Vector2d> pixel = c.project(onAxis);
  ASSERT_TRUE(pixel);
  EXPECT_NEAR(pixel->x(), c.cx, 1e-12);
  EXPECT_NEAR(pixel->y(), c.cy, 1e-12);
}

TEST(CameraModel, ProjectionScalesByFocalLengths) {
  Camera c = distortedCamera();
  c.distortion = {};
  const Eigen::Vector2d pixel = c.projectCameraPoint({0.6, -0.4, 2});  // normalised kPoint
  EXPECT_NEAR(pixel.x(), 500 * 0.3 + 322.5, 1e-12);
  EXPECT_NEAR(pixel.y(), 520 * -0.2 + 238.25, 1e-12);  // y down: negative y is above centre
}

TEST(CameraModel, CentreIsMinusRTransposeT) {
  Camera c;
  c.R << 0, -1, 0, 1, 0, 0, 0, 0, 1;  // 90 degrees about z
  c.t = {1, 2, 3};
  EXPECT_EQ(c.centre(), Eigen::Vector3d(-2, 1, -3));  // -Rᵀ t worked by hand
  EXPECT_EQ(c.toCamera(c.centre()), Eigen::Vector3d::Zero());
}

TEST(CameraModel, PointsOnOrBehindTheCameraPlaneDoNotProject) {
  const Camera c = distortedCamera();
  const auto world = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    return c.R.transpose() * (p - c.t);
  };
  EXPECT_FALSE(c.project(world({0.1, 0.2, -1})));
  EXPECT_FALSE(c.project(world({0.1, 0.2, 0})));
  EXPECT_TRUE(c.project(world({0.1, 0.2, 1e-3})));
}

TEST(CameraModel, ImageBoundsAreThePixelCorners) {
  const Camera c = distortedCamera();
  EXPECT_TRUE(c.inImage({0, 0}));
  EXPECT_TRUE(c.inImage({640, 480}));
  EXPECT_FALSE(c.inImage({-1e-9, 10}));
  EXPECT_FALSE(c.inImage({10, 480 + 1e-9}));
}

}  // namespace
}  // namespace texgrad
