// Wrapped texture coordinates: cutting faces along integer UV lines so that each lies in one unit
// tile, and moving the tiles into the image [0, 1]^2 as a wrapping sampler reads them (issue 30).
// Runs on the mesh before the atlas is built; docs/architecture.md, Data flow.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "texgrad/core/error.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// A corner closer than this (UV units) to an integer line lies on it: it is not cut off, and the
/// face it belongs to is on whichever side its other corners are. 1e-7 is about one float32 step
/// at 1 (glTF stores UVs as float32, so a corner meant to lie on a tile border is either on it or
/// at least this far off) and less than the texel grid's own snap (1/256 texel) at every texture
/// up to 32K texels across, so a sliver thinner than this would be invisible to the grid anyway.
inline constexpr double kTileBorderTolerance = 1e-7;

/// Texture coordinates of magnitude above this are refused: the fraction inside a tile would keep
/// fewer than 10 exact decimals, and a face reaching that far would be cut into millions of pieces.
inline constexpr double kMaxTileCoordinate = 1e6;

/// A unit UV tile [k, k + 1] x [l, l + 1].
struct UvTile {
  int32_t k = 0;  ///< tile column (u)
  int32_t l = 0;  ///< tile row (v)
  bool operator==(const UvTile&) const = default;
};

/// A mesh cut along integer UV lines, with each face's tile and the input face it comes from.
struct TileCut {
  TexturedMesh mesh;                ///< every face lies in one unit tile (up to the tolerance)
  std::vector<UvTile> faceTile;     ///< per face of mesh: its tile
  std::vector<int32_t> parentFace;  ///< per face of mesh: the face of the input it is part of
  bool cut = false;                 ///< false when no face crossed a line (mesh is the input)
};

/// Cuts every face that crosses an integer u line (alongU) or v line (alongV) along it, so that
/// each face lies in one unit tile (a face touching a line from one side is not cut; corners
/// within kTileBorderTolerance of a line are on it). The pieces of a face are convex polygons
/// fanned into triangles of the face's orientation; the first keeps the face's index, the others
/// are appended (faceMaterial follows). A point made on an edge has one new 3-D position, keyed
/// by the 3-D edge and its parameter, used by every face on that edge (faces across a seam that
/// no line crosses get the point too, so the surface stays watertight), and one new UV per UV
/// edge and tile: the two sides of a cut are then separate charts joined by a seam once the
/// tiles are moved apart. Faces no line crosses keep their indices; nothing is copied when no
/// face crosses. An axis that is not cut has tile index 0. Throws InvalidInputError naming the
/// face if a corner's |u| or |v| exceeds kMaxTileCoordinate.
TileCut cutAtTileBorders(TexturedMesh mesh, bool alongU = true, bool alongV = true);

/// Moves each face by its whole tile into [0, 1]^2 along each axis: Repeat shifts u by -k;
/// MirroredRepeat shifts even tiles and mirrors odd ones (u -> k + 1 - u); ClampToEdge leaves
/// the axis untouched. A UV index that faces of different tiles share is duplicated, one per
/// tile. `tiles` has one entry per face (cutAtTileBorders).
void wrapIntoUnitSquare(TexturedMesh& mesh, std::span<const UvTile> tiles, TextureWrap u,
                        TextureWrap v);

/// How a texture is sampled along u and along v.
struct UvWrap {
  TextureWrap u = TextureWrap::Repeat;  ///< along u
  TextureWrap v = TextureWrap::Repeat;  ///< along v
};

/// The sampler of the mesh's first texture in `slot`; Repeat on both axes when the slot has none
/// (OBJ renderers and glTF's default sampler repeat).
UvWrap samplerWrap(const TexturedMesh& mesh, std::string_view slot);

/// The wrap a front end's choice names: "auto" (samplerWrap of `slot`), "repeat", "mirror"
/// (MirroredRepeat) or "clamp" (ClampToEdge), the same on both axes but for auto. Throws
/// InvalidInputError on another word.
UvWrap parseUvWrap(std::string_view choice, const TexturedMesh& mesh, std::string_view slot);

/// A mesh whose UVs a wrapping texture reads inside the image, and where its faces come from.
struct WrappedMesh {
  TexturedMesh mesh;                ///< faces cut at tile borders and moved into [0, 1]^2
  std::vector<int32_t> parentFace;  ///< per face of mesh: the input face it is part of
};

/// Cuts the mesh at the tile borders of the axes that wrap and moves every tile into [0, 1]^2
/// (cutAtTileBorders, wrapIntoUnitSquare): a mesh whose charts lie in other tiles is then
/// processed exactly like its copy moved into the image, and the processed image is the texture
/// those UVs read. ClampToEdge on both axes returns the mesh unchanged.
WrappedMesh wrapTextureCoordinates(TexturedMesh mesh, UvWrap wrap);

/// Where a wrapping texture reads the UV point `uv`: moved by its tile like the faces there (a
/// point on a tile border counts in the tile above it).
Eigen::Vector2d wrapUvPoint(const Eigen::Vector2d& uv, UvWrap wrap);

/// Per-face values of the input mesh (a vector field, a material) carried to the faces of a
/// wrapped mesh: out[f] = values[parentFace[f]]. Throws InvalidInputError if a parent is out of
/// range.
template <typename T>
std::vector<T> followParentFaces(const std::vector<T>& values,
                                 std::span<const int32_t> parentFace) {
  std::vector<T> out;
  out.reserve(parentFace.size());
  for (int32_t parent : parentFace) {
    if (parent < 0 || static_cast<size_t>(parent) >= values.size())
      throw InvalidInputError("followParentFaces: parent face " + std::to_string(parent) +
                              " is out of range (" + std::to_string(values.size()) + " values)");
    out.push_back(values[static_cast<size_t>(parent)]);
  }
  return out;
}

}  // namespace texgrad
