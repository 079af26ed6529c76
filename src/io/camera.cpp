#include "texgrad/io/camera.h"

#include <Eigen/Geometry>

namespace texgrad {

Eigen::Vector2d LensDistortion::apply(const Eigen::Vector2d& normalised) const {
  const double x = normalised.x(), y = normalised.y();
  const double r2 = x * x + y * y;
  switch (model) {
    case DistortionModel::None:
      return normalised;
    case DistortionModel::SimpleRadial:
      return normalised * (1 + k1 * r2);
    case DistortionModel::Radial:
      return normalised * (1 + k1 * r2 + k2 * r2 * r2);
    case DistortionModel::OpenCV: {
      const double radial = 1 + k1 * r2 + k2 * r2 * r2;
      return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
              y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
    }
  }
  return normalised;
}

Eigen::Vector3d Camera::centre() const {
  return -R.transpose() * t;
}

Eigen::Vector3d Camera::toCamera(const Eigen::Vector3d& world) const {
  return R * world + t;
}

std::optional<Eigen::Vector2d> Camera::project(const Eigen::Vector3d& world) const {
  const Eigen::Vector3d p = toCamera(world);
  if (!(p.z() > 0)) return std::nullopt;
  return projectCameraPoint(p);
}

Eigen::Vector2d Camera::projectCameraPoint(const Eigen::Vector3d& cameraPoint) const {
  const Eigen::Vector2d distorted = distortion.apply(cameraPoint.head<2>() / cameraPoint.z());
  return {fx * distorted.x() + cx, fy * distorted.y() + cy};
}

bool Camera::inImage(const Eigen::Vector2d& pixel) const {
  return pixel.x() >= 0 && pixel.y() >= 0 && pixel.x() <= width && pixel.y() <= height;
}

}  // namespace texgrad
