// Test support: a synthetic photo capture of a shared mesh (true texture, cameras around it with
// per-view gain, colour cast and shading, photos rendered by photo_renderer.h), and the error
// measures the photo tests check: RMS after a per-channel gain/offset fit and the jump between
// regions taken from different views.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "photo_renderer.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/apps/texel_signal.h"

namespace texgrad::test {

/// The mesh's texture box-filtered down to width x height (an integer factor), the ground truth.
inline Image boxDownsample(const Image& full, int width, int height) {
  const int fx = full.width / width, fy = full.height / height;
  Image out(width, height, 3, PixelFormat::Float);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
      for (int c = 0; c < 3; ++c) {
        double sum = 0.0;
        for (int b = 0; b < fy; ++b)
          for (int a = 0; a < fx; ++a)
            sum += full.at(i * fx + a, j * fy + b, std::min(c, full.channels - 1));
        out.at(i, j, c) = static_cast<float>(sum / (fx * fy));
      }
  return out;
}

/// `image` smoothed by `passes` separable [1 2 1] / 4 filters (clamp-to-edge): a band-limited
/// ground truth, as a texture baked at the atlas's resolution is.
inline Image tentBlur(Image image, int passes) {
  for (int pass = 0; pass < passes; ++pass)
    for (int axis = 0; axis < 2; ++axis) {
      const Image in = image;
      for (int j = 0; j < image.height; ++j)
        for (int i = 0; i < image.width; ++i)
          for (int c = 0; c < image.channels; ++c) {
            const int di = axis == 0 ? 1 : 0, dj = axis == 1 ? 1 : 0;
            const float a = in.at(std::max(i - di, 0), std::max(j - dj, 0), c);
            const float b =
                in.at(std::min(i + di, image.width - 1), std::min(j + dj, image.height - 1), c);
            image.at(i, j, c) = 0.25f * a + 0.5f * in.at(i, j, c) + 0.25f * b;
          }
    }
  return image;
}

/// One synthetic capture: cameras around the mesh and the look of each view.
struct Capture {
  std::vector<Camera> cameras;
  std::vector<ViewLook> looks;
};

/// `views` cameras on a sphere around the mesh's bounding box (directions spread by a golden
/// spiral), photos width x height; every other camera has radial distortion (k1 = -0.08,
/// k2 = 0.01); gains, colour casts and light directions differ per view.
inline Capture captureAround(const TexturedMesh& mesh, int views, int width, int height) {
  Eigen::Vector3d lo = mesh.positions[0], hi = mesh.positions[0];
  for (const Eigen::Vector3d& p : mesh.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector3d centre = (lo + hi) / 2.0;
  const double radius = (hi - lo).norm() / 2.0, distance = 3.0 * radius;
  const double focal = 0.9 * (std::min(width, height) / 2.0) * distance / radius;
  Capture capture;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < views; ++k) {
    const double y = 1.0 - 2.0 * (k + 0.5) / views, r = std::sqrt(1.0 - y * y);
    const Eigen::Vector3d dir(r * std::cos(golden * k), y, r * std::sin(golden * k));
    const Eigen::Vector3d up =
        std::abs(y) > 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
    const bool distorted = k % 2 == 1;
    capture.cameras.push_back(lookAtCamera("view" + std::to_string(k) + ".png",
                                           centre + distance * dir, centre, up, width, height,
                                           focal, distorted ? -0.08 : 0.0, distorted ? 0.01 : 0.0));
    ViewLook look;
    look.gain = Eigen::Vector3d(0.75 + 0.04 * (k % 5), 0.8 + 0.03 * ((k * 3) % 5),
                                0.7 + 0.05 * ((k * 2) % 5));
    look.light = (dir + Eigen::Vector3d(0.3 * std::cos(k), 0.5, 0.3 * std::sin(k))).normalized();
    look.shading = 0.06;
    capture.looks.push_back(look);
  }
  return capture;
}

/// Per unknown: the mass of its basis function (row sum of M), its area on the surface.
inline Eigen::VectorXd texelMasses(const TexelDomain& domain) {
  return domain.operators().mass() * Eigen::VectorXd::Ones(domain.unknowns());
}

/// Error of `result` to the true texture as the surface shows it: mass-weighted RMS over the
/// texels where `seen` > 0 of result - (a_c truth + b_c), a_c and b_c the weighted least-squares
/// per-channel gain and offset. Weighting by mass measures the error on the surface: a texel
/// whose basis function covers almost no area (a corner of a chart) hardly shows there, and the
/// solve leaves such texels barely determined.
inline double fittedRms(const TexelDomain& domain, const Image& result, const Image& truth,
                        const Image& seen) {
  const Eigen::MatrixXd x = gatherTexels(domain.grid(), result),
                        y = gatherTexels(domain.grid(), truth),
                        s = gatherTexels(domain.grid(), seen);
  const Eigen::VectorXd mass = texelMasses(domain);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index u = 0; u < x.rows(); ++u)
    if (s(u, 0) > 0.0) rows.push_back(u);
  double sum = 0.0, weight = 0.0;
  for (Eigen::Index c = 0; c < 3; ++c) {
    Eigen::MatrixXd a(static_cast<Eigen::Index>(rows.size()), 2);
    Eigen::VectorXd b(a.rows()), w(a.rows());
    for (Eigen::Index k = 0; k < a.rows(); ++k) {
      const Eigen::Index u = rows[static_cast<size_t>(k)];
      w[k] = std::sqrt(mass[u]);
      a(k, 0) = w[k] * y(u, c);
      a(k, 1) = w[k];
      b[k] = w[k] * x(u, c);
    }
    const Eigen::Vector2d fit = a.colPivHouseholderQr().solve(b);
    sum += (a * fit - b).squaredNorm();
    weight += w.squaredNorm();
  }
  return std::sqrt(sum / weight);
}

