// Texture pages: finding them (UDIM tiles, one image per material), laying them out in one
// lattice, moving a mesh's UVs onto the layout, and copying images in and out of it.
#include "texgrad/io/texture_pages.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>
#include <string_view>

#include "texgrad/core/error.h"
#include "texgrad/core/path_exists.h"
#include "texgrad/io/image_io.h"

namespace texgrad {
namespace {

constexpr std::array<std::string_view, 2> kUdimTokens{"<UDIM>", "%04d"};
/// UDIM tiles per row (u in [0, 10)) and rows (v in [0, 10)).
constexpr int kUdimColumns = 10;

/// Position of the first UDIM token in `text` and its length; npos if none.
std::pair<size_t, size_t> findToken(const std::string& text) {
  for (std::string_view token : kUdimTokens)
    if (const size_t at = text.find(token); at != std::string::npos) return {at, token.size()};
  return {std::string::npos, 0};
}

/// How messages name the mesh: its file, or "the mesh" for a procedural one.
std::string meshName(const TexturedMesh& mesh) {
  return mesh.sourcePath.empty() ? "the mesh" : mesh.sourcePath.string();
}

/// A tile coordinate as a message shows it ("10", "-1", "nan").
std::string numberText(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

/// "face 12 (of material 'wood')" for messages.
std::string describeFace(const TexturedMesh& mesh, size_t f) {
  std::string text = "face " + std::to_string(f);
  if (f < mesh.faceMaterial.size() && mesh.faceMaterial[f] >= 0)
    text += " (material '" + mesh.materials[static_cast<size_t>(mesh.faceMaterial[f])] + "')";
  return text;
}

/// Who needs page `p`: "28 faces (first: face 12 (material 'wood'))".
std::string describeUsers(const TexturedMesh& mesh, const TexturePage& page) {
  std::string text = std::to_string(page.faces) + (page.faces == 1 ? " face" : " faces");
  if (page.firstFace >= 0)
    text += " (first: " + describeFace(mesh, static_cast<size_t>(page.firstFace)) + ")";
  return text;
}

/// How a message names a page: "UDIM tile 1002" or "page 'wood'".
std::string describePage(const TexturePage& page, bool udim) {
  return (udim ? "UDIM tile " : "page '") + page.name + (udim ? "" : "'");
}

/// Counts face `f` of `mesh` on page `p`, and its local u in the page's u range.
void addFace(PageLayout& layout, const TexturedMesh& mesh, size_t p, size_t f) {
  layout.facePage[f] = static_cast<int32_t>(p);
  TexturePage& page = layout.pages[p];
  if (page.faces++ == 0) page.firstFace = static_cast<int32_t>(f);
  for (int32_t t : mesh.uvTriangles[f]) {
    const double u = mesh.uvs[static_cast<size_t>(t)].x() - page.tileU;
    page.uMin = std::min(page.uMin, u);
    page.uMax = std::max(page.uMax, u);
  }
}

/// The UDIM tile of face `f`: floor of its UV centroid; every corner must lie in that tile.
std::array<int, 2> faceTile(const TexturedMesh& mesh, size_t f) {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (int32_t t : mesh.uvTriangles[f]) centroid += mesh.uvs[static_cast<size_t>(t)] / 3.0;
  const double rows = (kLastUdim - kFirstUdim + 1) / kUdimColumns;
  const double k = std::floor(centroid.x()), l = std::floor(centroid.y());
  if (!(k >= 0.0 && k < kUdimColumns && l >= 0.0 && l < rows))  // also NaN, before any cast
    throw InvalidInputError(meshName(mesh) + ": " + describeFace(mesh, f) + " lies in UV tile (" +
                            numberText(k) + ", " + numberText(l) +
                            "), outside the UDIM tiles 1001..1100 (u and v in [0, 10)); move its "
                            "chart into a tile");
  const std::array<int, 2> tile{static_cast<int>(k), static_cast<int>(l)};
  for (int32_t t : mesh.uvTriangles[f]) {
    const Eigen::Vector2d& uv = mesh.uvs[static_cast<size_t>(t)];
    for (int axis = 0; axis < 2; ++axis)
      if (uv[axis] < tile[static_cast<size_t>(axis)] ||
          uv[axis] > tile[static_cast<size_t>(axis)] + 1)
        throw InvalidInputError(
            meshName(mesh) + ": " + describeFace(mesh, f) + " straddles UDIM tiles (UV " +
            std::to_string(uv.x()) + ", " + std::to_string(uv.y()) +
            "); cut the faces at the tile borders first (meshForPages or cutAtTileBorders does)");
  }
  return tile;
}

/// One page per UDIM tile the faces use, in tile order; `pattern` holds the token.
PageLayout udimPages(const TexturedMesh& mesh, const std::filesystem::path& pattern, int texture) {
  PageLayout layout;
  layout.udim = true;
  layout.facePage.resize(mesh.faceCount());
  std::map<int, size_t> pageOfTile;
  std::vector<int> faceTiles(mesh.faceCount());
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const std::array<int, 2> tile = faceTile(mesh, f);
    faceTiles[f] = kFirstUdim + tile[0] + kUdimColumns * tile[1];
    pageOfTile[faceTiles[f]] = 0;
  }
  for (auto& [tile, p] : pageOfTile) {
    p = layout.pages.size();
    TexturePage page;
    page.name = std::to_string(tile);
    page.path = udimTilePath(pattern, tile);
    page.texture = texture;
    page.tileU = (tile - kFirstUdim) % kUdimColumns;
    page.tileV = (tile - kFirstUdim) / kUdimColumns;
    layout.pages.push_back(std::move(page));
  }
  for (size_t f = 0; f < mesh.faceCount(); ++f) addFace(layout, mesh, pageOfTile[faceTiles[f]], f);
  return layout;
}

/// A page name usable in a file name: path separators and spaces become '_'.
std::string fileSafe(std::string name) {
  for (char& c : name)
    if (c == '/' || c == '\\' || c == ' ' || c == ':') c = '_';
  return name;
}

/// One page per distinct image of the slot (mesh.textures), faces by material.
PageLayout materialPages(const TexturedMesh& mesh, const std::vector<int>& refs,
                         const std::string& slot) {
  PageLayout layout;
  layout.slot = slot;
  layout.facePage.assign(mesh.faceCount(), -1);
  std::vector<int32_t> pageOfMaterial(mesh.materials.size(), -1);
  for (int t : refs) {
    const TextureRef& ref = mesh.textures[static_cast<size_t>(t)];
    TexturePage page;
    for (int32_t m : ref.materials)
      if (m < 0 || static_cast<size_t>(m) >= mesh.materials.size())
        throw InvalidInputError(meshName(mesh) + ": texture " + ref.origin + " names material " +
                                std::to_string(m) + " but there are " +
                                std::to_string(mesh.materials.size()) + " materials");
    // Named after its material when it has one, else after its image file.
    page.name = fileSafe(ref.materials.size() == 1
                             ? mesh.materials[static_cast<size_t>(ref.materials.front())]
                             : ref.path.stem().string());
    if (page.name.empty()) page.name = std::to_string(layout.pages.size());
    for (const TexturePage& other : layout.pages)
      if (other.name == page.name) page.name += "-" + std::to_string(layout.pages.size());
    page.path = ref.path;
    page.texture = t;
    for (int32_t m : ref.materials)
      pageOfMaterial[static_cast<size_t>(m)] = static_cast<int32_t>(layout.pages.size());
    layout.pages.push_back(std::move(page));
  }
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const int32_t m = f < mesh.faceMaterial.size() ? mesh.faceMaterial[f] : -1;
    const int32_t p = m >= 0 ? pageOfMaterial[static_cast<size_t>(m)] : -1;
    if (p < 0)
      throw InvalidInputError(meshName(mesh) + ": " + describeFace(mesh, f) +
                              (m < 0 ? " has no material" : "'s material has no image") +
                              ", but the mesh's other faces use " +
                              std::to_string(layout.pages.size()) + " " + layout.slot +
                              " textures; give every face a material with a texture");
    addFace(layout, mesh, static_cast<size_t>(p), f);
  }
  return layout;
}

}  // namespace

