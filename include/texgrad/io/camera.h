// A calibrated photograph's camera: intrinsics, pose and lens distortion (COLMAP/OpenCV
// conventions).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace texgrad {

/// Lens distortion models of COLMAP's camera models (none for PINHOLE and SIMPLE_PINHOLE).
enum class DistortionModel { None, SimpleRadial, Radial, OpenCV };

/// Lens distortion coefficients applied to normalised image coordinates (x, y) = (X/Z, Y/Z).
///
/// SimpleRadial uses k1, Radial k1 and k2, OpenCV k1, k2 (radial) and p1, p2 (tangential):
/// x' = x (1 + k1 r² + k2 r⁴) + 2 p1 x y + p2 (r² + 2 x²), y' likewise with p1 and p2 swapped,
/// exactly as COLMAP's and OpenCV's models.
struct LensDistortion {
  DistortionModel model = DistortionModel::None;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0;  ///< coefficients; unused ones stay 0

  /// Maps undistorted normalised coordinates to distorted ones.
  Eigen::Vector2d apply(const Eigen::Vector2d& normalised) const;
};

/// One photograph and the pinhole camera (plus distortion) that took it.
///
/// World to camera: X_cam = R X + t, the camera looks down +z, x right, y down (OpenCV, COLMAP).
/// Pixel coordinates have their origin at the image's top-left corner, so the centre of pixel
/// (column i, row j counted from the top) is (i + 0.5, j + 0.5), as in COLMAP.
struct Camera {
  std::string name;                 ///< image file name as the camera file gives it
  std::filesystem::path imagePath;  ///< resolved path of the photo (empty until resolved)
  int width = 0, height = 0;        ///< image size in pixels
  double fx = 0, fy = 0;            ///< focal lengths in pixels
  double cx = 0, cy = 0;            ///< principal point in pixels
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  ///< rotation world -> camera
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      ///< translation world -> camera
  LensDistortion distortion;                        ///< lens distortion (none by default)

  /// Camera centre in world coordinates, C = -Rᵀ t.
  Eigen::Vector3d centre() const;
  /// A world point in camera coordinates.
  Eigen::Vector3d toCamera(const Eigen::Vector3d& world) const;
  /// Pixel position of a world point, or nothing when it lies on or behind the camera plane.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& world) const;
  /// Pixel position of a camera-space point with z > 0 (distortion applied).
  Eigen::Vector2d projectCameraPoint(const Eigen::Vector3d& cameraPoint) const;
  /// True when a pixel position lies inside the image.
  bool inImage(const Eigen::Vector2d& pixel) const;
};

}  // namespace texgrad
