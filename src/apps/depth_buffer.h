// Apps layer (private): the mesh rasterised as a camera sees it (nearest face per sample), for
// the visibility test of photo projection.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "texgrad/io/camera.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Nearest face per sample of a rectangle of the camera's *pinhole* image plane (pixel units,
/// distortion not applied, so triangles stay triangles): sample (i, j) sits at pinhole pixel
/// lo + (i + 0.5, j + 0.5) / scale. Depth is interpolated perspective-correctly (linear in 1/z);
/// geometry in front of the near plane z = zNear is clipped away.
class DepthBuffer {
 public:
  /// Rasterises every triangle of `mesh` (front and back faces) over [lo, hi] at `scale` samples
  /// per photo pixel.
  DepthBuffer(const TexturedMesh& mesh, const Camera& camera, const Eigen::Vector2d& lo,
              const Eigen::Vector2d& hi, double scale, double zNear);
  /// Face nearest the camera at pinhole pixel position q; -1 where no face covers the sample or
  /// q lies outside the rectangle.
  int32_t faceAt(const Eigen::Vector2d& q) const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  void rasterise(const Eigen::Vector3d (&corners)[3], int32_t face);

  const Camera& camera_;
  Eigen::Vector2d lo_;
  double scale_;
  int width_ = 0, height_ = 0;
  std::vector<float> depth_;
  std::vector<int32_t> face_;
};

}  // namespace texgrad
