// Camera file formats behind readCameraFile and the camera writers (private to the io module).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "texgrad/io/camera.h"

namespace texgrad::cameras {

/// How far RᵀR may be from the identity (largest entry) for R to count as a rotation: rounding in
/// files written with 6 significant digits stays well inside, a misread matrix does not.
inline constexpr double kRotationTolerance = 1e-4;

/// Reads COLMAP's text model (docs/photos.md): cameras.txt and images.txt.
std::vector<Camera> readColmapText(const std::filesystem::path& camerasTxt,
                                   const std::filesystem::path& imagesTxt);

/// Reads texgrad's camera JSON (docs/photos.md).
std::vector<Camera> readCameraJson(const std::filesystem::path& path);

/// Reads OpenMVS's interface file (.mvs, archive versions 0 to 7): the calibrated images.
std::vector<Camera> readOpenMvs(const std::filesystem::path& path);

/// A whole file as bytes; throws IoError naming it when it cannot be read.
std::string readWholeFile(const std::filesystem::path& path);

/// Writes `text` to `path` atomically (writeAtomically); throws IoError naming it on failure.
void writeTextFile(const std::filesystem::path& path, const std::string& text);

/// True if R is a rotation to kRotationTolerance (orthonormal, determinant +1).
bool isRotation(const Eigen::Matrix3d& R);

/// The shortest decimal text that reads back as exactly `value`.
std::string formatNumber(double value);

/// What is wrong with an image name, or empty when it is fine: names are non-empty, hold no
/// control characters (so messages stay one line) and neither start nor end with a blank.
std::string nameProblem(std::string_view name);

/// Throws InvalidInputError (prefixed by `where`) unless the camera can be written and read back:
/// a name without nameProblem, a positive size and focal lengths, finite
/// numbers, a rotation R.
void checkWritable(const Camera& camera, const std::string& where);

}  // namespace texgrad::cameras
