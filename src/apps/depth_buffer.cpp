// Z-buffer of a mesh seen from a camera; see the header.
#include "depth_buffer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace texgrad {
namespace {

/// Clips the polygon `in` (camera coordinates) to z >= zNear (Sutherland-Hodgman, one plane).
std::vector<Eigen::Vector3d> clipNear(const std::vector<Eigen::Vector3d>& in, double zNear) {
  std::vector<Eigen::Vector3d> out;
  for (size_t k = 0; k < in.size(); ++k) {
    const Eigen::Vector3d& a = in[k];
    const Eigen::Vector3d& b = in[(k + 1) % in.size()];
    const bool aIn = a.z() >= zNear, bIn = b.z() >= zNear;
    if (aIn) out.push_back(a);
    if (aIn != bIn) out.push_back(a + (b - a) * ((zNear - a.z()) / (b.z() - a.z())));
  }
  return out;
}

}  // namespace

DepthBuffer::DepthBuffer(const TexturedMesh& mesh, const Camera& camera, const Eigen::Vector2d& lo,
                         const Eigen::Vector2d& hi, double scale, double zNear)
    : camera_(camera), lo_(lo), scale_(scale) {
  width_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) * scale)));
  height_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) * scale)));
  const size_t samples = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  depth_.assign(samples, std::numeric_limits<float>::infinity());
  face_.assign(samples, -1);
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    std::vector<Eigen::Vector3d> polygon;
    for (int32_t v : t) polygon.push_back(camera.toCamera(mesh.positions[static_cast<size_t>(v)]));
    if (std::min({polygon[0].z(), polygon[1].z(), polygon[2].z()}) < zNear)
      polygon = clipNear(polygon, zNear);
    for (size_t k = 2; k < polygon.size(); ++k) {
      const Eigen::Vector3d corners[3] = {polygon[0], polygon[k - 1], polygon[k]};
      rasterise(corners, static_cast<int32_t>(f));
    }
  }
}

void DepthBuffer::rasterise(const Eigen::Vector3d (&corners)[3], int32_t face) {
  Eigen::Vector2d s[3];
  double w[3];
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& p = corners[k];
    const Eigen::Vector2d pinhole(camera_.fx * p.x() / p.z() + camera_.cx,
                                  camera_.fy * p.y() / p.z() + camera_.cy);
    s[k] = (pinhole - lo_) * scale_;
    w[k] = 1.0 / p.z();
  }
  const double area = (s[1] - s[0]).x() * (s[2] - s[0]).y() - (s[1] - s[0]).y() * (s[2] - s[0]).x();
  if (!(std::abs(area) > 0.0)) return;
  const double lox = std::min({s[0].x(), s[1].x(), s[2].x()});
  const double hix = std::max({s[0].x(), s[1].x(), s[2].x()});
  const double loy = std::min({s[0].y(), s[1].y(), s[2].y()});
  const double hiy = std::max({s[0].y(), s[1].y(), s[2].y()});
  // Sample (i, j) sits at (i + 0.5, j + 0.5); clamped in double first, since corners near the
  // near plane project far outside the buffer (beyond int range).
  auto sample = [](double c, int size, bool up) {
    const double at = up ? std::ceil(c - 0.5) : std::floor(c - 0.5);
    return static_cast<int>(std::clamp(at, -1.0, static_cast<double>(size)));
  };
  const int i0 = std::max(0, sample(lox, width_, true));
  const int i1 = std::min(width_ - 1, sample(hix, width_, false));
  const int j0 = std::max(0, sample(loy, height_, true));
  const int j1 = std::min(height_ - 1, sample(hiy, height_, false));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const Eigen::Vector2d q(i + 0.5, j + 0.5);
      double b[3];
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d& a = s[(k + 1) % 3];
        const Eigen::Vector2d& c = s[(k + 2) % 3];
        b[k] = ((c - a).x() * (q - a).y() - (c - a).y() * (q - a).x()) / area;
      }
      if (b[0] < 0.0 || b[1] < 0.0 || b[2] < 0.0) continue;
      const auto depth = static_cast<float>(1.0 / (b[0] * w[0] + b[1] * w[1] + b[2] * w[2]));
      const size_t index =
          static_cast<size_t>(j) * static_cast<size_t>(width_) + static_cast<size_t>(i);
      if (depth < depth_[index]) {
        depth_[index] = depth;
        face_[index] = face;
      }
    }
}

int32_t DepthBuffer::faceAt(const Eigen::Vector2d& q) const {
  const Eigen::Vector2d b = (q - lo_) * scale_;
  if (!(b.x() >= 0.0 && b.y() >= 0.0 && b.x() < width_ && b.y() < height_)) return -1;
  const auto i = static_cast<int>(b.x()), j = static_cast<int>(b.y());
  return face_[static_cast<size_t>(j) * static_cast<size_t>(width_) + static_cast<size_t>(i)];
}

}  // namespace texgrad
