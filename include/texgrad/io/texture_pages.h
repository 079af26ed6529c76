// Textures spread over several images (UDIM tiles, one image per material): the pages are laid
// side by side in one texel lattice, the "layout", so that every later stage sees one atlas
// (docs/architecture.md, Texture pages). One page is today's single image.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "texgrad/io/image.h"
#include "texgrad/io/textured_mesh.h"
#include "texgrad/io/uv_tiles.h"

namespace texgrad {

/// Page column offsets are multiples of this many texels, so that the coarse lattices of
/// multigrid (halving up to MultigridOptions::kMaxLevels times) line up with every page's.
inline constexpr int kPageAlignment = 64;
/// Empty texel columns at least between two pages: each page's texels just past its border
/// (bilinear support, gutters) stay apart from the next page's.
inline constexpr int kPageGap = 8;
/// The first and the last UDIM tile number (tiles u in [0, 10), v in [0, 10)).
inline constexpr int kFirstUdim = 1001;
inline constexpr int kLastUdim = 1100;

/// One image of a texture spread over several: where it comes from and where it sits.
struct TexturePage {
  std::string name;               ///< UDIM tile number ("1001") or material / image name
  std::filesystem::path path;     ///< image file; empty if embedded or if no image names it
  int texture = -1;               ///< index into TexturedMesh::textures it comes from, -1 if none
  int tileU = 0, tileV = 0;       ///< UDIM tile (k, l) of its faces: local UV = UV - (k, l)
  int width = 0, height = 0;      ///< image size in texels (0 until known)
  int offset = 0;                 ///< first texel column of the page in the layout
  size_t faces = 0;               ///< faces lying on the page
  int32_t firstFace = -1;         ///< the first of them, for messages
  double uMin = 0.0, uMax = 1.0;  ///< range of its faces' local u (wider than [0, 1] if they
                                  ///< reach past the image's sides)
};

/// Several pages placed left to right in one texel lattice, and the page of every face.
struct PageLayout {
  std::vector<TexturePage> pages;
  std::vector<int32_t> facePage;  ///< per face: index into pages
  int width = 0, height = 0;      ///< layout size in texels (arrangePages)
  bool udim = false;              ///< pages are UDIM tiles (named by tile number)
  std::string slot;               ///< texture slot the pages come from ("baseColor", ...)

