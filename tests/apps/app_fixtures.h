// Shared helpers of the app tests: random textures, RMS over active texels, Dirichlet energy.
#pragma once

#include <Eigen/Core>
#include <random>

#include "texgrad/apps/texel_domain.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/io/image.h"

namespace texgrad::test {

/// A W x H texture of uniform random values in [lo, hi] (seeded).
inline Image randomTexture(int w, int h, int channels, unsigned seed, float lo = 0.0f,
                           float hi = 1.0f) {
  Image image(w, h, channels, PixelFormat::Float);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(lo, hi);
  for (float& p : image.pixels) p = value(rng);
  return image;
}

/// RMS difference of two images over the domain's active in-image texels (all channels).
inline double activeRms(const TexelDomain& domain, const Image& a, const Image& b) {
  const Eigen::MatrixXd x = gatherTexels(domain.grid(), a), y = gatherTexels(domain.grid(), b);
  return std::sqrt((x - y).squaredNorm() / static_cast<double>(x.size()));
}

/// RMS of an image over the domain's active texels.
inline double activeRms(const TexelDomain& domain, const Image& a) {
  const Eigen::MatrixXd x = gatherTexels(domain.grid(), a);
  return std::sqrt(x.squaredNorm() / static_cast<double>(x.size()));
}

/// Dirichlet energy x^T S x of an image, summed over channels.
inline double dirichletEnergy(const TexelDomain& domain, const Image& image) {
  const Eigen::MatrixXd x = gatherTexels(domain.grid(), image);
  return (x.transpose() * (domain.operators().stiffness() * x)).trace();
}

/// Box-filtered copy of `image` reduced by an integer factor in each direction.
inline Image downsample(const Image& image, int factor) {
  if (factor <= 1) return image;
  Image out(image.width / factor, image.height / factor, image.channels, image.format);
  for (int j = 0; j < out.height; ++j)
    for (int i = 0; i < out.width; ++i)
      for (int c = 0; c < image.channels; ++c) {
        double sum = 0.0;
        for (int b = 0; b < factor; ++b)
          for (int a = 0; a < factor; ++a) sum += image.at(factor * i + a, factor * j + b, c);
        out.at(i, j, c) = static_cast<float>(sum / (factor * factor));
      }
  return out;
}

/// The texture of a shared mesh reduced to at most `maxSize` texels across (box filter).
inline Image textureAtMost(const Image& image, int maxSize) {
  int factor = 1;
  while (image.width / factor > maxSize) factor *= 2;
  return downsample(image, factor);
}

}  // namespace texgrad::test
