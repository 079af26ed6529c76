// readMeshTexturePages / placeMeshOnPages / writePagedImage / writeMeshTexturePages: one image or
// several pages, decided once for every front end.
#include "texgrad/io/mesh_texture_pages.h"

#include <optional>
#include <tuple>
#include <utility>

#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_texture.h"

namespace texgrad {

bool isOneImage(const PageLayout& layout) {
  return layout.single() && !layout.udim;
}

MeshTexturePages readMeshTexturePages(const TexturedMesh& mesh, const std::string& slot,
                                      const std::filesystem::path& texture,
                                      const std::function<Image()>& noTexture) {
  MeshTexturePages read;
  read.layout = findTexturePages(mesh, slot, texture);
  if (isOneImage(read.layout)) {  // the UVs unchanged
    if (!texture.empty()) {
      read.image = readImage(texture);
    } else {
      std::optional<Image> own = readMeshTexture(mesh, slot);
      read.image = own ? std::move(*own) : noTexture();
    }
    read.layout.pages.front().width = read.image.width;
    read.layout.pages.front().height = read.image.height;
    arrangePages(read.layout);
    return read;
  }
  readPageSizes(read.layout, mesh);
  read.image = readTexturePages(read.layout, mesh);
  if (!read.layout.single()) read.placed = placeOnPages(mesh, read.layout);
  return read;
}

MeshPages placeMeshOnPages(const TexturedMesh& mesh, const std::string& slot,
                           const std::filesystem::path& texture,
                           std::optional<std::pair<int, int>> size) {
  MeshPages pages;
  pages.layout = findTexturePages(mesh, slot, texture);
  if (size) {
    for (TexturePage& page : pages.layout.pages) std::tie(page.width, page.height) = *size;
    arrangePages(pages.layout);
  } else {
    readPageSizes(pages.layout, mesh);
  }
  if (!pages.layout.single()) pages.placed = placeOnPages(mesh, pages.layout);
  return pages;
}

PixelFormat writePagedImage(const std::filesystem::path& out, const PageLayout& layout,
                            const Image& image, std::optional<PixelFormat> format) {
  PixelFormat stored = format.value_or(image.format);
  for (size_t p = 0; p < layout.pages.size(); ++p)  // one page in memory at a time
    // One page is the image itself: written without a copy.
    stored = layout.single()
                 ? writeImage(pageOutputPath(out, layout, p), image, format)
                 : writeImage(pageOutputPath(out, layout, p), pageImage(layout, image, p), format);
  return stored;
}

WrittenTexturePages writeMeshTexturePages(const std::filesystem::path& out,
                                          const TexturedMesh& mesh, const PageLayout& layout,
                                          const Image& image, std::optional<PixelFormat> format) {
  WrittenTexturePages written;
  if (isGltfPath(out)) {
    checkMeshTextureOutput(out, mesh.sourcePath, format);
    WrittenTexture copy = layout.single() ? writeMeshTexture(out, mesh, image, layout.slot, format)
                                          : writeGltfTexturePages(out, mesh, layout, image, format);
    written.stored = copy.stored;
    written.files.push_back(out);
    written.warnings = std::move(copy.warnings);
    return written;
  }
  for (size_t p = 0; p < layout.pages.size(); ++p) {  // every file checked before any write
    written.files.push_back(pageOutputPath(out, layout, p));
    checkImageOutput(written.files.back(), format);
  }
  written.stored = writePagedImage(out, layout, image, format);
  return written;
}

}  // namespace texgrad
