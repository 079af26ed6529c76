// A mesh's texture over its pages (texture_pages.h) read, placed and written in one call each:
// the choice between one image and several pages (UDIM tiles, one image per material) that every
// front end (CLI, Python) makes the same way.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "texgrad/io/image.h"
#include "texgrad/io/texture_pages.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// The pages of a mesh's texture, arranged, and the mesh placed on them.
struct MeshPages {
  PageLayout layout;                   ///< the pages, arranged
  std::optional<TexturedMesh> placed;  ///< the mesh in the layout's UV space (placeOnPages);
                                       ///< empty for a single() layout: the mesh's own UVs
};

/// A texture read over its pages: the layout image besides the pages and the placed mesh.
struct MeshTexturePages : MeshPages {
  Image image;  ///< the layout image
};

/// True if the texture of `layout` is read as one image file, today's single image: a single()
/// layout that is not a UDIM tile (whose file is named by its tile number).
bool isOneImage(const PageLayout& layout);

/// Reads the `slot` texture of `mesh`, or `texture` (a file the user names, which may hold a UDIM
/// token; empty: the mesh's own), as one layout image: one image (isOneImage) is read by readImage
/// or readMeshTexture, or made by `noTexture` when the mesh names none; several pages by
/// readPageSizes and readTexturePages (IoError naming a missing page).
MeshTexturePages readMeshTexturePages(const TexturedMesh& mesh, const std::string& slot,
                                      const std::filesystem::path& texture,
                                      const std::function<Image()>& noTexture);

/// The pages of the `slot` texture of `mesh` (or of `texture`), each `size` (width, height: a
/// texture the caller makes) or, when nullopt, the size of its image (headers only), arranged,
/// and the mesh placed on them.
MeshPages placeMeshOnPages(const TexturedMesh& mesh, const std::string& slot,
                           const std::filesystem::path& texture,
                           std::optional<std::pair<int, int>> size);

/// Writes the layout image `image` of `layout` to the files readPagedImage reads back from `out`
/// (pageOutputPath: `out` itself for a single() layout without a UDIM token), one page in memory
/// at a time, in `format` (default image.format); returns the pixel format stored.
PixelFormat writePagedImage(const std::filesystem::path& out, const PageLayout& layout,
                            const Image& image, std::optional<PixelFormat> format = std::nullopt);

/// What writeMeshTexturePages wrote.
struct WrittenTexturePages {
  PixelFormat stored = PixelFormat::UInt8;   ///< the pixel format stored
  std::vector<std::filesystem::path> files;  ///< the glTF copy, or one image per page in order
  std::vector<std::string> warnings;         ///< one line per source image a glTF copy left out
};

/// Writes the layout image `image` of `layout` for `mesh` to `out`: a glTF `out` is checked
/// (checkMeshTextureOutput) and written as a copy of the mesh's asset (writeMeshTexture for a
/// single() layout, else writeGltfTexturePages); otherwise every page's file (pageOutputPath) is
/// checked (checkImageOutput) before the first is written, one page in memory at a time.
/// `format` defaults to image.format.
WrittenTexturePages writeMeshTexturePages(const std::filesystem::path& out,
                                          const TexturedMesh& mesh, const PageLayout& layout,
                                          const Image& image,
                                          std::optional<PixelFormat> format = std::nullopt);

}  // namespace texgrad