bool hasUdimToken(const std::filesystem::path& path) {
  return findToken(path.string()).first != std::string::npos;
}

std::filesystem::path udimTilePath(const std::filesystem::path& path, int tile) {
  std::string text = path.string();
  const auto [at, length] = findToken(text);
  if (at == std::string::npos) return path;
  return text.replace(at, length, std::to_string(tile));
}

bool isUdimTexture(const TexturedMesh& mesh, const std::string& slot,
                   const std::filesystem::path& texture) {
  if (!texture.empty()) return hasUdimToken(texture);
  const TextureRef* only = nullptr;
  for (const TextureRef& t : mesh.textures) {
    if (t.slot != slot) continue;
    if (only) return false;  // several images: material pages
    only = &t;
  }
  return only && hasUdimToken(only->path);
}

WrappedMesh meshForPages(TexturedMesh mesh, UvWrap wrap, const std::string& slot,
                         const std::filesystem::path& texture) {
  if (!isUdimTexture(mesh, slot, texture)) return wrapTextureCoordinates(std::move(mesh), wrap);
  TileCut cut = cutAtTileBorders(std::move(mesh));
  return {std::move(cut.mesh), std::move(cut.parentFace)};
}

PageLayout findTexturePages(const TexturedMesh& mesh, const std::string& slot,
                            const std::filesystem::path& texture) {
  std::vector<int> refs;
  for (size_t t = 0; t < mesh.textures.size(); ++t)
    if (mesh.textures[t].slot == slot) refs.push_back(static_cast<int>(t));
  PageLayout layout;
  if (!texture.empty() && hasUdimToken(texture)) {
    layout = udimPages(mesh, texture, -1);
  } else if (texture.empty() && refs.size() == 1 &&
             hasUdimToken(mesh.textures[static_cast<size_t>(refs.front())].path)) {
    layout = udimPages(mesh, mesh.textures[static_cast<size_t>(refs.front())].path, refs.front());
  } else if (texture.empty() && refs.size() > 1) {
    layout = materialPages(mesh, refs, slot);
  } else {
    TexturePage page;
    page.path = texture.empty() && !refs.empty()
                    ? mesh.textures[static_cast<size_t>(refs.front())].path
                    : texture;
    page.texture = texture.empty() && !refs.empty() ? refs.front() : -1;
    page.name = page.path.empty() ? std::string("0") : fileSafe(page.path.stem().string());
    layout.pages.push_back(std::move(page));
    layout.facePage.resize(mesh.faceCount());
    for (size_t f = 0; f < mesh.faceCount(); ++f) addFace(layout, mesh, 0, f);
  }
  layout.slot = slot;
  return layout;
}

