// Per-face tangent vector fields for line integral convolution (`texgrad lic`, paper §7.4): the
// .vf field file, principal curvature directions estimated on the mesh, and conversion to texels.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// How the per-face vectors of a field are expressed.
enum class FieldBasis : uint8_t {
  /// Two coefficients (a, b) per face: u = a (v1 - v0) + b (v2 - v0) on the face's corners. The
  /// same coefficients name the same tangent vector in 3-D and in UV, so no projection is needed.
  Intrinsic,
  /// A 3-D vector per face (mesh units); its component along the face normal is dropped.
  Extrinsic,
};

/// One tangent vector per face.
struct FaceVectorField {
  FieldBasis basis = FieldBasis::Extrinsic;
  std::vector<Eigen::Vector3d> vectors;  ///< per face; Intrinsic fields store (a, b, 0)
};

/// Reads a field file: a little-endian int32 count, then count x dim little-endian float64 values
/// (dim 2 for Intrinsic, 3 for Extrinsic), nothing else. Throws IoError if the file cannot be
/// read, InvalidInputError (naming the file) if its size does not match `basis`, if the count is
/// not `faceCount`, or if a value is not finite.
FaceVectorField readFaceVectorField(const std::filesystem::path& path, FieldBasis basis,
                                    size_t faceCount);

/// Writes a field in the format readFaceVectorField reads (atomically); throws IoError.
void writeFaceVectorField(const std::filesystem::path& path, const FaceVectorField& field);

/// The field as 3-D vectors (Extrinsic) on `mesh`'s faces: an Intrinsic field's (a, b) becomes
/// a (v1 - v0) + b (v2 - v0). Pieces of a face cut at tile borders (wrapTextureCoordinates) keep
/// the face's 3-D vector but not its edges, so a field follows them in this form. Throws
/// InvalidInputError if the face counts differ.
FaceVectorField extrinsicField(const TexturedMesh& mesh, const FaceVectorField& field);

/// The field as vectors in texel coordinates (grid units), one per face. Extrinsic vectors are
/// projected onto the face plane by least squares through the face's Jacobian. Faces with zero UV
/// area or a degenerate 3-D triangle get zero. Throws InvalidInputError if the face counts differ.
std::vector<Eigen::Vector2d> fieldInTexelCoordinates(const TexturedMesh& mesh,
                                                     const TexelGrid& grid,
                                                     const FaceVectorField& field);

/// Which principal curvature direction a curvature field follows.
enum class CurvatureDirection : uint8_t {
  Major,  ///< direction of the principal curvature of larger magnitude (around a cylinder)
  Minor,  ///< direction of the principal curvature of smaller magnitude (along a cylinder)
};

/// Options of principalCurvatures.
struct CurvatureOptions {
  /// Rounds of averaging the per-face shape operator with its vertex-ring neighbours (in 3-D)
  /// before the eigen-decomposition; each round widens the estimate by about one face ring.
  int smoothingRounds = 2;
  /// Throws InvalidInputError naming the bad field.
  void validate() const;
};

/// Per-face principal curvatures and directions of the mesh (welded positions).
struct PrincipalCurvatures {
  /// Per face, the principal curvatures with |kMajor| >= |kMinor|, in 1 / mesh units; positive
  /// where the surface bends away from its normal side (a sphere with outward normals has
  /// k = 1 / radius). Ordering by magnitude makes the directions independent of orientation.
  std::vector<double> kMajor, kMinor;
  /// Per face, unit 3-D directions in the face plane (zero for faces with a degenerate triangle).
  std::vector<Eigen::Vector3d> dirMajor, dirMinor;
};

/// Estimates the shape operator per face from the differences of vertex normals (Max 1999
/// weights) along its edges (least squares over the three edges, Rusinkiewicz 2004), smooths it
/// (CurvatureOptions) and decomposes it.
PrincipalCurvatures principalCurvatures(const TexturedMesh& mesh,
                                        const CurvatureOptions& options = {});

/// Extrinsic field of paper §7.4 / Fig. 18: the chosen principal direction scaled by
/// |k_major - k_minor| (so umbilic regions, where the direction is undefined, get short vectors).
FaceVectorField curvatureField(const TexturedMesh& mesh, CurvatureDirection direction,
                               const CurvatureOptions& options = {});

}  // namespace texgrad
