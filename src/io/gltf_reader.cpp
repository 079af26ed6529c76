// glTF 2.0 input (.gltf / .glb through tinygltf): every triangle primitive of the default scene
// with its node transform applied, one UV set (TEXCOORD_N) flipped to v-up, each face's material,
// and the materials' textures as references with their samplers' wrap modes.
#include <tiny_gltf.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <string>

#include "gltf_common.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad {
namespace {

using gltf::ImageBytes;
using gltf::percentDecode;
using gltf::sceneRoots;

/// Image loader for tinygltf: keeps the encoded bytes of embedded images (bufferView or data
/// URI) and decodes nothing; external images are only referenced by path.
bool captureImage(tinygltf::Image* image, const int index, std::string*, std::string*, int, int,
                  const unsigned char* bytes, int size, void* user) {
  if (!image->uri.empty() || bytes == nullptr || size <= 0) return true;
  (*static_cast<ImageBytes*>(user))[index].assign(bytes, bytes + size);
  return true;
}

/// Typed, bounds-checked view of an accessor's elements.
class AccessorView {
 public:
  AccessorView(const tinygltf::Model& model, int index, const std::string& where) {
    if (index < 0 || static_cast<size_t>(index) >= model.accessors.size())
      throw InvalidInputError(where + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& a = model.accessors[static_cast<size_t>(index)];
    if (a.sparse.isSparse || a.bufferView < 0)
      throw UnsupportedError(where +
                             ": sparse accessors are not supported; re-export without "
                             "sparse storage");
    if (static_cast<size_t>(a.bufferView) >= model.bufferViews.size())
      throw InvalidInputError(where + ": bufferView " + std::to_string(a.bufferView) +
                              " does not exist");
    const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(a.bufferView)];
    if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model.buffers.size())
      throw InvalidInputError(where + ": buffer " + std::to_string(view.buffer) +
                              " does not exist");
    const std::vector<unsigned char>& buffer = model.buffers[static_cast<size_t>(view.buffer)].data;
    const int componentSize =
        tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
    components_ = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
    if (componentSize <= 0 || components_ <= 0)
      throw InvalidInputError(where + ": unknown accessor component type " +
                              std::to_string(a.componentType));
    const size_t elementSize = static_cast<size_t>(componentSize * components_);
    stride_ = view.byteStride != 0 ? view.byteStride : elementSize;
    count_ = a.count;
    componentType_ = a.componentType;
    normalized_ = a.normalized;
    const bool viewFits =
        view.byteOffset <= buffer.size() && view.byteLength <= buffer.size() - view.byteOffset;
    const bool elementsFit =
        count_ == 0 || (stride_ >= elementSize && a.byteOffset <= view.byteLength &&
                        (count_ - 1) <= (view.byteLength - a.byteOffset) / stride_ &&
                        a.byteOffset + (count_ - 1) * stride_ + elementSize <= view.byteLength);
    if (!viewFits || !elementsFit)
      throw InvalidInputError(where + ": accessor " + std::to_string(index) +
                              " reaches past the end of its buffer; the file is truncated or "
                              "corrupt, re-export it");
    data_ = buffer.data() + view.byteOffset + a.byteOffset;
  }

  size_t count() const { return count_; }
  int components() const { return components_; }
  int componentType() const { return componentType_; }

  /// Component c of element i, converted to double (normalized integers mapped to [0,1]/[-1,1]).
  double get(size_t i, int c) const {
    const unsigned char* p = data_ + i * stride_;
    switch (componentType_) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return as<float>(p, c, 1.0);
      case TINYGLTF_COMPONENT_TYPE_DOUBLE:
        return as<double>(p, c, 1.0);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return as<uint8_t>(p, c, 255.0);
      case TINYGLTF_COMPONENT_TYPE_BYTE:
        return as<int8_t>(p, c, 127.0);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return as<uint16_t>(p, c, 65535.0);
      case TINYGLTF_COMPONENT_TYPE_SHORT:
        return as<int16_t>(p, c, 32767.0);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return as<uint32_t>(p, c, 4294967295.0);
      case TINYGLTF_COMPONENT_TYPE_INT:
        return as<int32_t>(p, c, 2147483647.0);
      default:
        return 0.0;
    }
  }

 private:
  template <typename T>
  double as(const unsigned char* p, int c, double normalizer) const {
    T value;
    std::memcpy(&value, p + static_cast<size_t>(c) * sizeof(T), sizeof(T));
    const auto x = static_cast<double>(value);
    return normalized_ ? std::max(x / normalizer, -1.0) : x;
  }

  const unsigned char* data_ = nullptr;
  size_t stride_ = 0;
  size_t count_ = 0;
  int components_ = 0;
  int componentType_ = 0;
  bool normalized_ = false;
};

