// Moving unit UV tiles into the image as a wrapping sampler reads them (wrapIntoUnitSquare,
// wrapTextureCoordinates), and choosing the wrap of a mesh's texture.
#include "texgrad/io/uv_tiles.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <unordered_map>

#include "uv_tile_keys.h"

namespace texgrad {
namespace {

using uv_tiles::lineAt;
using uv_tiles::NewUvKey;
using uv_tiles::NewUvKeyHash;

/// x moved out of tile `k` into [0, 1] as `wrap` reads it.
double wrapCoordinate(double x, int32_t k, TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::Repeat:
      return x - k;
    case TextureWrap::MirroredRepeat:
      return (k & 1) != 0 ? (k + 1) - x : x - k;
    case TextureWrap::ClampToEdge:
      return x;
  }
  return x;
}

}  // namespace

void wrapIntoUnitSquare(TexturedMesh& mesh, std::span<const UvTile> tiles, TextureWrap u,
                        TextureWrap v) {
  if (tiles.size() != mesh.faceCount())
    throw InvalidInputError("wrapIntoUnitSquare: " + std::to_string(tiles.size()) + " tiles for " +
                            std::to_string(mesh.faceCount()) + " faces");
  // The move each face gets (an axis that does not wrap does not move), and per UV index the
  // move of the first face using it; later faces with another move get their own copy.
  const auto moveOf = [&](UvTile t) {
    return UvTile{u == TextureWrap::ClampToEdge ? 0 : t.k, v == TextureWrap::ClampToEdge ? 0 : t.l};
  };
  const bool anyMove =
      std::any_of(tiles.begin(), tiles.end(), [&](UvTile t) { return moveOf(t) != UvTile{}; });
  if (!anyMove) return;
  std::vector<UvTile> moveOfUv(mesh.uvs.size());
  std::vector<uint8_t> claimed(mesh.uvs.size(), 0);
  std::unordered_map<NewUvKey, int32_t, NewUvKeyHash> copies;
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const UvTile move = moveOf(tiles[f]);
    for (int32_t& index : mesh.uvTriangles[f]) {
      const auto i = static_cast<size_t>(index);
      if (!claimed[i]) {
        claimed[i] = 1;
        moveOfUv[i] = move;
      } else if (moveOfUv[i] != move) {
        const auto [it, added] =
            copies.try_emplace(NewUvKey{index, 0, move}, static_cast<int32_t>(mesh.uvs.size()));
        if (added) {
          const Eigen::Vector2d uv = mesh.uvs[i];
          mesh.uvs.push_back(uv);
          moveOfUv.push_back(move);
          claimed.push_back(1);
        }
        index = it->second;
      }
    }
  }
  for (size_t i = 0; i < mesh.uvs.size(); ++i) {
    if (!claimed[i]) continue;
    mesh.uvs[i].x() = wrapCoordinate(mesh.uvs[i].x(), moveOfUv[i].k, u);
    mesh.uvs[i].y() = wrapCoordinate(mesh.uvs[i].y(), moveOfUv[i].l, v);
  }
}

UvWrap samplerWrap(const TexturedMesh& mesh, std::string_view slot) {
  const TextureRef* texture = mesh.texture(slot);
  if (!texture) return {};
  return {texture->wrapU, texture->wrapV};
}

UvWrap parseUvWrap(std::string_view choice, const TexturedMesh& mesh, std::string_view slot) {
  if (choice == "auto") return samplerWrap(mesh, slot);
  if (choice == "repeat") return {TextureWrap::Repeat, TextureWrap::Repeat};
  if (choice == "mirror") return {TextureWrap::MirroredRepeat, TextureWrap::MirroredRepeat};
  if (choice == "clamp") return {TextureWrap::ClampToEdge, TextureWrap::ClampToEdge};
  throw InvalidInputError("texture wrap '" + std::string(choice) +
                          "' is not one of auto, repeat, mirror, clamp");
}

WrappedMesh wrapTextureCoordinates(TexturedMesh mesh, UvWrap wrap) {
  const bool alongU = wrap.u != TextureWrap::ClampToEdge,
             alongV = wrap.v != TextureWrap::ClampToEdge;
  if (!alongU && !alongV) {
    std::vector<int32_t> parents(mesh.faceCount());
    for (size_t f = 0; f < parents.size(); ++f) parents[f] = static_cast<int32_t>(f);
    return {std::move(mesh), std::move(parents)};
  }
  TileCut cut = cutAtTileBorders(std::move(mesh), alongU, alongV);
  wrapIntoUnitSquare(cut.mesh, cut.faceTile, wrap.u, wrap.v);
  return {std::move(cut.mesh), std::move(cut.parentFace)};
}

Eigen::Vector2d wrapUvPoint(const Eigen::Vector2d& uv, UvWrap wrap) {
  Eigen::Vector2d out = uv;
  const std::array<TextureWrap, 2> modes{wrap.u, wrap.v};
  for (int axis = 0; axis < 2; ++axis) {
    if (modes[axis] == TextureWrap::ClampToEdge || !(std::abs(uv[axis]) <= kMaxTileCoordinate))
      continue;
    const std::optional<int32_t> line = lineAt(uv[axis]);
    const int32_t tile = line ? *line : static_cast<int32_t>(std::floor(uv[axis]));
    out[axis] = wrapCoordinate(uv[axis], tile, modes[axis]);
  }
  return out;
}

}  // namespace texgrad
