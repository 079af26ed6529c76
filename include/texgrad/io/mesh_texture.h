// A mesh's own textures: reading the image in one of its material slots, and writing a processed
// image back as an image file or into a copy of the glTF asset the mesh came from.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "texgrad/io/image.h"
#include "texgrad/io/texture_pages.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// The image of the mesh's `slot` texture ("baseColor", "normal", ...), read from the file the
/// mesh names or decoded from the bytes embedded in its asset; nullopt if it names no such
/// texture. Throws IoError naming the mesh file and the reference if the image (or the .mtl that
/// would name it) is missing, InvalidInputError if it cannot be decoded, and UnsupportedError if
/// the faces use several different images in the slot (one texture page only).
std::optional<Image> readMeshTexture(const TexturedMesh& mesh,
                                     const std::string& slot = "baseColor");

/// True if `path` names a glTF asset (extension .gltf or .glb, in any case).
bool isGltfPath(const std::filesystem::path& path);

/// What writeMeshTexture wrote.
struct WrittenTexture {
  PixelFormat stored = PixelFormat::UInt8;  ///< the pixel format stored
  std::vector<std::string> warnings;        ///< one line per source image a glTF copy left out
};

/// Writes a processed texture of `mesh` to `out`: an image file (writeImage), or, when `out` is
/// a glTF path, a copy of the mesh's source asset whose `slot` image (the one its faces use, by
/// writeGltfWithTextures; the asset's first if they use none, by writeGltfWithTexture) is
/// `image`: self-contained; a missing source image is left out with a warning. Throws
/// UnsupportedError for a glTF output when the faces use several images in the slot.
/// `format` defaults to image.format. Throws InvalidInputError if a glTF output is asked for a
/// mesh that was not read from glTF.
WrittenTexture writeMeshTexture(const std::filesystem::path& out, const TexturedMesh& mesh,
                                const Image& image, const std::string& slot = "baseColor",
                                std::optional<PixelFormat> format = std::nullopt);

/// writeMeshTexture for a texture over several pages into a glTF copy `out` of the mesh's source
/// asset: `image` is the layout image of `layout` (one page per image of the mesh's layout.slot
/// materials, findTexturePages), and each page's picture (pageImage, one page in memory at a
/// time) replaces the image it came from (TexturePage::texture), by writeGltfWithTextures; other
/// images are kept. Throws UnsupportedError for UDIM pages (glTF has no UDIM tiles),
/// InvalidInputError if the mesh was not read from glTF; otherwise as writeGltfWithTextures.
WrittenTexture writeGltfTexturePages(const std::filesystem::path& out, const TexturedMesh& mesh,
                                     const PageLayout& layout, const Image& image,
                                     std::optional<PixelFormat> format = std::nullopt);

/// Checks before any work that writeMeshTexture can write `out` for a mesh read from
/// `meshSource` (empty for a procedural mesh): checkImageOutput for an image; for a glTF output,
/// a glTF source, a `requested` depth its PNG holds (8 or 16 bits) and a writable folder.
void checkMeshTextureOutput(const std::filesystem::path& out,
                            const std::filesystem::path& meshSource,
                            std::optional<PixelFormat> requested = std::nullopt);

}  // namespace texgrad
