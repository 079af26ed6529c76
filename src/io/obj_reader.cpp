// Wavefront OBJ input (through tinyobjloader): polygons fanned into triangles, separate vertex
// and UV index spaces kept as in the file, the MTL's colour and normal maps as texture refs.
#include <tiny_obj_loader.h>

#include <algorithm>
#include <string>

#include "obj_lines.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad {
namespace {

/// Resolves a texture name from an MTL file (relative to the OBJ's folder, where tinyobjloader
/// looks for the MTL) to an absolute path; Windows separators are accepted.
std::filesystem::path resolveTexture(const std::filesystem::path& objPath, std::string name) {
  std::replace(name.begin(), name.end(), '\\', '/');
  const std::filesystem::path folder = std::filesystem::absolute(objPath).parent_path();
  return (folder / name).lexically_normal();
}

/// Materials in the order faces first use them, then any unused ones (so the texture of the
/// material actually applied wins when several define one).
std::vector<size_t> materialOrder(const std::vector<tinyobj::shape_t>& shapes,
                                  size_t materialCount) {
  std::vector<size_t> order;
  std::vector<bool> seen(materialCount, false);
  const auto add = [&](int id) {
    if (id < 0 || static_cast<size_t>(id) >= materialCount || seen[static_cast<size_t>(id)]) return;
    seen[static_cast<size_t>(id)] = true;
    order.push_back(static_cast<size_t>(id));
  };
  for (const auto& shape : shapes)
    for (int id : shape.mesh.material_ids) add(id);
  for (size_t id = 0; id < materialCount; ++id) add(static_cast<int>(id));
  return order;
}

/// True if two references name the same image (same file, or the same embedded bytes).
bool sameImage(const TextureRef& a, const TextureRef& b) {
  return a.path == b.path && a.embedded == b.embedded;
}

/// Adds the slot textures of the materials faces use, each distinct image once with the
/// materials using it (several images are several texture pages: texture_pages.h); unused
/// materials only fill empty slots.
void addTextures(TexturedMesh& mesh, const std::filesystem::path& path,
                 const std::vector<tinyobj::shape_t>& shapes,
                 const std::vector<tinyobj::material_t>& materials) {
  std::vector<size_t> faces(materials.size(), 0);  // triangles per material (faces are fanned)
  for (const auto& shape : shapes)
    for (size_t f = 0; f < shape.mesh.material_ids.size(); ++f) {
      const int id = shape.mesh.material_ids[f];
      const size_t corners =
          f < shape.mesh.num_face_vertices.size() ? shape.mesh.num_face_vertices[f] : 0;
      if (id >= 0 && static_cast<size_t>(id) < materials.size() && corners >= 3)
        faces[static_cast<size_t>(id)] += corners - 2;
    }
  const auto addSlot = [&](const char* slot, const char* keyword, const std::string& name,
                           const tinyobj::texture_option_t& options, const tinyobj::material_t& m,
                           size_t id, size_t materialFaces) {
    if (name.empty()) return;
    TextureRef ref;
    ref.slot = slot;
    ref.path = resolveTexture(path, name);
    ref.origin = "material '" + m.name + "' (" + keyword + " '" + name + "')";
    ref.faces = materialFaces;
    ref.materials = {static_cast<int32_t>(id)};
    // `-clamp on`: the edge texels extend (MTL's only wrap option; it applies to both axes).
    const TextureWrap wrap = options.clamp ? TextureWrap::ClampToEdge : TextureWrap::Repeat;
    ref.wrapU = ref.wrapV = wrap;
    for (TextureRef& t : mesh.textures)
      if (t.slot == ref.slot && sameImage(t, ref)) {
        t.faces += materialFaces;
        t.materials.push_back(ref.materials.front());
        return;
      }
    if (materialFaces == 0 && mesh.texture(slot) != nullptr) return;
    mesh.textures.push_back(std::move(ref));
  };
  for (size_t id : materialOrder(shapes, materials.size())) {
    const tinyobj::material_t& m = materials[id];
    addSlot("baseColor", "map_Kd", m.diffuse_texname, m.diffuse_texopt, m, id, faces[id]);
    addSlot("normal", "norm", m.normal_texname, m.normal_texopt, m, id, faces[id]);
    if (m.normal_texname.empty())
      addSlot("normal", "bump", m.bump_texname, m.bump_texopt, m, id, faces[id]);
  }
}

/// The material of polygon `f` of `shape` (an index into the file's materials), -1 if none.
int32_t materialOf(const tinyobj::shape_t& shape, size_t f, size_t materialCount) {
  if (f >= shape.mesh.material_ids.size()) return -1;
  const int id = shape.mesh.material_ids[f];
  return id >= 0 && static_cast<size_t>(id) < materialCount ? static_cast<int32_t>(id) : -1;
}

/// Checks one face corner and returns its (vertex, uv) indices.
std::pair<int32_t, int32_t> corner(const tinyobj::index_t& index, size_t line, size_t k,
                                   size_t vertexCount, size_t uvCount,
                                   const std::filesystem::path& path) {
  const std::string where =
      path.string() + " line " + std::to_string(line) + ": face corner " + std::to_string(k);
  if (index.vertex_index < 0 || static_cast<size_t>(index.vertex_index) >= vertexCount)
    throw InvalidInputError(where + " references vertex " + std::to_string(index.vertex_index) +
                            " but there are " + std::to_string(vertexCount) +
                            " vertices (0-based); fix the 'f' line or re-export the mesh");
  if (index.texcoord_index < 0 && uvCount == 0)
    throw InvalidInputError(path.string() +
                            ": the mesh has no texture coordinates ('vt' lines); UV-unwrap it "
                            "and export it with UVs");
  if (index.texcoord_index < 0)
    throw InvalidInputError(where +
                            " has no texture coordinate; write faces as 'f v/vt' "
                            "(every face must be UV-mapped)");
  if (static_cast<size_t>(index.texcoord_index) >= uvCount)
    throw InvalidInputError(where + " references texture coordinate " +
                            std::to_string(index.texcoord_index) + " but there are " +
                            std::to_string(uvCount) +
                            " (0-based); fix the 'f' line or re-export the mesh");
  return {index.vertex_index, index.texcoord_index};
}

}  // namespace

