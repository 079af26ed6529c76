// Writes a copy of a glTF asset with one of its textures replaced (glTF write-back).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "texgrad/io/image.h"

namespace texgrad {

/// Copies the glTF/GLB asset `source` to `target` (.gltf or .glb, chosen by extension) with the
/// texture of `slot` ("baseColor", "normal", "emissive", "metallicRoughness", "occlusion")
/// replaced by `image` (PNG, embedded in the asset; 8-bit if `format` (default image.format) is
/// UInt8, else 16-bit). Other resources stay valid: a .glb embeds them, a .gltf embeds its
/// buffers as base64 data URIs (no sidecar .bin) and refers to external source images by path
/// relative to the target's folder. The first material (reader order) with a texture in `slot`
/// names the texture replaced; images and textures shared with other slots are not modified.
/// Written atomically; throws InvalidInputError if the asset has no texture in that slot (or
/// `slot` is unknown), IoError if the source cannot be read or the target cannot be written.
void writeGltfWithTexture(const std::filesystem::path& source, const std::filesystem::path& target,
                          const std::string& slot, const Image& image,
                          std::optional<PixelFormat> format = std::nullopt);

}  // namespace texgrad
