// glTF helpers shared by the reader and the write-back.
#include "gltf_common.h"

#include <array>
#include <cctype>
#include <fstream>
#include <string_view>

#include "texgrad/core/error.h"

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

tinygltf::Model loadModel(const std::filesystem::path& path, tinygltf::LoadImageDataFunction capture,
                          ImageBytes& images) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(capture, &images);
  tinygltf::Model model;
  std::string error, warning;
  const bool ok = isBinaryGltf(path)
                      ? loader.LoadBinaryFromFile(&model, &error, &warning, path.string())
                      : loader.LoadASCIIFromFile(&model, &error, &warning, path.string());
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