TexturedMesh readObj(const std::filesystem::path& path) {
  requireReadableFile(path);
  const obj::ObjLines lines = obj::scanObjLines(path);
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;  // fanned below, after the indices are checked
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromFile(path.string(), config)) {
    std::string why = reader.Error();  // tinyobjloader's text may span lines: keep it on one
    std::replace(why.begin(), why.end(), '\n', ' ');
    while (!why.empty() && why.back() == ' ') why.pop_back();
    throw InvalidInputError(path.string() + ": not a readable OBJ file (" + why +
                            "); check that it is a Wavefront OBJ");
  }

  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  TexturedMesh mesh;
  const size_t vertexCount = attrib.vertices.size() / 3;
  const size_t uvCount = attrib.texcoords.size() / 2;
  mesh.positions.reserve(vertexCount);
  for (size_t v = 0; v < vertexCount; ++v)
    mesh.positions.emplace_back(static_cast<double>(attrib.vertices[3 * v]),
                                static_cast<double>(attrib.vertices[3 * v + 1]),
                                static_cast<double>(attrib.vertices[3 * v + 2]));
  mesh.uvs.reserve(uvCount);
  for (size_t t = 0; t < uvCount; ++t)
    mesh.uvs.emplace_back(static_cast<double>(attrib.texcoords[2 * t]),
                          static_cast<double>(attrib.texcoords[2 * t + 1]));

  size_t face = 0;
  std::vector<std::pair<int32_t, int32_t>> corners;
  const size_t materialCount = reader.GetMaterials().size();
  for (const tinyobj::material_t& m : reader.GetMaterials()) mesh.materials.push_back(m.name);
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    size_t offset = 0;
    const size_t firstFace = face;
    for (unsigned char n : shape.mesh.num_face_vertices) {
      // The line scan refused faces with fewer than 3 corners, so tinyobjloader dropped none
      // and faces map one-to-one onto 'f' lines.
      const size_t line = face < lines.faceLines.size() ? lines.faceLines[face] : 0;
      if (offset + n > shape.mesh.indices.size())
        throw UnsupportedError(path.string() + ": face " + std::to_string(face) +
                               " has more than 255 corners; triangulate it before reading");
      corners.clear();
      for (size_t k = 0; k < n; ++k)
        corners.push_back(
            corner(shape.mesh.indices[offset + k], line, k, vertexCount, uvCount, path));
      const int32_t material = materialOf(shape, face - firstFace, materialCount);
      for (size_t k = 1; k + 1 < n; ++k) {
        mesh.triangles.push_back({corners[0].first, corners[k].first, corners[k + 1].first});
        mesh.uvTriangles.push_back({corners[0].second, corners[k].second, corners[k + 1].second});
        if (materialCount > 0) mesh.faceMaterial.push_back(material);
      }
      offset += n;
      ++face;
    }
  }
  addTextures(mesh, path, reader.GetShapes(), reader.GetMaterials());
  mesh.missingFiles = lines.missingFiles;
  validateMesh(mesh, path.string());
  mesh.sourcePath = path;
  return mesh;
}

}  // namespace texgrad
