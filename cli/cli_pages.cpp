// Texture pages in the `texgrad` subcommands: the layout logic and the choice between one image
// and several pages are the io module's (texture_pages.h, mesh_texture_pages.h); this file adds
// the CLI's fallbacks, error wording and messages.
#include "cli_pages.h"

#include <array>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "cli_common.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_texture.h"
#include "texgrad/io/mesh_texture_pages.h"

namespace texgrad::cli {

namespace {

/// `pages` as a PagedTexture: the placed mesh, or `mesh` itself on one page.
PagedTexture pagedTexture(TexturedMesh mesh, MeshPages pages) {
  PagedTexture paged;
  paged.mesh = pages.placed ? std::move(*pages.placed) : std::move(mesh);
  paged.layout = std::move(pages.layout);
  return paged;
}

}  // namespace

PagedTexture loadPagedTexture(TexturedMesh mesh, const std::string& meshSpec,
                              const std::string& explicitPath, const std::string& slot) {
  MeshTexturePages read = readMeshTexturePages(mesh, slot, explicitPath,
                                               [&] { return missingTexture(meshSpec, slot); });
  Image image = std::move(read.image);
  PagedTexture paged = pagedTexture(std::move(mesh), std::move(read));
  paged.image = std::move(image);
  return paged;
}

PagedTexture placeOnPagesOfSize(TexturedMesh mesh, int width, int height) {
  MeshPages pages = placeMeshOnPages(mesh, "baseColor", {}, std::pair(width, height));
  return pagedTexture(std::move(mesh), std::move(pages));
}

std::optional<PagedTexture> placeOnPagesOfImages(const TexturedMesh& mesh) {
  if (isOneImage(findTexturePages(mesh, "baseColor"))) return std::nullopt;
  return pagedTexture(mesh, placeMeshOnPages(mesh, "baseColor", {}, std::nullopt));
}

void requireSinglePage(const PageLayout& layout, const std::string& option,
                       const std::string& instead) {
  if (layout.pages.size() > 1)
    throw UnsupportedError(option + " is not supported yet when the " + layout.slot +
                           " texture has " + std::to_string(layout.pages.size()) +
                           " pages (UDIM tiles or materials); " + instead);
}

void checkPagedOutputArgs(const std::string& out, const PageLayout& layout,
                          const std::string& bitDepth) {
  if (layout.single()) return;  // checkTextureOutputArgs checked `out` itself
  // A glTF copy: checkTextureOutputArgs checked the source and the depth.
  if (isGltfPath(out)) {
    if (layout.udim)
      throw UnsupportedError("--out " + out + ": the " + layout.slot +
                             " texture is UDIM tiles, which glTF cannot name; write images "
                             "(--out NAME.<UDIM>.png gives one image per tile)");
    return;
  }
  for (size_t p = 0; p < layout.pages.size(); ++p)
    checkImageOutput(pageOutputPath(out, layout, p), requestedFormat(bitDepth));
}

PixelFormat writePagedTexture(const std::string& out, const TexturedMesh& mesh,
                              const PageLayout& layout, const Image& image,
                              const std::string& bitDepth, bool quiet) {
  requireGltfMeshFor(out, mesh.sourcePath);     // the io module's refusals, in the CLI's words
  checkPagedOutputArgs(out, layout, bitDepth);  // (the commands checked both before the work)
  const WrittenTexturePages written =
      writeMeshTexturePages(out, mesh, layout, image, requestedFormat(bitDepth));
  printWarnings(quiet, written.warnings);
  return written.stored;
}

void printWrittenPages(bool quiet, const std::string& out, const PageLayout& layout,
                       const Image& image, PixelFormat stored, int64_t texels, double seconds) {
  if (layout.single() && !hasUdimToken(out)) {
    printWritten(quiet, out, image, stored, texels, seconds);
    return;
  }
  if (quiet) return;
  std::ostringstream files;
  if (isGltfPath(out)) files << out << " with ";  // one image per page inside the copy
  for (size_t p = 0; p < layout.pages.size(); ++p)
    files << (p == 0 ? "" : ", ")
          << (isGltfPath(out) ? layout.pages[p].name : pageOutputPath(out, layout, p).string())
          << " (" << layout.pages[p].width << "x" << layout.pages[p].height << ")";
  std::ostringstream line;
  static constexpr std::array<const char*, 4> kChannels{"1-channel", "2-channel", "RGB", "RGBA"};
  line << "wrote " << layout.pages.size() << (layout.pages.size() == 1 ? " page: " : " pages: ")
       << files.str() << ", "
       << (image.channels >= 1 && image.channels <= 4 ? kChannels[size_t(image.channels - 1)] : "?")
       << " " << pixelFormatName(stored);
  if (texels >= 0) line << ", " << texels << " texels solved";
  char time[32];
  std::snprintf(time, sizeof time, " in %.1f s", seconds);
  std::cerr << line.str() << time << "\n";
}

}  // namespace texgrad::cli
