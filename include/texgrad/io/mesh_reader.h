// Reads textured meshes (OBJ+MTL, PLY, glTF/GLB) into a TexturedMesh, welding split vertices.
#pragma once

#include <filesystem>

#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Options for readMesh; defaults weld only exactly coincident positions.
struct MeshReadOptions {
  /// Positions closer than this (in model units) are welded into one 3-D vertex; 0 = exact only.
  double weldTolerance = 0.0;
  /// UV set to read: glTF's TEXCOORD_N (every primitive must have it); OBJ and PLY have only 0.
  int uvSet = 0;
  /// Checks the options; throws InvalidInputError naming the bad field.
  void validate() const;
};

/// Reads a mesh by extension (.obj, .ply, .gltf, .glb), triangulating polygons and welding
/// positions so seams can be recovered. Throws IoError / InvalidInputError naming the file and
/// the element (face or vertex index) when the file is unreadable, truncated or inconsistent
/// (index out of range, NaN/Inf coordinate, no texture coordinates).
TexturedMesh readMesh(const std::filesystem::path& path, const MeshReadOptions& options = {});

/// Reads a Wavefront OBJ (and its MTL's diffuse map, if any).
TexturedMesh readObj(const std::filesystem::path& path);
/// Reads an ASCII or binary PLY with per-corner `texcoord` lists or per-vertex u/v, s/t,
/// texture_u/texture_v properties.
TexturedMesh readPly(const std::filesystem::path& path);
/// Reads a glTF 2.0 (.gltf) or binary (.glb) asset: all mesh primitives with node transforms
/// applied, UV set TEXCOORD_`uvSet`, the materials (faceMaterial from each primitive's), and the
/// base-colour/normal/emissive/metallicRoughness/occlusion images (one TextureRef per image and
/// slot, listing its materials, wrap modes from its sampler). A primitive without TEXCOORD_`uvSet`
/// throws InvalidInputError naming the file, mesh, primitive and set.
TexturedMesh readGltf(const std::filesystem::path& path, int uvSet = 0);

/// Merges 3-D vertices whose positions lie within `tolerance` (0: bit-identical) and remaps
/// triangles; UV indices are untouched. Returns the number of vertices removed.
size_t weldPositions(TexturedMesh& mesh, double tolerance);

/// Checks indices (faces, face materials), finiteness and that UVs exist; throws InvalidInputError
/// naming `what` (usually the file) and the first bad element.
void validateMesh(const TexturedMesh& mesh, const std::string& what);

/// Throws IoError "cannot open FILE: reason; ..." unless `path` is a file that can be opened
/// for reading (the readers call it first so a missing file is never reported as bad content).
void requireReadableFile(const std::filesystem::path& path);

}  // namespace texgrad
