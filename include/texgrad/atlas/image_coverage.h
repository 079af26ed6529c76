// Whether a mesh's atlas reaches the image at all: the check every command makes before it builds
// a texel grid, so UVs that lie wholly outside [0, 1]^2 are refused instead of solved to nothing.
#pragma once

#include <Eigen/Core>

#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Range of the texture coordinates of a mesh's face corners.
struct UvRange {
  Eigen::Vector2d min = Eigen::Vector2d::Zero();  ///< smallest (u, v)
  Eigen::Vector2d max = Eigen::Vector2d::Zero();  ///< largest (u, v)
};

/// Range of the UVs the faces use; zero if the mesh has no face.
UvRange faceUvRange(const TexturedMesh& mesh);

/// UV area (in units of the image, whose area is 1) that the faces cover inside the image
/// [0, 1]^2; stacked faces count once each. 0 exactly when no face overlaps the image's interior (a
/// face that only touches its edge adds nothing).
double uvAreaInImage(const TexturedMesh& mesh);

/// Throws InvalidInputError naming the UV range when the mesh's UV triangles cover no part of
/// the image [0, 1]^2 (wrapped or tiled UVs, e.g. all in [1, 2]): no texel of the output would
/// change. Meshes partly outside the image pass (the texel grid extends past the image).
void requireUvsInImage(const TexturedMesh& mesh);

}  // namespace texgrad
