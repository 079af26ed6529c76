// The `texgrad` subcommands' side of texture pages (texgrad/io/texture_pages.h): reading a
// texture over its pages, placing the mesh on their layout, and writing one image per page.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "texgrad/io/image.h"
#include "texgrad/io/mesh_texture_pages.h"
#include "texgrad/io/texture_pages.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad::cli {

/// What --out does for a texture over several pages, appended to each --out help.
inline constexpr const char* kPagedOutputHelp =
    ". A texture over several pages (UDIM tiles, or one image per material) gives one image per "
    "page: a <UDIM> or %04d in the name is replaced by the tile number, else the page name goes "
    "before the extension (out.png -> out.1001.png or out.MATERIAL.png); a glTF copy gets each "
    "material's page in place of its image (UDIM tiles: images only)";

/// What the TEXTURE argument accepts, appended to its help.
inline constexpr const char* kPagedInputHelp =
    "; a name with <UDIM> or %04d (tex.<UDIM>.png) reads one image per UDIM tile the UVs use";

/// How `stitch`'s texture-space inputs over several pages are named, appended to their help.
inline constexpr const char* kPagedInputsHelp =
    ". A texture over several pages (UDIM tiles, or one image per material) reads one image per "
    "page, named as --out names them (a <UDIM> replaced by the tile, else the page name before "
    "the extension: comp.1001.png, comp.MATERIAL.png); the same for --segments and --lock";

/// A mesh placed on the pages of its texture, and the layout image when one was read.
struct PagedTexture {
  TexturedMesh mesh;  ///< UVs in the layout's UV space (the mesh itself for one page)
  PageLayout layout;  ///< the pages, arranged
  Image image;        ///< the texture's layout image (empty when only sizes were set)
};

/// loadTexture over pages: the pages of `slot` (or of `explicitPath`, which may hold a UDIM token)
/// read into one layout image, and `mesh` placed on it. One page is read exactly as loadTexture
/// reads it.
PagedTexture loadPagedTexture(TexturedMesh mesh, const std::string& meshSpec,
                              const std::string& explicitPath, const std::string& slot);

/// The mesh's base-colour pages, each `width` x `height` (a texture the command makes: lic,
/// react, geodesic), and `mesh` placed on them; no image is read.
PagedTexture placeOnPagesOfSize(TexturedMesh mesh, int width, int height);

/// The mesh's base-colour pages with the sizes of their images (headers only), and `mesh` placed
/// on them; nullopt if the texture is one page (the caller keeps its own choice of size).
std::optional<PagedTexture> placeOnPagesOfImages(const TexturedMesh& mesh);

/// Refuses, naming `option` and saying what to do `instead`, an option not supported yet when
/// the texture has several pages.
void requireSinglePage(const PageLayout& layout, const std::string& option,
                       const std::string& instead);

/// Checks, before the work, that every page of `out` can be written: checkImageOutput for each
/// page's file; a glTF output of UDIM tiles is refused (one line), of material pages accepted.
void checkPagedOutputArgs(const std::string& out, const PageLayout& layout,
                          const std::string& bitDepth);

/// Writes the layout image `image` of the layout's slot with writeMeshTexturePages (one image,
/// one image per page at its pageOutputPath, or a glTF copy), `bitDepth` as parsePixelFormat
/// (empty: the image's); unless `quiet`, prints its warnings. Returns the pixel format stored.
PixelFormat writePagedTexture(const std::string& out, const TexturedMesh& mesh,
                              const PageLayout& layout, const Image& image,
                              const std::string& bitDepth, bool quiet);

/// printWritten for a paged output: one line naming every page file written.
void printWrittenPages(bool quiet, const std::string& out, const PageLayout& layout,
                       const Image& image, PixelFormat stored, int64_t texels, double seconds);

}  // namespace texgrad::cli
