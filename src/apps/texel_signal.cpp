// Gather/scatter between images and texel unknowns, and per-cell maps for local modulation.
#include "texgrad/apps/texel_signal.h"

#include <algorithm>
#include <string>

#include "texgrad/core/error.h"
#include "texgrad/io/image_sampling.h"

namespace texgrad {

void requireGridImageSize(const TexelGrid& grid, const Image& image) {
  if (image.width != grid.imageWidth || image.height != grid.imageHeight)
    throw InvalidInputError("texture is " + std::to_string(image.width) + "x" +
                            std::to_string(image.height) + " but the texel grid was built for " +
                            std::to_string(grid.imageWidth) + "x" +
                            std::to_string(grid.imageHeight));
}

std::array<int, 2> imageTexelOf(const TexelGrid& grid, int u) {
  const int t = grid.texelOfUnknown[static_cast<size_t>(u)];
  return {std::clamp(t % grid.nx + grid.x0, 0, grid.imageWidth - 1),
          std::clamp(t / grid.nx + grid.y0, 0, grid.imageHeight - 1)};
}

Eigen::MatrixXd gatherTexels(const TexelGrid& grid, const Image& image) {
  requireGridImageSize(grid, image);
  Eigen::MatrixXd values(grid.unknownCount(), image.channels);
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const auto [i, j] = imageTexelOf(grid, u);
    for (int c = 0; c < image.channels; ++c) values(u, c) = image.at(i, j, c);
  }
  return values;
}

void scatterTexels(const TexelGrid& grid, const Eigen::MatrixXd& values, Image& image) {
  if (values.rows() != grid.unknownCount() || values.cols() != image.channels)
    throw InvalidInputError("scatterTexels: value block has the wrong shape");
  for (int c = 0; c < image.channels; ++c) scatterTexelChannel(grid, values.col(c), c, image);
}

void scatterTexelChannel(const TexelGrid& grid, const Eigen::Ref<const Eigen::VectorXd>& values,
                         int c, Image& image) {
  if (values.size() != grid.unknownCount() || c < 0 || c >= image.channels)
    throw InvalidInputError("scatterTexelChannel: " + std::to_string(values.size()) +
                            " values for channel " + std::to_string(c) + " of " +
                            std::to_string(image.channels) + "; expected " +
                            std::to_string(grid.unknownCount()) + " for a channel of the image");
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const int t = grid.texelOfUnknown[u];
    const int x = t % grid.nx, y = t / grid.nx;
    if (grid.inImage(x, y)) image.at(x + grid.x0, y + grid.y0, c) = static_cast<float>(values(u));
  }
}

std::vector<double> cellValuesFromMap(const TexelGrid& grid, const Image& map, double low,
                                      double high) {
  if (map.empty()) throw InvalidInputError("the modulation map is empty");
  std::vector<double> values(grid.cellCoverage.size(), low);
  const int channels = map.channels >= 3 ? 3 : 1;
  for (int b = -1; b < grid.ny; ++b)
    for (int a = -1; a < grid.nx; ++a) {
      const Eigen::Vector2d uv = grid.toUv({a + 0.5, b + 0.5});
      double s = 0.0;
      for (int c = 0; c < channels; ++c) s += sampleBilinear(map, uv, c);
      values[grid.cellIndex(a, b)] = low + (high - low) * std::clamp(s / channels, 0.0, 1.0);
    }
  return values;
}

}  // namespace texgrad
