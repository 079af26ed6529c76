// Camera files of photogrammetry pipelines (COLMAP's text model, texgrad's camera JSON, OpenMVS's
// .mvs) read into Camera values, with each photo found under an images folder and its size checked.
#pragma once

#include <filesystem>
#include <vector>

#include "texgrad/io/camera.h"

namespace texgrad {

/// Reads a camera file without looking at the photos (Camera::imagePath stays empty).
///
/// `path` is a folder holding COLMAP's text model (cameras.txt + images.txt), either of those two
/// files (the other is taken from the same folder), a `.json` file in texgrad's camera JSON, or
/// an OpenMVS scene `.mvs` (its calibrated images; conventions in docs/photos.md). Cameras come in
/// the file's image order. Throws InvalidInputError for a file without any camera and naming the
/// file and line (or element) of malformed, non-finite or inconsistent entries, UnsupportedError
/// for camera models texgrad does not apply (naming the model), IoError when a file cannot be
/// read.
std::vector<Camera> readCameraFile(const std::filesystem::path& path);

/// Sets each camera's imagePath to imagesDir / name and checks that the photo exists and that
/// its size (read from the file's header only) is the camera's; throws IoError or
/// InvalidInputError naming the camera file, the image and what to do.
void resolveCameraImages(std::vector<Camera>& cameras, const std::filesystem::path& imagesDir,
                         const std::filesystem::path& cameraFile);

/// readCameraFile, then resolveCameraImages: the cameras of a reconstruction with their photos.
std::vector<Camera> readCameras(const std::filesystem::path& path,
                                const std::filesystem::path& imagesDir);

}  // namespace texgrad
