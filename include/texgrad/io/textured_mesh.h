// The in-memory textured triangle mesh every reader produces and every later stage consumes.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace texgrad {

/// Index triple of a triangle (into positions or into uvs).
using Triangle = std::array<int32_t, 3>;

/// How a texture is sampled outside [0, 1] along one axis (glTF sampler wrapS / wrapT).
enum class TextureWrap : uint8_t {
  Repeat,          ///< the image repeats (glTF's default; OBJ renderers' default)
  MirroredRepeat,  ///< the image repeats, every other copy mirrored
  ClampToEdge,     ///< the edge texels extend (OBJ `-clamp on`)
};

/// A texture referenced by the mesh file: a path on disk or bytes embedded in the asset.
struct TextureRef {
  std::string slot;                      ///< "baseColor", "normal", "emissive", ...
  std::filesystem::path path;            ///< resolved absolute path, empty if embedded
  std::vector<unsigned char> embedded;   ///< encoded image bytes (glTF bufferView / data URI)
  std::string mimeType;                  ///< e.g. "image/png" for embedded images
  std::string origin;  ///< where the file names it, for messages: "material 'red' (map_Kd 'r.png')"
  size_t faces = 0;    ///< faces (triangles) whose material uses this image in this slot
  std::vector<int32_t> materials;  ///< materials (TexturedMesh::materials) using it in this slot
  TextureWrap wrapU = TextureWrap::Repeat;  ///< sampling along u outside [0, 1]
  TextureWrap wrapV = TextureWrap::Repeat;  ///< sampling along v outside [0, 1]
};

/// Triangle mesh with per-corner texture coordinates (OBJ-style separate index spaces).
///
/// positions are welded 3-D vertices (seams are recovered from them); uvs are texture coordinates
/// with v upward (OBJ's convention; the glTF reader flips v: docs/architecture.md, Conventions).
/// triangles[f] and uvTriangles[f] index the corners of face f in the same order.
struct TexturedMesh {
  std::vector<Eigen::Vector3d> positions;  ///< 3-D vertex positions (welded)
  std::vector<Eigen::Vector2d> uvs;        ///< texture coordinates, unit square = atlas
  std::vector<Triangle> triangles;         ///< per face: indices into positions
  std::vector<Triangle> uvTriangles;       ///< per face: indices into uvs
  std::vector<TextureRef> textures;        ///< textures the file references (distinct per slot)
  std::vector<std::string> materials;      ///< material names, in the file's order
  std::vector<int32_t> faceMaterial;  ///< per face: index into materials, -1 if none; may be empty
  std::vector<std::string> missingFiles;   ///< files the mesh names but that are absent (a .mtl)
  std::filesystem::path sourcePath;        ///< file it was read from (empty if procedural)

  /// Number of faces.
  size_t faceCount() const { return triangles.size(); }
  /// First texture reference for a slot ("baseColor", "normal", ...), if the file names one;
  /// faces may use several (textures holds each distinct one), see readMeshTexture.
  const TextureRef* texture(std::string_view slot) const {
    for (const auto& t : textures)
      if (t.slot == slot) return &t;
    return nullptr;
  }
};

}  // namespace texgrad
