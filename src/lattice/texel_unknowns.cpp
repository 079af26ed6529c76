// TexelUnknowns: the active texels' bitmask and the running count per 64-texel word.
#include "texgrad/lattice/texel_unknowns.h"

#include <limits>
#include <string>

#include "texgrad/core/error.h"
#include "texgrad/core/storage_bytes.h"

namespace texgrad {

TexelUnknowns::TexelUnknowns(size_t texels, std::span<const int32_t> active)
    : size_(texels), bits_((texels + 63) / 64, 0), before_(bits_.size(), 0) {
  if (active.size() > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
    throw InvalidInputError("TexelUnknowns: " + std::to_string(active.size()) +
                            " active texels, more than an int32 numbers");
  int64_t previous = -1;
  for (const int32_t t : active) {
    if (t <= previous || static_cast<size_t>(t) >= texels)
      throw InvalidInputError("TexelUnknowns: active texel " + std::to_string(t) +
                              " is not ascending within [0, " + std::to_string(texels) + ")");
    bits_[static_cast<size_t>(t) / 64] |= uint64_t{1} << (static_cast<unsigned>(t) % 64);
    previous = t;
  }
  int32_t count = 0;
  for (size_t w = 0; w < bits_.size(); ++w) {
    before_[w] = count;
    count += bitsSet(bits_[w]);
  }
}

int64_t TexelUnknowns::storageBytes() const { return capacityBytes(bits_, before_); }

}  // namespace texgrad
