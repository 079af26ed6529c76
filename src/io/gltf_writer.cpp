// glTF write-back: copies a .gltf/.glb asset with material images replaced by PNGs that are
// embedded in the asset (one image per texture page of a slot). tinygltf parses the source without
// decoding any image (bytes are only captured) and serialises the edited model to a stream inside
// writeAtomically.
//
// The output is one self-contained file that can be moved anywhere:
//  * .glb  - all buffers are merged into buffer 0 (the BIN chunk) and every image is stored in a
//            bufferView.
//  * .gltf - every buffer is embedded as a base64 data URI (no sidecar .bin, so the one atomic
//            rename publishes the whole asset), and every image, the new texture and the source's
//            external image files alike, lives in a bufferView of buffer 0.
// A source image file that is missing cannot be embedded: the copy leaves that image out with
// the textures and material references that use it (gltf::dropImages), so it never carries a
// dangling URI, and the caller gets one warning line naming the file.
//
// A replaced image is named by materials: those of a mesh's TextureRef (writeGltfWithTextures), or
// the first material (in the reader's order: primitives of the drawn scene, then the material
// list) with a texture in the slot (writeGltfWithTexture). Their slot textures, and every texture
// showing the same image, form the set T redirected: every material slot of that kind pointing
// into T follows; a texture of T is reused if nothing else refers to it, otherwise a copy (same
// sampler) is added. The new image takes an old image's index if no other texture uses that
// image, otherwise it is appended; the old image's embedded bytes are cut out of the buffer when
// nothing else shares them, so repeated write-backs do not grow a GLB. Both functions run the
// same code (writeCopy); only the choice of images differs.
#include "texgrad/io/gltf_writer.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <string_view>
#include <vector>

