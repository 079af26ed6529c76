// Camera files written from Camera values (COLMAP's text model, texgrad's camera JSON): round
// trips of the readers and synthetic reconstructions for tests.
#pragma once

#include <filesystem>
#include <vector>

#include "texgrad/io/camera.h"

namespace texgrad {

/// Writes COLMAP's text model into `folder` (created if needed): cameras.txt (one camera per
/// image, camera id = image id = index + 1), images.txt (quaternion and translation world ->
/// camera, an empty 2-D point line per image) and an empty points3D.txt, so COLMAP can load it.
/// A camera without distortion is written as PINHOLE; SimpleRadial and Radial as SIMPLE_RADIAL
/// and RADIAL when fx == fy, else as the OPENCV model with the same projection; OpenCV as OPENCV.
/// Numbers are written with 17 significant digits. Throws InvalidInputError for a non-finite
/// value or an empty or multi-line name, IoError when a file cannot be written.
void writeColmapText(const std::filesystem::path& folder, const std::vector<Camera>& cameras);

/// Writes texgrad's camera JSON (docs/photos.md): per camera file, width, height, K, R, t and the
/// distortion unless it is none. Same refusals as writeColmapText.
void writeCameraJson(const std::filesystem::path& path, const std::vector<Camera>& cameras);

}  // namespace texgrad
