// Writes textured meshes (OBJ + MTL) so procedural meshes can be inspected in any tool.
#pragma once

#include <filesystem>

#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Writes `mesh` as Wavefront OBJ with `vt` (v upward) and, if `texture` is not empty, an MTL
/// file next to it whose map_Kd names `texture` (relative to the OBJ's folder). Atomic.
void writeObj(const std::filesystem::path& path, const TexturedMesh& mesh,
              const std::filesystem::path& texture = {});

}  // namespace texgrad