#include "gltf_common.h"
#include "gltf_drop_images.h"
#include "png_encode.h"
#include "texgrad/core/error.h"
#include "texgrad/io/atomic_file.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad {
namespace {

namespace fs = std::filesystem;

using Bytes = std::vector<unsigned char>;
using gltf::ImageBytes;
using gltf::percentDecode;
using gltf::sceneRoots;

constexpr std::array<std::string_view, 5> kSlots = {"baseColor", "normal", "emissive",
                                                    "metallicRoughness", "occlusion"};
/// A GLB's total length is a uint32 (glTF 2.0 spec, "GLB File Format Specification").
constexpr size_t kMaxGlbBytes = std::numeric_limits<uint32_t>::max();

/// Image loader for tinygltf: keeps the encoded bytes of every image not stored in a bufferView
/// (external files and data URIs) and decodes nothing.
bool captureImage(tinygltf::Image* image, const int index, std::string*, std::string*, int, int,
                  const unsigned char* bytes, int size, void* user) {
  if (image->bufferView >= 0 || bytes == nullptr || size <= 0) return true;
  (*static_cast<ImageBytes*>(user))[index].assign(bytes, bytes + size);
  return true;
}

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

bool startsWith(const Bytes& bytes, std::string_view magic) {
  return bytes.size() >= magic.size() && std::memcmp(bytes.data(), magic.data(), magic.size()) == 0;
}

/// MIME type of encoded image bytes, or "" if the format is not one glTF (or a common texture
/// extension) can carry in a bufferView.
std::string mimeTypeOf(const Bytes& bytes) {
  using namespace std::string_view_literals;
  if (startsWith(bytes, "\x89PNG\r\n\x1a\n"sv)) return "image/png";
  if (startsWith(bytes, "\xff\xd8\xff"sv)) return "image/jpeg";
  if (startsWith(bytes, "RIFF"sv) && bytes.size() >= 12 &&
      std::memcmp(bytes.data() + 8, "WEBP", 4) == 0)
    return "image/webp";
  if (startsWith(bytes, "\xabKTX 20\xbb\r\n\x1a\n"sv)) return "image/ktx2";
  if (startsWith(bytes, "DDS "sv)) return "image/vnd-ms.dds";
  return "";
}

/// The texture index field of `slot` in a (const or mutable) material.
template <typename Material>
auto& slotIndex(Material& m, std::string_view slot) {
  if (slot == "baseColor") return m.pbrMetallicRoughness.baseColorTexture.index;
  if (slot == "normal") return m.normalTexture.index;
  if (slot == "emissive") return m.emissiveTexture.index;
  if (slot == "metallicRoughness") return m.pbrMetallicRoughness.metallicRoughnessTexture.index;
  return m.occlusionTexture.index;
}

/// True if `value` holds, at any depth, a member `key` whose number is `index` (used to find
/// texture references inside extensions such as KHR_materials_clearcoat, conservatively).
bool mentionsIndex(const tinygltf::Value& value, const std::string& key, int index) {
  if (value.IsObject()) {
    for (const std::string& k : value.Keys()) {
      const tinygltf::Value& child = value.Get(k);
      if (k == key && child.IsNumber() && child.GetNumberAsInt() == index) return true;
      if (mentionsIndex(child, key, index)) return true;
    }
  } else if (value.IsArray()) {
    for (size_t i = 0; i < value.ArrayLen(); ++i)
      if (mentionsIndex(value.Get(static_cast<int>(i)), key, index)) return true;
  }
  return false;
}

bool mentionsIndex(const tinygltf::ExtensionMap& extensions, const std::string& key, int index) {
  return std::any_of(extensions.begin(), extensions.end(),
                     [&](const auto& entry) { return mentionsIndex(entry.second, key, index); });
}

/// Root nodes to draw: the default scene, else scene 0, else every node without a parent (the
/// reader's rule).
/// Materials in the order readGltf consults them (primitives of the drawn scene, depth first),
/// followed by every material index as a fallback.
std::vector<int> materialOrder(const tinygltf::Model& model) {
  std::vector<int> order;
  std::vector<bool> onPath(model.nodes.size(), false);
  std::function<void(int)> visit = [&](int node) {
    if (node < 0 || static_cast<size_t>(node) >= model.nodes.size() ||
        onPath[static_cast<size_t>(node)])
      return;
    onPath[static_cast<size_t>(node)] = true;
    const tinygltf::Node& n = model.nodes[static_cast<size_t>(node)];
    if (n.mesh >= 0 && static_cast<size_t>(n.mesh) < model.meshes.size())
      for (const auto& primitive : model.meshes[static_cast<size_t>(n.mesh)].primitives)
        if (primitive.material >= 0) order.push_back(primitive.material);
    for (int child : n.children) visit(child);
    onPath[static_cast<size_t>(node)] = false;
  };
  for (int root : sceneRoots(model)) visit(root);
  for (size_t m = 0; m < model.materials.size(); ++m) order.push_back(static_cast<int>(m));
  return order;
}

/// The first material (reader order) with a texture in `slot`, or -1.
int firstSlotMaterial(const tinygltf::Model& model, std::string_view slot) {
  for (int m : materialOrder(model)) {
    if (static_cast<size_t>(m) >= model.materials.size()) continue;
    const int texture = slotIndex(model.materials[static_cast<size_t>(m)], slot);
    if (texture >= 0 && static_cast<size_t>(texture) < model.textures.size()) return m;
  }
  return -1;
}

/// True if texture `texture` is used by anything other than the `slot` fields being redirected.
bool textureUsedElsewhere(const tinygltf::Model& model, int texture, std::string_view slot) {
  for (const auto& m : model.materials) {
    for (std::string_view other : kSlots)
      if (other != slot && slotIndex(m, other) == texture) return true;
    if (mentionsIndex(m.extensions, "index", texture) ||
        mentionsIndex(m.pbrMetallicRoughness.extensions, "index", texture))
      return true;
  }
  return mentionsIndex(model.extensions, "index", texture);
}

/// True if any texture uses image `image` (as its source or as an extension's source).
bool imageUsed(const tinygltf::Model& model, int image) {
  return std::any_of(model.textures.begin(), model.textures.end(), [&](const auto& t) {
    return t.source == image || mentionsIndex(t.extensions, "source", image);
  });
}

/// The textures one replacement redirects: those `materials` use in `slot`, and every texture
/// whose image is one of theirs (the reader merges materials by image, so these are one page).
std::set<int> replacedTextures(const tinygltf::Model& model, std::string_view slot,
                               const std::vector<int32_t>& materials) {
  std::set<int> textures, images;
  for (int32_t m : materials) {
    if (m < 0 || static_cast<size_t>(m) >= model.materials.size()) continue;
    const int t = slotIndex(model.materials[static_cast<size_t>(m)], slot);
    if (t < 0 || static_cast<size_t>(t) >= model.textures.size()) continue;
    textures.insert(t);
    const int image = model.textures[static_cast<size_t>(t)].source;
    if (image >= 0 && static_cast<size_t>(image) < model.images.size()) images.insert(image);
  }
  for (size_t t = 0; t < model.textures.size(); ++t)
    if (images.count(model.textures[t].source) != 0) textures.insert(static_cast<int>(t));
  return textures;
}

/// Appends `bytes` to buffer 0 (4-byte aligned) as bufferView `reuse`, or as a new bufferView if
/// `reuse` is -1; returns its index.
int appendBufferView(tinygltf::Model& model, const Bytes& bytes, int reuse = -1) {
  Bytes& data = model.buffers[0].data;
  data.resize((data.size() + 3) / 4 * 4, 0);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = bytes.size();
  data.insert(data.end(), bytes.begin(), bytes.end());
  if (reuse >= 0) {
    model.bufferViews[static_cast<size_t>(reuse)] = std::move(view);
    return reuse;
  }
  model.bufferViews.push_back(std::move(view));
  return static_cast<int>(model.bufferViews.size() - 1);
}

/// True if anything but image `image` uses bufferView `view` (accessors, other images, or a
/// "bufferView" member in an extension such as KHR_draco_mesh_compression).
bool bufferViewUsedElsewhere(const tinygltf::Model& model, int view, int image) {
  for (const auto& a : model.accessors)
    if (a.bufferView == view || a.sparse.indices.bufferView == view ||
        a.sparse.values.bufferView == view)
      return true;
  for (size_t i = 0; i < model.images.size(); ++i)
    if (static_cast<int>(i) != image && model.images[i].bufferView == view) return true;
  for (const auto& mesh : model.meshes) {
    if (mentionsIndex(mesh.extensions, "bufferView", view)) return true;
    for (const auto& primitive : mesh.primitives)
      if (mentionsIndex(primitive.extensions, "bufferView", view)) return true;
  }
  return mentionsIndex(model.extensions, "bufferView", view);
}

/// If image `image` is stored in a bufferView nothing else uses, cuts its bytes out of the buffer
/// (later bufferViews move down by a multiple of 4, keeping their alignment; with no later ones,
/// the buffer ends where the image started) and returns the
/// bufferView's index for reuse; returns -1 and changes nothing if that is not safe.
int releaseImageBytes(tinygltf::Model& model, int image) {
  const int index = model.images[static_cast<size_t>(image)].bufferView;
  if (index < 0 || static_cast<size_t>(index) >= model.bufferViews.size() ||
      bufferViewUsedElsewhere(model, index, image))
    return -1;
  // Compressed views (EXT_meshopt_compression) address buffers by offset: never move bytes then.
  for (const auto& v : model.bufferViews)
    if (!v.extensions.empty()) return -1;
  const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(index)];
  if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model.buffers.size()) return -1;
  Bytes& data = model.buffers[static_cast<size_t>(view.buffer)].data;
  const size_t start = view.byteOffset, end = view.byteOffset + view.byteLength;
  if (start > data.size() || end > data.size()) return -1;
  for (size_t v = 0; v < model.bufferViews.size(); ++v) {
    const tinygltf::BufferView& other = model.bufferViews[v];
    if (static_cast<int>(v) != index && other.buffer == view.buffer && other.byteOffset < end &&
        other.byteOffset + other.byteLength > start)
      return -1;  // overlapping views share bytes
  }
  // Later bufferViews move down by a multiple of 4; with none after it, everything from the
  // image's start goes (its padding too), so a replaced image leaves no byte behind.
  const bool bytesAfter = std::any_of(model.bufferViews.begin(), model.bufferViews.end(),
                                      [&](const tinygltf::BufferView& other) {
                                        return other.buffer == view.buffer &&
                                               other.byteOffset >= end && &other != &view;
                                      });
  const size_t cut = bytesAfter ? (end - start) / 4 * 4 : data.size() - start;
  // The new image goes into buffer 0: another buffer emptied would be left as an empty one,
  // which glTF readers refuse, so its bytes stay (the view is not reused).
  if (cut == data.size() && view.buffer != 0) return -1;
  data.erase(data.begin() + static_cast<std::ptrdiff_t>(start),
             data.begin() + static_cast<std::ptrdiff_t>(start + cut));
  for (auto& other : model.bufferViews)
    if (other.buffer == view.buffer && other.byteOffset >= end) other.byteOffset -= cut;
  return index;
}

