// One source of partials-mode stitching kept compactly: only the unknowns it sees, with its
// colour and confidence there (what `texgrad texture` holds per photo between projection and
// stitching).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/image.h"

namespace texgrad {

/// A partial texture and its confidence at the unknowns with confidence > 0 (ascending unknown
/// index); the unknowns it does not see have confidence 0 and no colour.
struct PartialView {
  int channels = 0;               ///< colour channels per entry
  std::vector<int32_t> unknowns;  ///< seen unknowns, ascending
  std::vector<float> values;      ///< unknowns.size() x channels, row-major
  std::vector<float> confidence;  ///< per seen unknown, in (0, 1]
  /// Number of seen unknowns.
  size_t size() const { return unknowns.size(); }
  /// Bytes held by the three arrays (their capacity).
  int64_t storageBytes() const;
};

/// The compact form of a partial texture and its confidence map (channel 0, clamped to [0, 1])
/// at the grid's unknowns, read as gatherTexels reads them (clamp-to-edge outside the image).
/// Both images must have the grid's image size.
PartialView compactPartial(const TexelGrid& grid, const Image& partial, const Image& confidence);

/// The compact form of dense per-unknown blocks (values n x channels, confidence n, clamped to
/// [0, 1]).
PartialView compactPartial(const Eigen::MatrixXd& values, const Eigen::VectorXd& confidence);

}  // namespace texgrad
