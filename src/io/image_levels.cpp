// 8-bit levels of an image and back, exact both ways: a level's value is the one the image
// codecs decode it to (codec::levelValue).
#include "texgrad/io/image_levels.h"

#include <array>
#include <cmath>
#include <limits>

#include "image_codecs.h"

namespace texgrad {

const std::array<float, kByteLevels>& byteLevelValues() {
  static const std::array<float, kByteLevels> values = [] {
    std::array<float, kByteLevels> v{};
    for (int level = 0; level < kByteLevels; ++level)
      v[static_cast<size_t>(level)] = codec::levelValue(static_cast<uint8_t>(level));
    return v;
  }();
  return values;
}

std::optional<std::vector<uint8_t>> exactByteLevels(const Image& image) {
  if (image.format != PixelFormat::UInt8) return std::nullopt;
  const std::array<float, kByteLevels>& values = byteLevelValues();
  constexpr float top = kByteLevels - 1;
  std::vector<uint8_t> levels(image.pixels.size());
  for (size_t k = 0; k < levels.size(); ++k) {
    const float v = image.pixels[k];
    if (!(v >= 0.0f && v <= 1.0f)) return std::nullopt;  // NaN fails too
    const auto level = static_cast<uint8_t>(std::lround(v * top));
    if (values[level] != v) return std::nullopt;
    levels[k] = level;
  }
  return levels;
}

std::vector<float> valuesOfByteLevels(std::span<const uint8_t> levels) {
  const std::array<float, kByteLevels>& values = byteLevelValues();
  std::vector<float> out(levels.size());
  for (size_t k = 0; k < levels.size(); ++k) out[k] = values[levels[k]];
  return out;
}

}  // namespace texgrad