/// Moves the data of every buffer into buffer 0 (which becomes the GLB's BIN chunk).
void mergeBuffers(tinygltf::Model& model) {
  Bytes& merged = model.buffers[0].data;
  for (size_t b = 1; b < model.buffers.size(); ++b) {
    merged.resize((merged.size() + 3) / 4 * 4, 0);
    const size_t offset = merged.size();
    const Bytes& data = model.buffers[b].data;
    merged.insert(merged.end(), data.begin(), data.end());
    for (auto& view : model.bufferViews)
      if (view.buffer == static_cast<int>(b)) {
        view.buffer = 0;
        view.byteOffset += offset;
      }
  }
  model.buffers.resize(1);
  model.buffers[0].uri.clear();
}

/// The file an external image's URI names, relative to the source asset's folder.
fs::path imageFile(const tinygltf::Image& image, const fs::path& source) {
  return (fs::absolute(source).parent_path() / percentDecode(image.uri)).lexically_normal();
}

/// Stores every image not yet in a bufferView (external files, data URIs) in buffer 0, so the
/// output refers to no file; returns the indices of the external images whose file is missing
/// (left as they are, for dropImages). Throws if an image's bytes are not a format glTF carries.
std::vector<int> embedSourceImages(tinygltf::Model& model, const ImageBytes& sourceImages,
                                   const fs::path& source) {
  std::vector<int> missing;
  for (size_t i = 0; i < model.images.size(); ++i) {
    tinygltf::Image& img = model.images[i];
    if (img.bufferView >= 0) continue;
    const std::string name = source.string() + ": image " + std::to_string(i) +
                             (img.uri.empty() ? "" : " (URI '" + img.uri + "')");
    const auto captured = sourceImages.find(static_cast<int>(i));
    if (captured == sourceImages.end()) {
      if (img.uri.empty())
        throw InvalidInputError(name + " has neither a URI nor data; re-export the asset");
      if (fs::exists(imageFile(img, source)))
        throw IoError(name + " could not be read from " + imageFile(img, source).string());
      missing.push_back(static_cast<int>(i));
      continue;
    }
    const std::string mime = img.mimeType.empty() ? mimeTypeOf(captured->second) : img.mimeType;
    if (mime.empty())
      throw UnsupportedError(name +
                             " is not a PNG, JPEG, WebP, KTX2 or DDS image, so it cannot "
                             "be embedded in the output; convert it to PNG");
    img.mimeType = mime;
    img.bufferView = appendBufferView(model, captured->second);
    img.uri.clear();
  }
  return missing;
}

