// Renders texel classes of a TexelGrid as an image (`texgrad mask`).
#include "texgrad/atlas/texel_mask.h"

#include <array>
#include <cmath>

#include "texgrad/core/error.h"

namespace texgrad {
namespace {

/// Golden-ratio hue steps give neighbouring chart ids clearly different colours.
constexpr double kGoldenRatioConjugate = 0.618033988749895;

std::array<float, 3> chartColour(int chart) {
  const double hue = std::fmod(0.13 + kGoldenRatioConjugate * chart, 1.0) * 6.0;
  const int sector = static_cast<int>(hue);
  const float f = static_cast<float>(hue - sector);
  const float lo = 0.25f, hi = 1.0f;
  const float up = lo + (hi - lo) * f, down = hi - (hi - lo) * f;
  switch (sector) {
    case 0: return {hi, up, lo};
    case 1: return {down, hi, lo};
    case 2: return {lo, hi, up};
    case 3: return {lo, down, hi};
    case 4: return {up, lo, hi};
    default: return {hi, lo, down};
  }
}

std::array<float, 3> texelColour(const TexelGrid& grid, int t, MaskKind kind,
                                 const std::vector<bool>& multiChart) {
  const TexelClass c = grid.texelClass[static_cast<size_t>(t)];
  if (c == TexelClass::Inactive) return {0, 0, 0};
  switch (kind) {
    case MaskKind::Active: return {1, 1, 1};
    case MaskKind::Boundary: return c == TexelClass::Boundary ? std::array<float, 3>{1, 1, 1}
                                                              : std::array<float, 3>{0, 0, 0};
    case MaskKind::Interior: return c == TexelClass::Interior ? std::array<float, 3>{1, 1, 1}
                                                              : std::array<float, 3>{0, 0, 0};
    case MaskKind::Chart: return chartColour(grid.chartOfTexel(static_cast<size_t>(t)));
    case MaskKind::Coverage:
      return multiChart[static_cast<size_t>(t)] ? std::array<float, 3>{1, 0, 0}
                                                : std::array<float, 3>{1, 1, 1};
  }
  return {0, 0, 0};
}

}  // namespace

MaskKind parseMaskKind(const std::string& text) {
  if (text == "active") return MaskKind::Active;
  if (text == "boundary") return MaskKind::Boundary;
  if (text == "interior") return MaskKind::Interior;
  if (text == "chart") return MaskKind::Chart;
  if (text == "coverage") return MaskKind::Coverage;
  throw InvalidInputError("unknown mask kind '" + text +
                          "'; use active, boundary, interior, chart or coverage");
}

Image texelMask(const TexelGrid& grid, MaskKind kind) {
  const bool colour = kind == MaskKind::Chart || kind == MaskKind::Coverage;
  Image image(grid.imageWidth, grid.imageHeight, colour ? 3 : 1, PixelFormat::UInt8);
  std::vector<bool> multiChart(grid.texelClass.size(), false);
  for (int32_t t : grid.multiChartTexels) multiChart[static_cast<size_t>(t)] = true;
  for (int y = 0; y < grid.ny; ++y) {
    for (int x = 0; x < grid.nx; ++x) {
      if (!grid.inImage(x, y)) continue;
      const auto rgb = texelColour(grid, grid.texelIndex(x, y), kind, multiChart);
      for (int c = 0; c < image.channels; ++c)
        image.at(x + grid.x0, y + grid.y0, c) = rgb[static_cast<size_t>(c)];
    }
  }
  return image;
}

}  // namespace texgrad
