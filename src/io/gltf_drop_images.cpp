// Removing images from a glTF model with the textures and material references that use them
// (write-back of an asset whose image files are partly missing).
#include "gltf_drop_images.h"

#include <array>
#include <optional>
#include <string>

namespace texgrad::gltf {
namespace {

/// Old index -> new index after removal; -1 for a removed element.
using Renumbering = std::vector<int>;

Renumbering renumberingWithout(size_t count, const std::vector<bool>& removed) {
  Renumbering map(count, -1);
  int next = 0;
  for (size_t i = 0; i < count; ++i)
    if (!removed[i]) map[i] = next++;
  return map;
}

/// The new index of `index` (-1 if removed; an index out of range is kept as it is, for the
/// validator to report, as it was in the source).
int renumber(int index, const Renumbering& map) {
  if (index < 0 || static_cast<size_t>(index) >= map.size()) return index;
  return map[static_cast<size_t>(index)];
}

/// Copy of `value` where every object's numeric member `key` is renumbered by `map`; an object
/// whose `key` names a removed element is left out of its parent. nullopt if `value` itself is
/// such an object.
std::optional<tinygltf::Value> renumbered(const tinygltf::Value& value, const std::string& key,
                                          const Renumbering& map) {
  if (value.IsArray()) {
    tinygltf::Value::Array items;
    for (const tinygltf::Value& item : value.Get<tinygltf::Value::Array>())
      if (auto kept = renumbered(item, key, map)) items.push_back(std::move(*kept));
    return tinygltf::Value(std::move(items));
  }
  if (!value.IsObject()) return value;
  tinygltf::Value::Object members;
  for (const auto& [name, child] : value.Get<tinygltf::Value::Object>()) {
    if (name == key && child.IsNumber()) {
      const int index = renumber(child.GetNumberAsInt(), map);
      if (index < 0 && child.GetNumberAsInt() >= 0) return std::nullopt;
      members.emplace(name, tinygltf::Value(index));
    } else if (auto kept = renumbered(child, key, map)) {
      members.emplace(name, std::move(*kept));
    }
  }
  return tinygltf::Value(std::move(members));
}

/// `extensions` renumbered by renumbered(); an extension that is itself a removed reference goes.
tinygltf::ExtensionMap renumbered(const tinygltf::ExtensionMap& extensions, const std::string& key,
                                  const Renumbering& map) {
  tinygltf::ExtensionMap out;
  for (const auto& [name, value] : extensions)
    if (auto kept = renumbered(value, key, map)) out.emplace(name, std::move(*kept));
  return out;
}

/// True if `value` has, at any depth, a numeric member `key` naming a removed element.
bool namesRemoved(const tinygltf::Value& value, const std::string& key, const Renumbering& map) {
  if (value.IsArray()) {
    for (const tinygltf::Value& item : value.Get<tinygltf::Value::Array>())
      if (namesRemoved(item, key, map)) return true;
  } else if (value.IsObject()) {
    for (const auto& [name, child] : value.Get<tinygltf::Value::Object>()) {
      const bool removed = name == key && child.IsNumber() && child.GetNumberAsInt() >= 0 &&
                           renumber(child.GetNumberAsInt(), map) < 0;
      if (removed || namesRemoved(child, key, map)) return true;
    }
  }
  return false;
}

bool namesRemoved(const tinygltf::ExtensionMap& extensions, const std::string& key,
                  const Renumbering& map) {
  for (const auto& entry : extensions)
    if (namesRemoved(entry.second, key, map)) return true;
  return false;
}

/// The texture index fields of a material's core slots.
std::array<int*, 5> coreSlots(tinygltf::Material& m) {
  return {&m.pbrMetallicRoughness.baseColorTexture.index,
          &m.pbrMetallicRoughness.metallicRoughnessTexture.index, &m.normalTexture.index,
          &m.occlusionTexture.index, &m.emissiveTexture.index};
}

}  // namespace

void dropImages(tinygltf::Model& model, const std::vector<int>& dropped) {
  std::vector<bool> imageRemoved(model.images.size(), false);
  for (int i : dropped)
    if (i >= 0 && static_cast<size_t>(i) < imageRemoved.size())
      imageRemoved[static_cast<size_t>(i)] = true;
  const Renumbering images = renumberingWithout(model.images.size(), imageRemoved);

  std::vector<bool> textureRemoved(model.textures.size(), false);
  for (size_t t = 0; t < model.textures.size(); ++t) {
    const tinygltf::Texture& texture = model.textures[t];
    textureRemoved[t] = (texture.source >= 0 && renumber(texture.source, images) < 0) ||
                        namesRemoved(texture.extensions, "source", images);
  }
  const Renumbering textures = renumberingWithout(model.textures.size(), textureRemoved);

  for (tinygltf::Material& m : model.materials) {
    for (int* slot : coreSlots(m)) *slot = renumber(*slot, textures);
    m.extensions = renumbered(m.extensions, "index", textures);
    m.pbrMetallicRoughness.extensions =
        renumbered(m.pbrMetallicRoughness.extensions, "index", textures);
  }
  std::vector<tinygltf::Texture> keptTextures;
  for (size_t t = 0; t < model.textures.size(); ++t) {
    if (textureRemoved[t]) continue;
    tinygltf::Texture texture = std::move(model.textures[t]);
    texture.source = renumber(texture.source, images);
    texture.extensions = renumbered(texture.extensions, "source", images);
    keptTextures.push_back(std::move(texture));
  }
  model.textures = std::move(keptTextures);
  std::vector<tinygltf::Image> keptImages;
  for (size_t i = 0; i < model.images.size(); ++i)
    if (!imageRemoved[i]) keptImages.push_back(std::move(model.images[i]));
  model.images = std::move(keptImages);
}

}  // namespace texgrad::gltf
