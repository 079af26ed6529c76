// Test support: synthetic photographs of a textured mesh by ray casting, written independently of
// the library's photo projection (its own distortion formulas and no z-buffer), so tests of
// `project` / `texture` compare against ground truth rather than against the code under test.
#pragma once

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "texgrad/io/camera.h"
#include "texgrad/io/image.h"
#include "texgrad/io/image_sampling.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad::test {

/// Photometric look of one synthetic view: colour = texture * gain * (base + shading n . light).
struct ViewLook {
  Eigen::Vector3d gain = Eigen::Vector3d::Ones();    ///< exposure and colour cast per channel
  Eigen::Vector3d light = Eigen::Vector3d::UnitZ();  ///< unit direction towards the light
  double shading = 0.0;                              ///< amplitude of the normal-dependent term
  double background = 0.5;                           ///< value of pixels that see no surface
};

/// Radial distortion of normalised coordinates (COLMAP RADIAL: k1, k2), written out here.
inline Eigen::Vector2d radialDistort(double k1, double k2, const Eigen::Vector2d& x) {
  const double r2 = x.squaredNorm();
  return x * (1.0 + k1 * r2 + k2 * r2 * r2);
}

/// Inverse of radialDistort by fixed-point iteration (mild distortion only).
inline Eigen::Vector2d radialUndistort(double k1, double k2, const Eigen::Vector2d& xd) {
  Eigen::Vector2d x = xd;
  for (int k = 0; k < 50; ++k) x = xd - (radialDistort(k1, k2, x) - x);
  return x;
}

/// A camera at `centre` looking at `target` with image y pointing away from world +`up`
/// (OpenCV axes: x right, y down, z forward), pixel focal length `focal`, principal point at
/// the image centre, radial distortion k1, k2 (RADIAL model when non-zero).
inline Camera lookAtCamera(const std::string& name, const Eigen::Vector3d& centre,
                           const Eigen::Vector3d& target, const Eigen::Vector3d& up, int width,
                           int height, double focal, double k1 = 0.0, double k2 = 0.0) {
  Camera c;
  c.name = name;
  c.width = width;
  c.height = height;
  c.fx = c.fy = focal;
  c.cx = width / 2.0;
  c.cy = height / 2.0;
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = z.cross(up).normalized();
  const Eigen::Vector3d y = z.cross(x);
  c.R.row(0) = x.transpose();
  c.R.row(1) = y.transpose();
  c.R.row(2) = z.transpose();
  c.t = -c.R * centre;
  if (k1 != 0.0 || k2 != 0.0) {
    c.distortion.model = DistortionModel::Radial;
    c.distortion.k1 = k1;
    c.distortion.k2 = k2;
  }
  return c;
}

/// Pixel (COLMAP convention: top-left origin, pixel centres at +0.5) of a world point, from the
/// camera's fields with this file's own formulas (radial models only).
inline Eigen::Vector2d projectIndependently(const Camera& c, const Eigen::Vector3d& world) {
  const Eigen::Vector3d p = c.R * world + c.t;
  const Eigen::Vector2d xd = radialDistort(c.distortion.k1, c.distortion.k2, p.head<2>() / p.z());
  return {c.fx * xd.x() + c.cx, c.fy * xd.y() + c.cy};
}

