// Renderer-style texture lookups on an Image (bilinear, clamp-to-edge), in UV or texel coordinates.
#pragma once

#include <Eigen/Core>

#include "texgrad/io/image.h"

namespace texgrad {

/// Bilinear lookup at continuous texel coordinates p = (u W - 0.5, v H - 0.5) with clamp-to-edge
/// addressing (what a GPU sampler does with CLAMP_TO_EDGE and LINEAR filtering).
float sampleBilinearTexel(const Image& image, const Eigen::Vector2d& p, int channel);

/// Bilinear lookup at a UV point (v upward), clamp-to-edge.
inline float sampleBilinear(const Image& image, const Eigen::Vector2d& uv, int channel) {
  return sampleBilinearTexel(
      image, {uv.x() * image.width - 0.5, uv.y() * image.height - 0.5}, channel);
}

}  // namespace texgrad