/// The warning for a missing source image that the copy leaves out.
std::string missingImageWarning(const tinygltf::Model& model, int image, const fs::path& source,
                                const fs::path& target) {
  const tinygltf::Image& img = model.images[static_cast<size_t>(image)];
  return source.string() + ": image " + std::to_string(image) + " (URI '" + img.uri +
         "') was not found at " + imageFile(img, source).string() + "; " + target.string() +
         " leaves it out, with the textures and material slots that used it";
}

/// Serialises the model to `path`; tinygltf's image writer is disabled so image URIs stay as set.
void writeModel(const tinygltf::Model& model, const fs::path& path, const fs::path& target,
                bool binary) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw IoError("cannot write " + target.string() + ": cannot create a file there");
  tinygltf::TinyGLTF writer;
  writer.SetImageWriter(nullptr, nullptr);
  const bool ok = writer.WriteGltfSceneToStream(&model, out, true, binary);
  out.close();
  if (!ok || !out)
    throw IoError("cannot write " + target.string() + ": writing failed (disk full?)");
}

/// One image to replace: the textures whose slot references move to it, and its PNG encoding.
struct PlannedImage {
  std::set<int> textures;
  std::function<Bytes()> png;
};

/// Points the `slot` references to `textures` at a new image holding `png`. A texture also used
/// elsewhere (another slot, an extension) is copied, keeping its sampler; an old image nothing uses
/// any more is overwritten in place (its bytes cut out), otherwise the new image is appended.
void replaceImage(tinygltf::Model& model, std::string_view slot, const std::set<int>& textures,
                  const Bytes& png) {
  std::vector<int> redirected;
  std::set<int> oldImages;
  for (int texture : textures) {
    oldImages.insert(model.textures[static_cast<size_t>(texture)].source);
    int target = texture;
    if (textureUsedElsewhere(model, texture, slot)) {
      tinygltf::Texture copy = model.textures[static_cast<size_t>(texture)];
      model.textures.push_back(std::move(copy));
      target = static_cast<int>(model.textures.size() - 1);
      for (auto& m : model.materials)
        if (slotIndex(m, slot) == texture) slotIndex(m, slot) = target;
    }
    tinygltf::Texture& t = model.textures[static_cast<size_t>(target)];
    t.extensions.clear();  // alternative sources (KHR_texture_basisu, ...) would win
    t.source = -1;
    redirected.push_back(target);
  }
  tinygltf::Image replacement;
  replacement.name = slot;
  replacement.mimeType = "image/png";
  int newImage = -1;
  for (int old : oldImages)
    if (old >= 0 && static_cast<size_t>(old) < model.images.size() && !imageUsed(model, old)) {
      // The old picture is referenced by nothing else: drop it (and its bytes, if embedded).
      newImage = old;
      const int freedView = releaseImageBytes(model, old);
      replacement.bufferView = appendBufferView(model, png, freedView);
      if (!model.images[static_cast<size_t>(old)].name.empty())
        replacement.name = model.images[static_cast<size_t>(old)].name;
      model.images[static_cast<size_t>(old)] = std::move(replacement);
      break;
    }
  if (newImage < 0) {
    replacement.bufferView = appendBufferView(model, png);
    model.images.push_back(std::move(replacement));
    newImage = static_cast<int>(model.images.size() - 1);
  }
  for (int t : redirected) model.textures[static_cast<size_t>(t)].source = newImage;
}