  /// True if the layout is today's single image: one page, the mesh's UVs unchanged.
  bool single() const {
    return pages.size() == 1 && pages.front().tileU == 0 && pages.front().tileV == 0;
  }
};

/// True if `path` holds a UDIM token (`<UDIM>` or `%04d`) standing for the tile number.
bool hasUdimToken(const std::filesystem::path& path);

/// `path` with its UDIM token replaced by `tile`.
std::filesystem::path udimTilePath(const std::filesystem::path& path, int tile);

/// True if the `slot` texture of `mesh`, or `texture` (a file the user names; empty: the mesh's
/// own), is a set of UDIM tiles: a path with a UDIM token (findTexturePages' first two cases).
bool isUdimTexture(const TexturedMesh& mesh, const std::string& slot = "baseColor",
                   const std::filesystem::path& texture = {});

/// The mesh as the pages of its `slot` texture (or of `texture`) read it, with each face's
/// parent face: for UDIM tiles each tile is a page, so faces are cut at the tile borders (a chart
/// straddling two tiles becomes two charts joined by a seam) and stay in their tiles, and `wrap`
/// is not used (a UV outside one tile is in another); any other texture wraps by `wrap`
/// (wrapTextureCoordinates), each of its pages read like a single image.
WrappedMesh meshForPages(TexturedMesh mesh, UvWrap wrap, const std::string& slot = "baseColor",
                         const std::filesystem::path& texture = {});

/// The pages of `mesh`'s `slot` texture, sizes not yet known. `texture` (a file the user names;
/// empty: the mesh's own) with a UDIM token, or a mesh texture whose path has one, gives one page
/// per UDIM tile the faces use: a face's tile is the floor (k, l) of its UV centroid, tile number
/// 1001 + k + 10 l. Otherwise each distinct image of the slot's materials is a page and a face
/// lies on the page of its material (TexturedMesh::faceMaterial); one image or none: one page
/// with every face. Throws InvalidInputError naming the face for a face straddling tiles (run the
/// mesh through meshForPages first: it cuts such faces), a tile outside 1001..1100, or a face
/// whose material has no image in a multi-page slot.
PageLayout findTexturePages(const TexturedMesh& mesh, const std::string& slot = "baseColor",
                            const std::filesystem::path& texture = {});

/// Texel columns page `page`'s faces reach past its left and right sides: their UVs' overhang
/// (uMin < 0, uMax > 1) plus the bilinear support of a texel.
std::pair<int, int> pageReach(const TexturePage& page);

/// Sets every page's offset (multiples of kPageAlignment, left to right in page order, at least
/// kPageGap empty columns apart and more where faces reach past a page's side: pageReach) and the
/// layout size: the sum of the placed widths by the largest height. Throws InvalidInputError if
/// a page has no size.
void arrangePages(PageLayout& layout);

/// The first layout column that page `page` + 1 owns (texels left of it and right of the page
/// before belong to the page before): the middle of the columns the two pages' reaches leave.
int pageBoundary(const PageLayout& layout, size_t page);

/// Throws IoError, naming the file, the page and the faces that need it, if page `page`'s image
/// file is missing (embedded pages never are).
void requirePageImage(const PageLayout& layout, const TexturedMesh& mesh, size_t page);

/// The size of page `page`'s image: its file's header, or the embedded image decoded. Throws
/// as requirePageImage does, or InvalidInputError if the image cannot be decoded.
std::pair<int, int> readPageSize(const PageLayout& layout, const TexturedMesh& mesh, size_t page);

/// Reads each page image's size (its header, or the embedded bytes) and arranges the pages.
/// Throws IoError naming the missing file and the faces that need it.
void readPageSizes(PageLayout& layout, const TexturedMesh& mesh);

/// A copy of `mesh` whose UVs are in the layout's UV space: a face on page p with local UV
/// (u, v) gets ((u w_p + x_p) / W, v h_p / H). A UV shared by faces of different pages is
/// duplicated. For a single() layout the copy is `mesh` itself.
TexturedMesh placeOnPages(const TexturedMesh& mesh, const PageLayout& layout);

/// The layout image of `pages` (one image per page, in page order, sizes as the layout's): a
/// texel outside every page takes the clamp-to-edge value of the page owning its column
/// (pageBoundary), which is what that page alone reads past its border.
Image composePages(const PageLayout& layout, const std::vector<Image>& pages);

/// Reads every page image of `mesh` into the layout image, one page at a time (peak memory: the
/// layout and one page); the layout must be arranged. Throws IoError naming a missing file and
/// the faces that need it, InvalidInputError if pages have different channel counts.
Image readTexturePages(const PageLayout& layout, const TexturedMesh& mesh);

/// What the layout texels outside every page hold when paged images are read.
enum class PageGapFill {
  ClampToEdge,  ///< the clamp-to-edge value of the page owning the column (colours, weights)
  Zero,         ///< zero (labels: a gap texel belongs to no source)
};

/// Sets every page's size from the header of its image named after `name` by pageOutputPath's
/// rule (a `<UDIM>` token replaced by the tile, else the page name before the extension; a
/// single() layout: `name` itself) and arranges the layout. Throws IoError naming a missing file.
void readPagedImageSizes(PageLayout& layout, const std::filesystem::path& name);

/// Reads the images named after `name` (pageOutputPath's rule: what writing a layout image to
/// `name` wrote) into one layout image, one page at a time; the layout must be arranged. Throws
/// IoError in one line naming a missing page file, InvalidInputError for a page of another size.
Image readPagedImage(const PageLayout& layout, const std::filesystem::path& name,
                     PageGapFill gap = PageGapFill::ClampToEdge);

/// Page `page` cut out of the layout image `image`.
Image pageImage(const PageLayout& layout, const Image& image, size_t page);

/// Every page cut out of the layout image (pageImage for each).
std::vector<Image> splitPages(const PageLayout& layout, const Image& image);

/// The file page `page` of an output named `out` goes to: a UDIM token in `out` is replaced by
/// the tile; otherwise the page name goes before the extension (out.png -> out.1001.png,
/// out.wood.png). A single() layout writes `out` itself.
std::filesystem::path pageOutputPath(const std::filesystem::path& out, const PageLayout& layout,
                                     size_t page);

}  // namespace texgrad
