// glTF helpers shared by the reader and the write-back.
#include "gltf_common.h"

#include <array>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string_view>
#include <system_error>

#include "texgrad/core/error.h"
#include "texgrad/core/json_depth.h"

namespace texgrad::gltf {

bool isBinaryGltf(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<char, 4> magic{};
  in.read(magic.data(), magic.size());
  return in && std::string_view(magic.data(), magic.size()) == "glTF";
}

std::string percentDecode(const std::string& uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      out.push_back(static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16)));
      i += 2;
    } else {
      out.push_back(uri[i]);
    }
  }
  return out;
}

std::vector<int> sceneRoots(const tinygltf::Model& model) {
  if (!model.scenes.empty()) {
    const int scene =
        model.defaultScene >= 0 && static_cast<size_t>(model.defaultScene) < model.scenes.size()
            ? model.defaultScene
            : 0;
    return model.scenes[static_cast<size_t>(scene)].nodes;
  }
  std::vector<bool> isChild(model.nodes.size(), false);
  for (const auto& node : model.nodes)
    for (int c : node.children)
      if (c >= 0 && static_cast<size_t>(c) < isChild.size()) isChild[static_cast<size_t>(c)] = true;
  std::vector<int> roots;
  for (size_t i = 0; i < model.nodes.size(); ++i)
    if (!isChild[i]) roots.push_back(static_cast<int>(i));
  return roots;
}

void requireJsonDepth(std::string_view text, const std::string& file) {
  if (jsonNestsDeeperThan(text, kMaxJsonDepth))
    throw InvalidInputError(file + ": JSON nests deeper than " + std::to_string(kMaxJsonDepth) +
                            " levels; no glTF asset needs that, so it is refused");
}

namespace {

/// The JSON text of a .gltf (the whole file) or of a GLB (its first chunk, clipped to the file).
std::string_view jsonText(const std::vector<unsigned char>& bytes, bool binary) {
  const std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  if (!binary) return all;
  constexpr size_t kHeader = 12, kChunkHeader = 8;  // GLB header; chunk length + type
  if (all.size() < kHeader + kChunkHeader) return {};
  uint32_t length = 0;
  std::memcpy(&length, all.data() + kHeader, sizeof(length));  // little-endian, as GLB is
  return all.substr(kHeader + kChunkHeader, length);
}

/// What checkedCapture needs: the caller's image loader and the model tinygltf is filling.
struct CaptureContext {
  tinygltf::LoadImageDataFunction capture;
  ImageBytes* images;
  const tinygltf::Model* model;
};

/// Image loader that refuses an image whose bufferView reaches past its buffer before the
/// caller's loader reads it: tinygltf 2.7 checks the view's and buffer's indices, not the range.
bool checkedCapture(tinygltf::Image* image, const int index, std::string* error,
                    std::string* warning, int width, int height, const unsigned char* bytes,
                    int size, void* user) {
  const auto& context = *static_cast<const CaptureContext*>(user);
  if (image->bufferView >= 0) {  // tinygltf has checked both indices before calling
    const tinygltf::BufferView& view =
        context.model->bufferViews[static_cast<size_t>(image->bufferView)];
    const size_t available = context.model->buffers[static_cast<size_t>(view.buffer)].data.size();
    if (view.byteOffset > available || view.byteLength > available - view.byteOffset) {
      *error += "image " + std::to_string(index) + ": bufferView " +
                std::to_string(image->bufferView) + " (bytes " + std::to_string(view.byteOffset) +
                " + " + std::to_string(view.byteLength) + ") reaches past the end of buffer " +
                std::to_string(view.buffer) + " (" + std::to_string(available) + " bytes)";
      return false;
    }
  }
  return context.capture(image, index, error, warning, width, height, bytes, size, context.images);
}

std::vector<unsigned char> readBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), {});
  if (!in && !in.eof()) throw IoError("cannot read " + path.string());
  return bytes;
}

/// tinygltf's test for an external buffer or image file, true for regular files only. Its own
/// accepts anything fopen opens, a folder included (a URI of "." or one that decodes to a NUL
/// byte names the glTF's folder), and its reader then takes a folder's end offset, 2^63 - 1, for
/// the file's size and allocates that (found by fuzzing). A folder is thus a missing file.
bool isRegularFile(const std::string& path, void* /*user*/) {
  std::error_code error;
  return std::filesystem::is_regular_file(path, error);
}

/// tinygltf's reader of an external buffer or image file, for regular files only (isRegularFile).
bool readRegularFile(std::vector<unsigned char>* out, std::string* error, const std::string& path,
                     void* user) {
  if (!isRegularFile(path, user)) {
    *error += "not a regular file";
    return false;
  }
  try {
    *out = readBytes(path);
  } catch (const IoError&) {
    *error += "cannot be read";
    return false;
  }
  return true;
}

}  // namespace

tinygltf::Model loadModel(const std::filesystem::path& path, tinygltf::LoadImageDataFunction capture,
                          ImageBytes& images) {
  const std::vector<unsigned char> bytes = readBytes(path);
  if (bytes.empty()) throw InvalidInputError(path.string() + ": the file is empty");
  if (bytes.size() > std::numeric_limits<unsigned int>::max())  // tinygltf's size type
    throw UnsupportedError(path.string() + ": glTF files over 4 GiB are not supported");
  const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
  // tinygltf parses with nlohmann::json and converts the result recursively: a deep enough file
  // would overflow the stack, so the nesting is bounded before anything is parsed.
  requireJsonDepth(jsonText(bytes, binary), path.string());
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  CaptureContext context{capture, &images, &model};
  loader.SetImageLoader(checkedCapture, &context);
  loader.SetFsCallbacks(tinygltf::FsCallbacks{isRegularFile, tinygltf::ExpandFilePath,
                                              readRegularFile, tinygltf::WriteWholeFile, nullptr});
  std::string error, warning;
  const std::string folder = path.parent_path().string();  // external buffers and images
  const auto size = static_cast<unsigned int>(bytes.size());
  const bool ok =
      binary ? loader.LoadBinaryFromMemory(&model, &error, &warning, bytes.data(), size, folder)
             : loader.LoadASCIIFromString(&model, &error, &warning,
                                          reinterpret_cast<const char*>(bytes.data()), size,
                                          folder);
  if (!ok) {
    while (!error.empty() && error.back() == '\n') error.pop_back();
    if (error.find("File not found") != std::string::npos ||
        error.find("File read error") != std::string::npos)
      throw IoError("cannot load " + path.string() + ": " + error +
                    "; keep its .bin and image files next to it");
    throw InvalidInputError(path.string() + ": not a valid glTF 2.0 file (" + error +
                            "); check it with the Khronos glTF validator");
  }
  return model;
}

}  // namespace texgrad::gltf