std::pair<int, int> pageReach(const TexturePage& page) {
  // A texel's bilinear support spans one texel each side; one more keeps the reaches of two
  // pages from touching.
  constexpr int kSupportTexels = 2;
  const auto texels = [&](double overhang) {
    return static_cast<int>(std::ceil(std::max(0.0, overhang) * page.width)) + kSupportTexels;
  };
  return {texels(-page.uMin), texels(page.uMax - 1.0)};
}

void arrangePages(PageLayout& layout) {
  int column = 0;
  layout.height = 0;
  for (size_t p = 0; p < layout.pages.size(); ++p) {
    TexturePage& page = layout.pages[p];
    if (page.width <= 0 || page.height <= 0)
      throw InvalidInputError("texture page '" + page.name + "' has no size");
    // The next multiple of kPageAlignment at least kPageGap columns, and both reaches, past the
    // previous page.
    const int gap =
        p == 0 ? 0
               : std::max(kPageGap, pageReach(layout.pages[p - 1]).second + pageReach(page).first);
    page.offset =
        p == 0 ? 0 : (column + gap + kPageAlignment - 1) / kPageAlignment * kPageAlignment;
    column = page.offset + page.width;
    layout.height = std::max(layout.height, page.height);
  }
  layout.width = column;
}

int pageBoundary(const PageLayout& layout, size_t p) {
  const TexturePage& left = layout.pages.at(p);
  const TexturePage& right = layout.pages.at(p + 1);
  const int leftReach = left.offset + left.width + pageReach(left).second;
  const int rightReach = right.offset - pageReach(right).first;
  return (leftReach + rightReach + 1) / 2;
}

