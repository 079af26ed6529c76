// glTF helpers shared by the reader and the write-back (private to the io module).
#pragma once

#include <tiny_gltf.h>

#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace texgrad::gltf {

/// Encoded bytes of images kept by a tinygltf image loader, by image index.
using ImageBytes = std::map<int, std::vector<unsigned char>>;

/// Deepest JSON nesting (arrays and objects) a glTF asset may have; glTF itself needs under 10,
/// the rest is headroom for extensions and extras.
inline constexpr int kMaxJsonDepth = 64;

/// Throws InvalidInputError naming `file` if `text` nests arrays/objects deeper than
/// kMaxJsonDepth (a scan without recursion: brackets in strings do not count).
void requireJsonDepth(std::string_view text, const std::string& file);

/// True if the file starts with the GLB magic "glTF".
bool isBinaryGltf(const std::filesystem::path& path);

/// Decodes %XX escapes in a relative URI (glTF image URIs are URI-encoded).
std::string percentDecode(const std::string& uri);

/// Root nodes of the default scene (or of the node forest when there is no scene).
std::vector<int> sceneRoots(const tinygltf::Model& model);

/// Loads a .gltf or .glb with `capture` as tinygltf's image loader (it decides which encoded
/// images go into `images`; nothing is decoded). Throws IoError for missing side files and
/// InvalidInputError for malformed assets.
tinygltf::Model loadModel(const std::filesystem::path& path, tinygltf::LoadImageDataFunction capture,
                          ImageBytes& images);

}  // namespace texgrad::gltf
