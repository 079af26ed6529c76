// Writes a copy of a glTF asset with one of its textures replaced (glTF write-back).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "texgrad/io/image.h"

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

}  // namespace texgrad
