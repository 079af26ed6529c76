// Private to io's UV tiles (uv_tile_cut.cpp, uv_tiles.cpp): which integer line a coordinate lies
// on, and the key of a UV made for one tile.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "texgrad/io/uv_tiles.h"

namespace texgrad::uv_tiles {

/// The integer line x lies on (within kTileBorderTolerance), if any.
inline std::optional<int32_t> lineAt(double x) {
  const double r = std::round(x);
  if (std::abs(x - r) <= kTileBorderTolerance) return static_cast<int32_t>(r);
  return std::nullopt;
}

/// Key of a UV made for one tile: the point (a 3-D position for a cut point, the original UV
/// index for a copy), what it lies on (a UV edge, a face interior; 0 for a copy) and the tile.
struct NewUvKey {
  int32_t position;
  uint64_t owner;
  UvTile tile;
  bool operator==(const NewUvKey&) const = default;
};
/// Hash of a NewUvKey.
struct NewUvKeyHash {
  size_t operator()(const NewUvKey& key) const {
    uint64_t h = key.owner * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<uint64_t>(static_cast<uint32_t>(key.position)) + (h << 6) + (h >> 2);
    h ^= (uint64_t{static_cast<uint32_t>(key.tile.k)} << 32 | static_cast<uint32_t>(key.tile.l)) +
         (h << 6) + (h >> 2);
    return static_cast<size_t>(h);
  }
};

}  // namespace texgrad::uv_tiles
