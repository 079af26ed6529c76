// 8-bit images held as their levels (one byte per value instead of a float) while nothing reads
// them: a one-shot filter keeps the input texture this way between gathering and writing back.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "texgrad/io/image.h"

namespace texgrad {

/// Number of 8-bit levels; the top one is the value 1.
inline constexpr int kByteLevels = 256;

/// The float each 8-bit level decodes to (readImage's own conversion, which is not always
/// level / 255.0f).
const std::array<float, kByteLevels>& byteLevelValues();

/// The values of `image` as 8-bit levels (same order as Image::pixels) if its format is UInt8
/// and every value is exactly what readImage decodes a level of an 8-bit file to (about
/// level / 255); nullopt otherwise (the float values then hold more than the levels could).
std::optional<std::vector<uint8_t>> exactByteLevels(const Image& image);

/// The decoded value of each of `levels`: the pixels exactByteLevels was given, bit for bit.
std::vector<float> valuesOfByteLevels(std::span<const uint8_t> levels);

}  // namespace texgrad
