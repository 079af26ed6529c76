// Texture pages in the `texgrad` subcommands: the layout logic is the io module's
// (texture_pages.h); this file only chooses between one page (today's path) and several.
#include "cli_pages.h"

#include <array>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "cli_common.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_texture.h"

namespace texgrad::cli {

PagedTexture loadPagedTexture(TexturedMesh mesh, const std::string& meshSpec,
                              const std::string& explicitPath, const std::string& slot) {
  PagedTexture paged;
  paged.layout = findTexturePages(mesh, slot, explicitPath);
  if (paged.layout.single() && !paged.layout.udim) {
    paged.image = loadTexture(mesh, meshSpec, explicitPath, slot);
    paged.layout.pages.front().width = paged.image.width;
    paged.layout.pages.front().height = paged.image.height;
    arrangePages(paged.layout);
    paged.mesh = std::move(mesh);
    return paged;
  }
  readPageSizes(paged.layout, mesh);
  paged.image = readTexturePages(paged.layout, mesh);
  paged.mesh = placeOnPages(mesh, paged.layout);
  return paged;
}

PagedTexture placeOnPagesOfSize(TexturedMesh mesh, int width, int height) {
  PagedTexture paged;
  paged.layout = findTexturePages(mesh, "baseColor");
  for (TexturePage& page : paged.layout.pages) {
    page.width = width;
    page.height = height;
  }
  arrangePages(paged.layout);
  paged.mesh = paged.layout.single() ? std::move(mesh) : placeOnPages(mesh, paged.layout);
  return paged;
}

std::optional<PagedTexture> placeOnPagesOfImages(const TexturedMesh& mesh) {
  PagedTexture paged;
  paged.layout = findTexturePages(mesh, "baseColor");
  if (paged.layout.single() && !paged.layout.udim) return std::nullopt;
  readPageSizes(paged.layout, mesh);
  paged.mesh = placeOnPages(mesh, paged.layout);
  return paged;
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
                              const PageLayout& layout, const Image& image, const std::string& slot,
                              const std::string& bitDepth, bool quiet) {
  if (layout.single() && !hasUdimToken(out))
    return writeTextureOutput(out, mesh, image, slot, bitDepth, quiet);
  checkPagedOutputArgs(out, layout, bitDepth);
  if (isGltfPath(out)) {
    const WrittenTexture written =
        writeGltfTexturePages(out, mesh, layout, image, requestedFormat(bitDepth));
    if (!quiet)
      for (const std::string& warning : written.warnings)
        std::cerr << "texgrad: warning: " << warning << "\n";
    return written.stored;
  }
  PixelFormat stored = image.format;
  for (size_t p = 0; p < layout.pages.size(); ++p)  // one page in memory at a time
    stored = writeImage(pageOutputPath(out, layout, p), pageImage(layout, image, p),
                        requestedFormat(bitDepth));
  return stored;
}

PixelFormat writePagedImage(const std::string& out, const PageLayout& layout, const Image& image,
                            PixelFormat format) {
  if (layout.single() && !hasUdimToken(out)) return writeImage(out, image, format);
  PixelFormat stored = format;
  for (size_t p = 0; p < layout.pages.size(); ++p)
    stored = writeImage(pageOutputPath(out, layout, p), pageImage(layout, image, p), format);
  return stored;
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
