// readMeshTexture / writeMeshTexture: the texture slot of a mesh, on disk or embedded, and the
// choice between an image file and glTF write-back for the processed result.
#include "texgrad/io/mesh_texture.h"

#include <algorithm>
#include <cctype>
#include <vector>

#include "texgrad/core/error.h"
#include "texgrad/core/path_exists.h"
#include "texgrad/io/atomic_file.h"
#include "texgrad/io/gltf_writer.h"
#include "texgrad/io/image_io.h"

namespace texgrad {

namespace {

/// The mesh's distinct textures in `slot`, in the reader's order.
std::vector<const TextureRef*> slotTextures(const TexturedMesh& mesh, const std::string& slot) {
  std::vector<const TextureRef*> refs;
  for (const TextureRef& t : mesh.textures)
    if (t.slot == slot) refs.push_back(&t);
  return refs;
}

/// The depth of the PNG a glTF copy embeds for an image in `format` (writeGltfWithTexture).
PixelFormat embeddedPngFormat(PixelFormat format) {
  return format == PixelFormat::UInt8 ? PixelFormat::UInt8 : PixelFormat::UInt16;
}

/// How a message names a texture: where the file names it, else its file.
std::string describe(const TextureRef& ref) {
  if (!ref.origin.empty()) return ref.origin;
  return ref.path.empty() ? "an embedded image" : "'" + ref.path.string() + "'";
}

}  // namespace

std::optional<Image> readMeshTexture(const TexturedMesh& mesh, const std::string& slot) {
  const std::vector<const TextureRef*> refs = slotTextures(mesh, slot);
  const std::string file = mesh.sourcePath.string();
  if (refs.empty() && !mesh.missingFiles.empty())
    throw IoError(mesh.missingFiles.front() + ", so the mesh's " + slot +
                  " texture is unknown; restore the file or pass the texture as an argument");
  if (refs.empty()) return std::nullopt;
  if (refs.size() > 1) {
    std::string list;
    for (const TextureRef* ref : refs)
      list += (list.empty() ? "" : ", ") + describe(*ref) + " on " + std::to_string(ref->faces) +
              (ref->faces == 1 ? " face" : " faces");
    throw UnsupportedError(file + ": its faces use " + std::to_string(refs.size()) + " different " +
                           slot + " textures (" + list +
                           "), and only one texture page is supported; give every face one "
                           "material, or pass the texture to process as an argument");
  }
  const TextureRef* ref = refs.front();
  if (!ref->path.empty() && !pathExists(ref->path))
    throw IoError(file + ": " + describe(*ref) + ", the " + slot + " texture, was not found at " +
                  ref->path.string() + "; restore the image file or fix the reference");
  if (!ref->path.empty()) return readImage(ref->path);
  return readImageFromMemory(ref->embedded,
                             mesh.sourcePath.string() + " (embedded " + slot + " texture)");
}

bool isGltfPath(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".gltf" || ext == ".glb";
}

namespace {

/// Throws InvalidInputError naming `out` unless `meshSource` is a glTF asset to copy.
void requireGltfSource(const std::filesystem::path& out, const std::filesystem::path& meshSource) {
  if (!isGltfPath(meshSource))
    throw InvalidInputError(out.string() +
                            " asks for a glTF asset, but the mesh was not read from glTF; write "
                            "an image (.png, .exr, ...) instead");
}

}  // namespace

void checkMeshTextureOutput(const std::filesystem::path& out,
                            const std::filesystem::path& meshSource,
                            std::optional<PixelFormat> requested) {
  if (!isGltfPath(out)) {
    checkImageOutput(out, requested);
    return;
  }
  requireGltfSource(out, meshSource);
  if (requested && *requested != PixelFormat::UInt8 && *requested != PixelFormat::UInt16)
    throw InvalidInputError("cannot write " + out.string() + " with a " +
                            std::string(pixelFormatName(*requested)) +
                            " texture: glTF output embeds a PNG (8 or 16 bits)");
  checkWritableTarget(out);
}

WrittenTexture writeMeshTexture(const std::filesystem::path& out, const TexturedMesh& mesh,
                                const Image& image, const std::string& slot,
                                std::optional<PixelFormat> format) {
  if (!isGltfPath(out)) return {writeImage(out, image, format), {}};
  requireGltfSource(out, mesh.sourcePath);
  const std::vector<const TextureRef*> refs = slotTextures(mesh, slot);
  if (refs.size() > 1)
    throw UnsupportedError("cannot write " + out.string() + ": " + mesh.sourcePath.string() +
                           " has " + std::to_string(refs.size()) + " " + slot +
                           " images, and one processed image cannot replace them all; process "
                           "its texture pages together");
  WrittenTexture written;
  // A mesh whose faces use no image in the slot: the asset's first slot texture is replaced.
  written.warnings = refs.empty()
                         ? writeGltfWithTexture(mesh.sourcePath, out, slot, image, format)
                         : writeGltfWithTextures(
                               mesh.sourcePath, out, slot,
                               {{refs.front(), [&]() -> const Image& { return image; }}}, format);
  written.stored = embeddedPngFormat(format.value_or(image.format));
  return written;
}

WrittenTexture writeGltfTexturePages(const std::filesystem::path& out, const TexturedMesh& mesh,
                                     const PageLayout& layout, const Image& image,
                                     std::optional<PixelFormat> format) {
  requireGltfSource(out, mesh.sourcePath);
  if (layout.udim)
    throw UnsupportedError("cannot write " + out.string() + ": its " + layout.slot +
                           " texture is UDIM tiles, which glTF has no way to name; write images "
                           "(--out NAME.<UDIM>.png)");
  Image page;  // the page being written: one in memory at a time
  std::vector<GltfImageReplacement> replacements;
  for (size_t p = 0; p < layout.pages.size(); ++p) {
    const int texture = layout.pages[p].texture;
    if (texture < 0 || static_cast<size_t>(texture) >= mesh.textures.size())
      throw InvalidInputError("cannot write " + out.string() + ": page '" + layout.pages[p].name +
                              "' comes from no image of " + mesh.sourcePath.string());
    auto cut = [&, p]() -> const Image& { return page = pageImage(layout, image, p); };
    replacements.push_back({&mesh.textures[static_cast<size_t>(texture)], cut});
  }
  WrittenTexture written;
  written.warnings = writeGltfWithTextures(mesh.sourcePath, out, layout.slot, replacements, format);
  written.stored = embeddedPngFormat(format.value_or(image.format));
  return written;
}

}  // namespace texgrad