/// Checks `slot` and `target`'s extension; returns true for a .glb.
bool checkTarget(const std::string& slot, const fs::path& target) {
  if (std::find(kSlots.begin(), kSlots.end(), slot) == kSlots.end())
    throw InvalidInputError("unknown texture slot '" + slot +
                            "'; use baseColor, normal, emissive, metallicRoughness or occlusion");
  const std::string extension = lowercase(target.extension().string());
  if (extension != ".gltf" && extension != ".glb")
    throw UnsupportedError("cannot write " + target.string() + ": unknown glTF extension '" +
                           target.extension().string() + "'; use .gltf or .glb");
  return extension == ".glb";
}

/// The write-back both public functions share: `plan` picks, from the loaded source model, the
/// images to replace; each is encoded and stored in turn, then the copy is written atomically.
std::vector<std::string> writeCopy(
    const fs::path& source, const fs::path& target, const std::string& slot,
    const std::function<std::vector<PlannedImage>(const tinygltf::Model&)>& plan) {
  const bool binary = checkTarget(slot, target);
  const std::string where = "cannot write " + target.string() + ": ";
  requireReadableFile(source);
  ImageBytes sourceImages;
  tinygltf::Model model = gltf::loadModel(source, captureImage, sourceImages);
  const std::vector<PlannedImage> planned = plan(model);

  if (model.buffers.empty()) model.buffers.emplace_back();
  if (binary) mergeBuffers(model);
  for (const PlannedImage& image : planned) replaceImage(model, slot, image.textures, image.png());

  const std::vector<int> missing = embedSourceImages(model, sourceImages, source);
  std::vector<std::string> warnings;
  for (int i : missing) warnings.push_back(missingImageWarning(model, i, source, target));
  gltf::dropImages(model, missing);

  if (binary && model.buffers[0].data.size() > kMaxGlbBytes)
    throw UnsupportedError(where + "the binary data exceeds the 4 GB a GLB can hold; write .gltf");
  if (model.asset.version.empty()) model.asset.version = "2.0";

  writeAtomically(target,
                  [&](const fs::path& temporary) { writeModel(model, temporary, target, binary); });
  return warnings;
}

}  // namespace

