// Apps layer: a distance field as a picture for people (viridis ramp with contour lines), used by
// the geodesic command and its tests.
#include "texgrad/apps/distance_colour_map.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "texgrad/core/error.h"

namespace texgrad {
namespace {

/// Isoline half-width in texels (lines fade out linearly to this distance from the level).
constexpr double kIsolineHalfWidth = 0.75;
/// How dark an isoline is at its centre (0: colour unchanged, 1: black).
constexpr double kIsolineDarkness = 0.85;
/// Colour of texels no source reaches in distanceColourMap.
constexpr float kUnreachableGrey = 0.5f;

/// Viridis colour map at t in [0, 1] (9 samples of matplotlib's table, linearly interpolated).
Eigen::Vector3d viridis(double t) {
  static const std::array<Eigen::Vector3d, 9> table{
      Eigen::Vector3d(0.267, 0.005, 0.329), Eigen::Vector3d(0.279, 0.175, 0.483),
      Eigen::Vector3d(0.230, 0.322, 0.546), Eigen::Vector3d(0.173, 0.449, 0.558),
      Eigen::Vector3d(0.128, 0.567, 0.551), Eigen::Vector3d(0.158, 0.684, 0.502),
      Eigen::Vector3d(0.369, 0.789, 0.383), Eigen::Vector3d(0.678, 0.864, 0.190),
      Eigen::Vector3d(0.993, 0.906, 0.144)};
  const double x = std::clamp(t, 0.0, 1.0) * static_cast<double>(table.size() - 1);
  const size_t i = std::min(static_cast<size_t>(x), table.size() - 2);
  const double f = x - static_cast<double>(i);
  return (1.0 - f) * table[i] + f * table[i + 1];
}

}  // namespace

Image distanceColourMap(const TexelGrid& grid, const Eigen::VectorXd& distances, double maxDistance,
                        int isolines) {
  if (distances.size() != grid.unknownCount())
    throw InvalidInputError("distanceColourMap: expected one distance per unknown (" +
                            std::to_string(grid.unknownCount()) + "), got " +
                            std::to_string(distances.size()));
  if (isolines < 0) throw InvalidInputError("isolines must be >= 0");
  Image image(grid.imageWidth, grid.imageHeight, 3, PixelFormat::UInt8);
  const double scale = maxDistance > 0.0 ? 1.0 / maxDistance : 0.0;
  // Distance in isoline units, NaN off the grid, at an inactive texel or an unreached one (NaN,
  // not std::optional: GCC 12 reports the optional's value as maybe uninitialised when the
  // sanitizer build leaves UBSan's null check out).
  auto level = [&](int x, int y) {
    constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    if (x < 0 || y < 0 || x >= grid.nx || y >= grid.ny) return kNone;
    const int32_t u = grid.unknownOfTexel[static_cast<size_t>(grid.texelIndex(x, y))];
    if (u < 0 || !std::isfinite(distances[u])) return kNone;
    return distances[u] * scale * (isolines + 1);
  };
  // Derivative of the level along one axis by central (or one-sided) differences.
  auto slope = [&](double centre, double minus, double plus) {
    const bool hasMinus = !std::isnan(minus), hasPlus = !std::isnan(plus);
    if (hasMinus && hasPlus) return 0.5 * (plus - minus);
    if (hasPlus) return plus - centre;
    if (hasMinus) return centre - minus;
    return 0.0;
  };
  tbb::parallel_for(0, grid.ny, [&](int y) {
    for (int x = 0; x < grid.nx; ++x) {
      if (!grid.inImage(x, y)) continue;
      const int32_t u = grid.unknownOfTexel[static_cast<size_t>(grid.texelIndex(x, y))];
      if (u < 0) continue;
      if (!std::isfinite(distances[u])) {
        for (int c = 0; c < 3; ++c) image.at(x + grid.x0, y + grid.y0, c) = kUnreachableGrey;
        continue;
      }
      Eigen::Vector3d colour = viridis(distances[u] * scale);
      if (isolines > 0) {
        const double s = level(x, y);
        const double gx = slope(s, level(x - 1, y), level(x + 1, y));
        const double gy = slope(s, level(x, y - 1), level(x, y + 1));
        const double nearest = std::round(s);
        const double gradient = std::hypot(gx, gy);
        if (nearest >= 1.0 && nearest <= isolines && gradient > 0.0) {
          const double texels = std::abs(s - nearest) / gradient;
          colour *= 1.0 - kIsolineDarkness * std::clamp(1.0 - texels / kIsolineHalfWidth, 0.0, 1.0);
        }
      }
      for (int c = 0; c < 3; ++c)
        image.at(x + grid.x0, y + grid.y0, c) = static_cast<float>(colour[c]);
    }
  });
  return image;
}

}  // namespace texgrad
