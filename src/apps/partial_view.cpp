// Compact partial textures; see the header.
#include "texgrad/apps/partial_view.h"

#include <algorithm>

#include "texgrad/core/error.h"

namespace texgrad {

int64_t PartialView::storageBytes() const {
  return static_cast<int64_t>(unknowns.capacity() * sizeof(int32_t) +
                              values.capacity() * sizeof(float) +
                              confidence.capacity() * sizeof(float));
}

PartialView compactPartial(const TexelGrid& grid, const Image& partial, const Image& confidence) {
  for (const Image* image : {&partial, &confidence})
    if (image->width != grid.imageWidth || image->height != grid.imageHeight)
      throw InvalidInputError("compactPartial: image is " + std::to_string(image->width) + "x" +
                              std::to_string(image->height) + " but the texel grid was built for " +
                              std::to_string(grid.imageWidth) + "x" +
                              std::to_string(grid.imageHeight));
  PartialView view;
  view.channels = partial.channels;
  for (int u = 0; u < grid.unknownCount(); ++u) {
    // Clamp-to-edge outside the image, as gatherTexels.
    const int t = grid.texelOfUnknown[static_cast<size_t>(u)];
    const int i = std::clamp(t % grid.nx + grid.x0, 0, partial.width - 1);
    const int j = std::clamp(t / grid.nx + grid.y0, 0, partial.height - 1);
    const float c = std::min(confidence.at(i, j), 1.0f);
    if (!(c > 0.0f)) continue;
    view.unknowns.push_back(u);
    view.confidence.push_back(c);
    for (int ch = 0; ch < partial.channels; ++ch) view.values.push_back(partial.at(i, j, ch));
  }
  return view;
}

PartialView compactPartial(const Eigen::MatrixXd& values, const Eigen::VectorXd& confidence) {
  if (values.rows() != confidence.size())
    throw InvalidInputError("compactPartial: values and confidence have different row counts");
  PartialView view;
  view.channels = static_cast<int>(values.cols());
  for (Eigen::Index u = 0; u < values.rows(); ++u) {
    const double c = std::min(confidence[u], 1.0);
    if (!(c > 0.0)) continue;
    view.unknowns.push_back(static_cast<int32_t>(u));
    view.confidence.push_back(static_cast<float>(c));
    for (Eigen::Index ch = 0; ch < values.cols(); ++ch)
      view.values.push_back(static_cast<float>(values(u, ch)));
  }
  return view;
}

}  // namespace texgrad