/// RMS over pairs of neighbouring in-image texels, both active, labelled by different views in
/// `segments` (channel 0 > 0), of the jump (result difference) minus the true texture's jump,
/// after scaling the truth per channel by its least-squares gain to `result` on those texels;
/// each pair weighted by the smaller mass of its two texels (see fittedRms).
inline double regionBoundaryJump(const TexelDomain& domain, const Image& result, const Image& truth,
                                 const Image& segments) {
  const TexelGrid& grid = domain.grid();
  const Eigen::VectorXd mass = texelMasses(domain);
  auto massAt = [&](int i, int j) {
    return mass[grid.unknownOfTexel[static_cast<size_t>(
        grid.texelIndex(i - grid.x0, j - grid.y0))]];
  };
  double sum = 0.0, count = 0.0;
  auto active = [&](int i, int j) {
    const int x = i - grid.x0, y = j - grid.y0;
    return x >= 0 && y >= 0 && x < grid.nx && y < grid.ny &&
           grid.unknownOfTexel[static_cast<size_t>(grid.texelIndex(x, y))] >= 0 &&
           segments.at(i, j) > 0.0f;
  };
  double gain[3];
  for (int c = 0; c < 3; ++c) {
    double rt = 0.0, tt = 0.0;
    for (int j = 0; j < result.height; ++j)
      for (int i = 0; i < result.width; ++i)
        if (active(i, j)) {
          rt += result.at(i, j, c) * truth.at(i, j, c);
          tt += truth.at(i, j, c) * truth.at(i, j, c);
        }
    gain[c] = tt > 0.0 ? rt / tt : 1.0;
  }
  for (int j = 0; j + 1 < result.height; ++j)
    for (int i = 0; i + 1 < result.width; ++i) {
      if (!active(i, j)) continue;
      for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (!active(i + di, j + dj) || segments.at(i, j) == segments.at(i + di, j + dj)) continue;
        for (int c = 0; c < 3; ++c) {
          const double jump = result.at(i + di, j + dj, c) - result.at(i, j, c);
          const double trueJump = gain[c] * (truth.at(i + di, j + dj, c) - truth.at(i, j, c));
          const double w = std::min(massAt(i, j), massAt(i + di, j + dj));
          sum += w * (jump - trueJump) * (jump - trueJump);
          count += w;
        }
      }
    }
  return count > 0.0 ? std::sqrt(sum / count) : 0.0;
}

}  // namespace texgrad::test
