// Bilinear clamp-to-edge texture lookups used by diagnostics and apps.
#include "texgrad/io/image_sampling.h"

#include <algorithm>
#include <cmath>

namespace texgrad {

float sampleBilinearTexel(const Image& image, const Eigen::Vector2d& p, int channel) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y());
  const double tx = p.x() - fx, ty = p.y() - fy;
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  auto texel = [&](int x, int y) {
    x = std::clamp(x, 0, image.width - 1);
    y = std::clamp(y, 0, image.height - 1);
    return static_cast<double>(image.at(x, y, channel));
  };
  // A texel of weight 0 is not read: 0 * inf would turn a lookup next to an infinite texel (an
  // unreachable geodesic distance) into NaN although the texel does not contribute.
  auto mix = [](double a, double b, double t) { return t == 0.0 ? a : (1 - t) * a + t * b; };
  auto row = [&](int y) { return mix(texel(x0, y), texel(x0 + 1, y), tx); };
  return static_cast<float>(mix(row(y0), row(y0 + 1), ty));
}

}  // namespace texgrad