namespace {}  // namespace

void requirePageImage(const PageLayout& layout, const TexturedMesh& mesh, size_t p) {
  const TexturePage& page = layout.pages.at(p);
  if (page.path.empty() || pathExists(page.path)) return;
  throw IoError(page.path.string() + " was not found: it is " + describePage(page, layout.udim) +
                " of " + meshName(mesh) + "'s " + layout.slot + " texture, needed by " +
                describeUsers(mesh, page) + "; restore the image or fix the reference");
}

namespace {

/// Decodes page `page`'s image (its file, or the bytes embedded in the mesh's asset).
Image readPage(const PageLayout& layout, const TexturedMesh& mesh, size_t p) {
  requirePageImage(layout, mesh, p);
  const TexturePage& page = layout.pages[p];
  if (!page.path.empty()) return readImage(page.path);
  if (page.texture < 0)
    throw InvalidInputError(describePage(page, layout.udim) + " names no image to read");
  return readImageFromMemory(
      mesh.textures[static_cast<size_t>(page.texture)].embedded,
      mesh.sourcePath.string() + " (embedded " + layout.slot + " texture " + page.name + ")");
}

/// Copies `image` (page `p`) into the layout image with clamp-to-edge values (or zeros, `gap`)
/// around it.
void copyIntoLayout(const PageLayout& layout, size_t p, const Image& image, Image& out,
                    PageGapFill gap = PageGapFill::ClampToEdge) {
  const TexturePage& page = layout.pages[p];
  if (image.width != page.width || image.height != page.height)
    throw InvalidInputError(describePage(page, layout.udim) + " is " + std::to_string(image.width) +
                            "x" + std::to_string(image.height) +
                            " but the layout was arranged for " + std::to_string(page.width) + "x" +
                            std::to_string(page.height));
  if (image.channels != out.channels)
    throw InvalidInputError(
        describePage(page, layout.udim) + " has " + std::to_string(image.channels) +
        " channels but " + describePage(layout.pages.front(), layout.udim) + " has " +
        std::to_string(out.channels) + "; give every page the same channels (e.g. all RGB)");
  const int first = p == 0 ? 0 : pageBoundary(layout, p - 1);
  const int last = p + 1 == layout.pages.size() ? layout.width : pageBoundary(layout, p);
  for (int j = 0; j < layout.height; ++j) {
    const int row = std::min(j, page.height - 1);
    for (int x = first; x < last; ++x) {
      const int column = std::clamp(x - page.offset, 0, page.width - 1);
      const bool outside = j != row || column != x - page.offset;
      for (int c = 0; c < out.channels; ++c)
        out.at(x, j, c) = outside && gap == PageGapFill::Zero ? 0.0f : image.at(column, row, c);
    }
  }
}

}  // namespace

std::pair<int, int> readPageSize(const PageLayout& layout, const TexturedMesh& mesh, size_t page) {
  requirePageImage(layout, mesh, page);
  if (!layout.pages[page].path.empty()) return readImageSize(layout.pages[page].path);
  const Image image = readPage(layout, mesh, page);  // embedded: no header-only reader
  return {image.width, image.height};
}

void readPageSizes(PageLayout& layout, const TexturedMesh& mesh) {
  for (size_t p = 0; p < layout.pages.size(); ++p)
    std::tie(layout.pages[p].width, layout.pages[p].height) = readPageSize(layout, mesh, p);
  arrangePages(layout);
}

TexturedMesh placeOnPages(const TexturedMesh& mesh, const PageLayout& layout) {
  TexturedMesh placed = mesh;
  if (layout.single()) return placed;
  // UV index -> its copy on each page (-1: none yet); the first page to use it keeps it.
  std::vector<int32_t> owner(mesh.uvs.size(), -1);
  std::map<std::pair<int32_t, int32_t>, int32_t> copies;
  placed.uvs.clear();
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const auto p = static_cast<size_t>(layout.facePage[f]);
    const TexturePage& page = layout.pages[p];
    for (int32_t& t : placed.uvTriangles[f]) {
      const auto key = std::make_pair(t, static_cast<int32_t>(p));
      if (const auto it = copies.find(key); it != copies.end()) {
        t = it->second;
        continue;
      }
      const Eigen::Vector2d& uv = mesh.uvs[static_cast<size_t>(t)];
      const double u = (uv.x() - page.tileU) * page.width + page.offset;
      const double v = (uv.y() - page.tileV) * page.height;
      placed.uvs.emplace_back(u / layout.width, v / layout.height);
      t = copies[key] = static_cast<int32_t>(placed.uvs.size() - 1);
    }
  }
  return placed;
}

