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
  const double bottom = (1 - tx) * texel(x0, y0) + tx * texel(x0 + 1, y0);
  const double top = (1 - tx) * texel(x0, y0 + 1) + tx * texel(x0 + 1, y0 + 1);
  return static_cast<float>((1 - ty) * bottom + ty * top);
}

}  // namespace texgrad