Eigen::Matrix4d localTransform(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) return Eigen::Map<const Eigen::Matrix4d>(node.matrix.data());
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  if (node.translation.size() == 3)
    t.translate(Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]));
  if (node.rotation.size() == 4)
    t.rotate(
        Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2])
            .normalized());
  if (node.scale.size() == 3) t.scale(Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]));
  return t.matrix();
}

/// Triangle indices of a primitive (its index accessor, or 0..n-1 when it has none).
std::vector<uint32_t> primitiveIndices(const tinygltf::Model& model,
                                       const tinygltf::Primitive& primitive, size_t vertexCount,
                                       const std::string& where) {
  std::vector<uint32_t> indices;
  if (primitive.indices < 0) {
    indices.resize(vertexCount);
    for (size_t i = 0; i < vertexCount; ++i) indices[i] = static_cast<uint32_t>(i);
  } else {
    const AccessorView view(model, primitive.indices, where + " indices");
    const int type = view.componentType();
    if (view.components() != 1 || (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                   type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                                   type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
      throw InvalidInputError(where + ": indices must be unsigned byte/short/int scalars");
    indices.resize(view.count());
    for (size_t i = 0; i < view.count(); ++i) indices[i] = static_cast<uint32_t>(view.get(i, 0));
  }
  if (indices.size() % 3 != 0)
    throw InvalidInputError(where + ": " + std::to_string(indices.size()) +
                            " indices is not a multiple of 3; the triangle list is corrupt");
  for (size_t i = 0; i < indices.size(); ++i)
    if (indices[i] >= vertexCount)
      throw InvalidInputError(where + ": face " + std::to_string(i / 3) + " references vertex " +
                              std::to_string(indices[i]) + " but the primitive has " +
                              std::to_string(vertexCount) + " vertices; re-export the file");
  return indices;
}

int attribute(const tinygltf::Primitive& primitive, const std::string& name) {
  const auto it = primitive.attributes.find(name);
  return it == primitive.attributes.end() ? -1 : it->second;
}

void appendPrimitive(TexturedMesh& mesh, const tinygltf::Model& model,
                     const tinygltf::Primitive& primitive, const Eigen::Matrix4d& transform,
                     int uvSet, const std::string& where) {
  if (primitive.mode != -1 && primitive.mode != TINYGLTF_MODE_TRIANGLES)
    throw UnsupportedError(where + " has mode " + std::to_string(primitive.mode) +
                           " (points, lines, strips or fans); texgrad reads TRIANGLES only, "
                           "re-export with triangle lists");
  const int positionAccessor = attribute(primitive, "POSITION");
  const std::string uvName = "TEXCOORD_" + std::to_string(uvSet);
  const int uvAccessor = attribute(primitive, uvName);
  if (positionAccessor < 0) throw InvalidInputError(where + " has no POSITION attribute");
  if (uvAccessor < 0)
    throw InvalidInputError(where + " has no " + uvName +
                            (uvSet == 0 ? "; UV-unwrap the mesh and export it with texture "
                                          "coordinates"
                                        : "; choose a UV set every primitive has"));
  const AccessorView positions(model, positionAccessor, where + " POSITION");
  const AccessorView uvs(model, uvAccessor, where + " " + uvName);
  if (positions.components() != 3 || uvs.components() != 2 || positions.count() != uvs.count())
    throw InvalidInputError(where + ": POSITION must be VEC3 and " + uvName +
                            " VEC2 with the same count");
  const size_t base = mesh.positions.size();
  if (base + positions.count() > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
    throw UnsupportedError(where + ": more than 2^31 vertices in total");
  for (size_t i = 0; i < positions.count(); ++i) {
    const Eigen::Vector4d p(positions.get(i, 0), positions.get(i, 1), positions.get(i, 2), 1.0);
    mesh.positions.push_back((transform * p).head<3>());
    mesh.uvs.emplace_back(uvs.get(i, 0), 1.0 - uvs.get(i, 1));
  }
  // A mirroring transform reverses the winding (glTF 2.0 spec, "Transformations").
  const bool mirrored = transform.topLeftCorner<3, 3>().determinant() < 0.0;
  const std::vector<uint32_t> indices =
      primitiveIndices(model, primitive, positions.count(), where);
  for (size_t f = 0; f + 2 < indices.size(); f += 3) {
    Triangle t{static_cast<int32_t>(base + indices[f]), static_cast<int32_t>(base + indices[f + 1]),
               static_cast<int32_t>(base + indices[f + 2])};
    if (mirrored) std::swap(t[1], t[2]);
    mesh.triangles.push_back(t);
    mesh.uvTriangles.push_back(t);
  }
}

/// A material a primitive uses and the faces (triangles) the primitive added.
struct MaterialUse {
  int material = -1;
  size_t faces = 0;
};

class SceneCollector {
 public:
  SceneCollector(const tinygltf::Model& model, std::string file, int uvSet)
      : model_(model), file_(std::move(file)), uvSet_(uvSet), onPath_(model.nodes.size(), false) {}

  void visit(int node, const Eigen::Matrix4d& parent) {
    if (node < 0 || static_cast<size_t>(node) >= model_.nodes.size())
      throw InvalidInputError(file_ + ": node " + std::to_string(node) + " does not exist");
    if (onPath_[static_cast<size_t>(node)])
      throw InvalidInputError(file_ + ": node " + std::to_string(node) +
                              " is its own ancestor; the node hierarchy must be a tree");
    onPath_[static_cast<size_t>(node)] = true;
    const tinygltf::Node& n = model_.nodes[static_cast<size_t>(node)];
    const Eigen::Matrix4d world = parent * localTransform(n);
    if (n.mesh >= 0) addMesh(n.mesh, world);
    for (int child : n.children) visit(child, world);
    onPath_[static_cast<size_t>(node)] = false;
  }

  void addMesh(int index, const Eigen::Matrix4d& world) {
    if (static_cast<size_t>(index) >= model_.meshes.size())
      throw InvalidInputError(file_ + ": mesh " + std::to_string(index) + " does not exist");
    const tinygltf::Mesh& m = model_.meshes[static_cast<size_t>(index)];
    for (size_t p = 0; p < m.primitives.size(); ++p) {
      const std::string where = file_ + ": mesh " + std::to_string(index) + " ('" + m.name +
                                "') primitive " + std::to_string(p);
      const int material = m.primitives[p].material;
      if (material >= static_cast<int>(model_.materials.size()))
        throw InvalidInputError(where + " uses material " + std::to_string(material) +
                                " but the file has " + std::to_string(model_.materials.size()) +
                                " materials; the file is corrupt, re-export it");
      const size_t before = mesh_.faceCount();
      appendPrimitive(mesh_, model_, m.primitives[p], world, uvSet_, where);
      const size_t added = mesh_.faceCount() - before;
      mesh_.faceMaterial.insert(mesh_.faceMaterial.end(), added, std::max(material, -1));
      if (material >= 0) materials_.push_back({material, added});
    }
  }

  TexturedMesh& mesh() { return mesh_; }
  const std::vector<MaterialUse>& materials() const { return materials_; }

 private:
  const tinygltf::Model& model_;
  std::string file_;
  int uvSet_;
  std::vector<bool> onPath_;
  TexturedMesh mesh_;
  std::vector<MaterialUse> materials_;  ///< in primitive order
};

/// glTF sampler wrap code (glTF 2.0 spec, "Samplers") as a TextureWrap.
TextureWrap wrapOf(int code, const std::string& where) {
  switch (code) {
    case TINYGLTF_TEXTURE_WRAP_REPEAT:
      return TextureWrap::Repeat;
    case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT:
      return TextureWrap::MirroredRepeat;
    case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE:
      return TextureWrap::ClampToEdge;
    default:
      throw InvalidInputError(where + " has wrap mode " + std::to_string(code) +
                              ", not 10497 (REPEAT), 33648 (MIRRORED_REPEAT) or 33071 "
                              "(CLAMP_TO_EDGE); the file is corrupt, re-export it");
  }
}

/// Sets `ref`'s wrap modes from texture `texture`'s sampler (none: REPEAT, the glTF default).
void readSampler(TextureRef& ref, const tinygltf::Model& model, const tinygltf::Texture& texture,
                 const std::string& file) {
  if (texture.sampler < 0) return;
  const std::string where = file + ": sampler " + std::to_string(texture.sampler);
  if (static_cast<size_t>(texture.sampler) >= model.samplers.size())
    throw InvalidInputError(where + " does not exist; the file is corrupt, re-export it");
  const tinygltf::Sampler& sampler = model.samplers[static_cast<size_t>(texture.sampler)];
  ref.wrapU = wrapOf(sampler.wrapS, where);
  ref.wrapV = wrapOf(sampler.wrapT, where);
}

/// Adds the image of texture `textureIndex` to `slot`, used by material `use.material` on
/// `use.faces` faces. An image the slot already holds (same file or same embedded bytes) stays one
/// reference listing every material using it (its sampler is the first such material's);
/// different images mean several texture pages (readMeshTexture refuses them).
void addTexture(TexturedMesh& mesh, const tinygltf::Model& model, const ImageBytes& embedded,
                const std::filesystem::path& folder, const std::string& file, const char* slot,
                int textureIndex, const MaterialUse& use) {
  if (textureIndex < 0 || static_cast<size_t>(textureIndex) >= model.textures.size()) return;
  const tinygltf::Texture& texture = model.textures[static_cast<size_t>(textureIndex)];
  const int source = texture.source;
  if (source < 0 || static_cast<size_t>(source) >= model.images.size()) return;
  const tinygltf::Image& image = model.images[static_cast<size_t>(source)];
  TextureRef ref;
  ref.slot = slot;
  ref.origin = "image " + std::to_string(source);
  if (!image.uri.empty()) {
    ref.path = (folder / percentDecode(image.uri)).lexically_normal();
    ref.origin += " (URI '" + image.uri + "')";
  } else {
    const auto it = embedded.find(source);
    if (it == embedded.end()) return;
    ref.embedded = it->second;
    ref.mimeType = image.mimeType;
  }
  const auto material = static_cast<int32_t>(use.material);
  for (TextureRef& t : mesh.textures)
    if (t.slot == ref.slot && t.path == ref.path && t.embedded == ref.embedded) {
      t.faces += use.faces;
      if (std::find(t.materials.begin(), t.materials.end(), material) == t.materials.end())
        t.materials.push_back(material);
      return;
    }
  ref.faces = use.faces;
  ref.materials.push_back(material);
  readSampler(ref, model, texture, file);
  mesh.textures.push_back(std::move(ref));
}

/// Material names in file order ("material N" for an unnamed one).
std::vector<std::string> materialNames(const tinygltf::Model& model) {
  std::vector<std::string> names;
  for (size_t m = 0; m < model.materials.size(); ++m)
    names.push_back(model.materials[m].name.empty() ? "material " + std::to_string(m)
                                                    : model.materials[m].name);
  return names;
}

}  // namespace

TexturedMesh readGltf(const std::filesystem::path& path, int uvSet) {
  requireReadableFile(path);
  const std::string file = path.string();
  if (uvSet < 0)
    throw InvalidInputError(file + ": UV set " + std::to_string(uvSet) +
                            " does not exist; glTF names UV sets TEXCOORD_0, TEXCOORD_1, ...");
  ImageBytes embedded;
  const tinygltf::Model model = gltf::loadModel(path, captureImage, embedded);

  SceneCollector collector(model, file, uvSet);
  for (int root : sceneRoots(model)) collector.visit(root, Eigen::Matrix4d::Identity());
  TexturedMesh mesh = std::move(collector.mesh());
  mesh.materials = materialNames(model);

  const std::filesystem::path folder = std::filesystem::absolute(path).parent_path();
  for (const MaterialUse& use : collector.materials()) {
    const tinygltf::Material& m = model.materials[static_cast<size_t>(use.material)];
    const auto add = [&](const char* slot, int texture) {
      addTexture(mesh, model, embedded, folder, file, slot, texture, use);
    };
    add("baseColor", m.pbrMetallicRoughness.baseColorTexture.index);
    add("normal", m.normalTexture.index);
    add("emissive", m.emissiveTexture.index);
    add("metallicRoughness", m.pbrMetallicRoughness.metallicRoughnessTexture.index);
    add("occlusion", m.occlusionTexture.index);
  }
  for (TextureRef& t : mesh.textures) std::sort(t.materials.begin(), t.materials.end());
  validateMesh(mesh, file);
  mesh.sourcePath = path;
  return mesh;
}

}  // namespace texgrad