Image composePages(const PageLayout& layout, const std::vector<Image>& pages) {
  if (pages.size() != layout.pages.size() || pages.empty())
    throw InvalidInputError("composePages: " + std::to_string(pages.size()) + " images for " +
                            std::to_string(layout.pages.size()) + " pages");
  Image out(layout.width, layout.height, pages.front().channels, pages.front().format);
  for (size_t p = 0; p < pages.size(); ++p) copyIntoLayout(layout, p, pages[p], out);
  return out;
}

Image readTexturePages(const PageLayout& layout, const TexturedMesh& mesh) {
  Image out;
  for (size_t p = 0; p < layout.pages.size(); ++p) {
    const Image page = readPage(layout, mesh, p);
    if (p == 0) out = Image(layout.width, layout.height, page.channels, page.format);
    copyIntoLayout(layout, p, page, out);
  }
  return out;
}

namespace {

/// Page `p`'s file of the paged image `name`, throwing IoError in one line if it is missing.
std::filesystem::path requirePagedFile(const PageLayout& layout, const std::filesystem::path& name,
                                       size_t p) {
  const std::filesystem::path path = pageOutputPath(name, layout, p);
  if (!pathExists(path))
    throw IoError("missing image '" + path.string() + "': " +
                  describePage(layout.pages[p], layout.udim) + " of '" + name.string() + "'");
  return path;
}

}  // namespace

void readPagedImageSizes(PageLayout& layout, const std::filesystem::path& name) {
  for (size_t p = 0; p < layout.pages.size(); ++p)
    std::tie(layout.pages[p].width, layout.pages[p].height) =
        readImageSize(requirePagedFile(layout, name, p));
  arrangePages(layout);
}

Image readPagedImage(const PageLayout& layout, const std::filesystem::path& name, PageGapFill gap) {
  Image out;
  for (size_t p = 0; p < layout.pages.size(); ++p) {
    const Image page = readImage(requirePagedFile(layout, name, p));
    if (p == 0) out = Image(layout.width, layout.height, page.channels, page.format);
    copyIntoLayout(layout, p, page, out, gap);
  }
  return out;
}

Image pageImage(const PageLayout& layout, const Image& image, size_t p) {
  const TexturePage& page = layout.pages.at(p);
  if (image.width != layout.width || image.height != layout.height)
    throw InvalidInputError("pageImage: the image is " + std::to_string(image.width) + "x" +
                            std::to_string(image.height) + ", the layout " +
                            std::to_string(layout.width) + "x" + std::to_string(layout.height));
  Image out(page.width, page.height, image.channels, image.format);
  for (int j = 0; j < page.height; ++j)
    for (int i = 0; i < page.width; ++i)
      for (int c = 0; c < image.channels; ++c) out.at(i, j, c) = image.at(page.offset + i, j, c);
  return out;
}

std::vector<Image> splitPages(const PageLayout& layout, const Image& image) {
  std::vector<Image> pages;
  for (size_t p = 0; p < layout.pages.size(); ++p) pages.push_back(pageImage(layout, image, p));
  return pages;
}

std::filesystem::path pageOutputPath(const std::filesystem::path& out, const PageLayout& layout,
                                     size_t p) {
  const std::string& name = layout.pages.at(p).name;
  if (hasUdimToken(out)) {
    std::string text = out.string();
    const auto [at, length] = findToken(text);
    return text.replace(at, length, name);
  }
  if (layout.single()) return out;
  std::filesystem::path path = out;
  return path.replace_extension("." + name + out.extension().string());
}

}  // namespace texgrad
