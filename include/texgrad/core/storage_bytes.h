// Core: bytes a container holds, for the storage reports of the operators and the solver
// (docs/memory.md), so memory per texel can be tested, not only benchmarked.
#pragma once

#include <cstdint>
#include <vector>

namespace texgrad {

/// Bytes allocated by `v` (its capacity, not its size).
template <typename T>
int64_t capacityBytes(const std::vector<T>& v) {
  return static_cast<int64_t>(v.capacity() * sizeof(T));
}

/// Sum of capacityBytes over `vs`.
template <typename T, typename... Rest>
int64_t capacityBytes(const std::vector<T>& v, const Rest&... rest) {
  return capacityBytes(v) + capacityBytes(rest...);
}

}  // namespace texgrad
