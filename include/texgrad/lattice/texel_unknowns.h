// The unknown numbering of a texel lattice: active texels numbered in row-major order, stored as a
// rank over their bitmask instead of an int per texel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace texgrad {

/// Per grid texel, its unknown index, or -1 if it is inactive, where unknowns number the active
/// texels in ascending texel order. Held as one bit per texel and a count of the active texels
/// before every 64: 0.19 bytes per texel instead of 4 (64 MB less at a 4096² texture, all of it
/// live while the operators are assembled; docs/memory.md).
class TexelUnknowns {
 public:
  /// No texels.
  TexelUnknowns() = default;
  /// The numbering of `texels` texels of which `active` (ascending, each < texels) are active;
  /// throws InvalidInputError otherwise.
  TexelUnknowns(size_t texels, std::span<const int32_t> active);

  /// Unknown index of texel t (< size()), -1 if it is inactive.
  int32_t operator[](size_t t) const {
    const uint64_t word = bits_[t / 64];
    const unsigned bit = t % 64;
    if (((word >> bit) & 1U) == 0) return -1;
    // The active texels before t: those before its word, and those below it in the word.
    const uint64_t below = word & ((uint64_t{1} << bit) - 1U);
    return before_[t / 64] + bitsSet(below);
  }
  /// Number of texels.
  size_t size() const { return size_; }
  /// True if there are no texels (never built, or freed by clear()).
  bool empty() const { return size_ == 0; }
  /// Frees the numbering's storage; size() becomes 0.
  void clear() { *this = TexelUnknowns(); }
  /// Bytes of storage held.
  int64_t storageBytes() const;

  /// Same texels with the same active ones.
  bool operator==(const TexelUnknowns&) const = default;

 private:
  /// Number of bits set in `word`, in a dozen inline operations: std::popcount is a call into
  /// libgcc where the build does not assume the popcnt instruction (x86-64 before v2), and this
  /// runs for every texel lookup of the operators' assembly.
  static int32_t bitsSet(uint64_t word) {
    word -= (word >> 1) & 0x5555555555555555U;
    word = (word & 0x3333333333333333U) + ((word >> 2) & 0x3333333333333333U);
    word = (word + (word >> 4)) & 0x0f0f0f0f0f0f0f0fU;
    return static_cast<int32_t>((word * 0x0101010101010101U) >> 56);
  }

  size_t size_ = 0;
  std::vector<uint64_t> bits_;    ///< bit t % 64 of word t / 64: texel t is active
  std::vector<int32_t> before_;  ///< per word: active texels in the words before it
};

}  // namespace texgrad