std::vector<std::string> writeGltfWithTexture(const fs::path& source, const fs::path& target,
                                              const std::string& slot, const Image& image,
                                              std::optional<PixelFormat> format) {
  checkTarget(slot, target);
  const std::string where = "cannot write " + target.string() + ": ";
  png::checkImage(image, where);
  return writeCopy(source, target, slot, [&](const tinygltf::Model& model) {
    const int material = firstSlotMaterial(model, slot);
    if (material < 0)
      throw InvalidInputError(source.string() + " has no " + slot +
                              " texture to replace; its materials reference none");
    return std::vector<PlannedImage>{
        {replacedTextures(model, slot, {material}),
         [&] { return png::encodePng(image, format.value_or(image.format), where); }}};
  });
}

std::vector<std::string> writeGltfWithTextures(
    const fs::path& source, const fs::path& target, const std::string& slot,
    const std::vector<GltfImageReplacement>& replacements, std::optional<PixelFormat> format) {
  checkTarget(slot, target);
  const std::string where = "cannot write " + target.string() + ": ";
  for (const GltfImageReplacement& r : replacements)
    if (r.texture == nullptr || !r.image || r.texture->slot != slot)
      throw InvalidInputError(where + "every replaced image needs a " + slot +
                              " texture of the mesh and a picture");
  return writeCopy(source, target, slot, [&](const tinygltf::Model& model) {
    std::vector<PlannedImage> planned;
    std::set<int> taken;
    for (const GltfImageReplacement& r : replacements) {
      const std::string name = source.string() + ": " + slot + " " + r.texture->origin;
      std::set<int> textures = replacedTextures(model, slot, r.texture->materials);
      if (textures.empty())
        throw InvalidInputError(name +
                                " is used by no material of the asset in that slot; pass "
                                "a texture of the mesh read from this file");
      for (int t : textures)
        if (!taken.insert(t).second)
          throw InvalidInputError(name + " is replaced twice; give each image one picture");
      planned.push_back({std::move(textures), [&r, &where, format] {
                           const Image& image = r.image();
                           png::checkImage(image, where);
                           return png::encodePng(image, format.value_or(image.format), where);
                         }});
    }
    return planned;
  });
}

}  // namespace texgrad
