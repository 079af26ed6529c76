// Writes a copy of a glTF asset with some of its textures replaced (glTF write-back).
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "texgrad/io/image.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Copies the glTF/GLB asset `source` to `target` (.gltf or .glb, chosen by extension) with the
/// texture of `slot` ("baseColor", "normal", "emissive", "metallicRoughness", "occlusion")
/// replaced by `image` (PNG, 8-bit if `format` (default image.format) is UInt8, else 16-bit).
/// The output is self-contained, so it can be moved anywhere: every buffer and image, the
/// source's external image files included, is embedded (a .glb in its binary chunk, a .gltf as
/// one base64 data URI). The first material (reader order) with a texture in `slot` names the
/// texture replaced; images and textures shared with other slots are not modified. A source
/// image file that is missing is left out with the textures and material slots that use it (no
/// dangling reference); the result holds one warning line per such image. Written atomically;
/// throws InvalidInputError if the asset has no texture in that slot (or `slot` is unknown),
/// UnsupportedError for an image that is not PNG/JPEG/WebP/KTX2/DDS, IoError if the source cannot
/// be read or the target cannot be written.
std::vector<std::string> writeGltfWithTexture(const std::filesystem::path& source,
                                              const std::filesystem::path& target,
                                              const std::string& slot, const Image& image,
                                              std::optional<PixelFormat> format = std::nullopt);

/// The new picture of one image (texture page) of a slot, for writeGltfWithTextures.
struct GltfImageReplacement {
  /// The image replaced: a TextureRef of the mesh readGltf read from the source asset (its
  /// `materials` name the glTF materials, hence the image, it stands for).
  const TextureRef* texture = nullptr;
  /// Returns the new picture; called once, while writing, and the reference it returns need only
  /// live until the next call, so a caller can cut each page out of a larger image in turn.
  std::function<const Image&()> image;
};

/// Copies the glTF/GLB asset `source` to `target` like writeGltfWithTexture, with every image in
/// `replacements` replaced in `slot` (each TextureRef must be of that slot): the `slot` of every
/// material whose image there is the TextureRef's gets the new picture (one PNG per replacement,
/// shared by those materials; their samplers are kept). Every other image stays embedded as it
/// was, and images and textures shared with other slots are not modified. Throws
/// InvalidInputError if a TextureRef's materials have no image in `slot` in the source, or if two
/// replacements name the same image; otherwise as writeGltfWithTexture.
std::vector<std::string> writeGltfWithTextures(
    const std::filesystem::path& source, const std::filesystem::path& target,
    const std::string& slot, const std::vector<GltfImageReplacement>& replacements,
    std::optional<PixelFormat> format = std::nullopt);

}  // namespace texgrad