/// Renders `mesh` textured with `texture` (bilinear) as `camera` sees it, by casting one ray per
/// pixel centre through the lens model (radial distortion undone per pixel) and taking the
/// nearest hit (Moller-Trumbore). Returns the photo in texel order (row 0 = bottom), 3 channels,
/// Float. Every vertex must lie in front of the camera.
inline Image renderPhoto(const TexturedMesh& mesh, const Image& texture, const Camera& camera,
                         const ViewLook& look) {
  const double k1 = camera.distortion.k1, k2 = camera.distortion.k2;
  std::vector<Eigen::Vector3d> cam(mesh.positions.size()),
      normal(mesh.positions.size(), Eigen::Vector3d::Zero());
  for (size_t v = 0; v < cam.size(); ++v) cam[v] = camera.R * mesh.positions[v] + camera.t;
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3d n =
        (mesh.positions[static_cast<size_t>(t[1])] - mesh.positions[static_cast<size_t>(t[0])])
            .cross(mesh.positions[static_cast<size_t>(t[2])] -
                   mesh.positions[static_cast<size_t>(t[0])]);
    for (int32_t v : t) normal[static_cast<size_t>(v)] += n;
  }
  // Bin faces by their bounding box on the plane z = 1 (undistorted normalised coordinates).
  constexpr int kTiles = 64;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Eigen::Vector3d& p : cam) {
    lo = lo.cwiseMin(p.head<2>() / p.z());
    hi = hi.cwiseMax(p.head<2>() / p.z());
  }
  const Eigen::Vector2d cell = (hi - lo) / kTiles;
  auto tileOf = [&](const Eigen::Vector2d& x, int axis) {
    return std::clamp(static_cast<int>((x[axis] - lo[axis]) / cell[axis]), 0, kTiles - 1);
  };
  std::vector<std::vector<int32_t>> tiles(kTiles * kTiles);
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    Eigen::Vector2d a = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), b = -a;
    for (int32_t v : mesh.triangles[f]) {
      const Eigen::Vector3d& p = cam[static_cast<size_t>(v)];
      a = a.cwiseMin(p.head<2>() / p.z());
      b = b.cwiseMax(p.head<2>() / p.z());
    }
    for (int j = tileOf(a, 1); j <= tileOf(b, 1); ++j)
      for (int i = tileOf(a, 0); i <= tileOf(b, 0); ++i)
        tiles[static_cast<size_t>(j * kTiles + i)].push_back(static_cast<int32_t>(f));
  }
  Image photo(camera.width, camera.height, 3, PixelFormat::Float);
  tbb::parallel_for(0, camera.height, [&](int row) {
    for (int col = 0; col < camera.width; ++col) {
      const Eigen::Vector2d xd((col + 0.5 - camera.cx) / camera.fx,
                               (row + 0.5 - camera.cy) / camera.fy);
      const Eigen::Vector2d x = radialUndistort(k1, k2, xd);
      const Eigen::Vector3d dir(x.x(), x.y(), 1.0);
      double best = std::numeric_limits<double>::infinity();
      int32_t hit = -1;
      Eigen::Vector3d bary;
      if (x.x() >= lo.x() && x.y() >= lo.y() && x.x() <= hi.x() && x.y() <= hi.y())
        for (int32_t f : tiles[static_cast<size_t>(tileOf(x, 1) * kTiles + tileOf(x, 0))]) {
          const Triangle& t = mesh.triangles[static_cast<size_t>(f)];
          const Eigen::Vector3d& p0 = cam[static_cast<size_t>(t[0])];
          const Eigen::Vector3d e1 = cam[static_cast<size_t>(t[1])] - p0;
          const Eigen::Vector3d e2 = cam[static_cast<size_t>(t[2])] - p0;
          const Eigen::Vector3d h = dir.cross(e2);
          const double det = e1.dot(h);
          if (det == 0.0) continue;
          const Eigen::Vector3d s = -p0;
          const double b1 = s.dot(h) / det;
          const Eigen::Vector3d q = s.cross(e1);
          const double b2 = dir.dot(q) / det;
          const double along = e2.dot(q) / det;
          if (b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0 || !(along > 0.0) || along >= best) continue;
          best = along;
          hit = f;
          bary = {1.0 - b1 - b2, b1, b2};
        }
      const int texelRow = camera.height - 1 - row;
      if (hit < 0) {
        for (int c = 0; c < 3; ++c)
          photo.at(col, texelRow, c) = static_cast<float>(look.background);
        continue;
      }
      const Triangle& t = mesh.triangles[static_cast<size_t>(hit)];
      const Triangle& tu = mesh.uvTriangles[static_cast<size_t>(hit)];
      Eigen::Vector2d uv = Eigen::Vector2d::Zero();
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        uv += bary[k] * mesh.uvs[static_cast<size_t>(tu[static_cast<size_t>(k)])];
        n += bary[k] * normal[static_cast<size_t>(t[static_cast<size_t>(k)])].normalized();
      }
      const double shade = 1.0 - look.shading + look.shading * n.normalized().dot(look.light);
      for (int c = 0; c < 3; ++c)
        photo.at(col, texelRow, c) = static_cast<float>(
            sampleBilinear(texture, uv, std::min(c, texture.channels - 1)) * look.gain[c] * shade);
    }
  });
  return photo;
}

}  // namespace texgrad::test
