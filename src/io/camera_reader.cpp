// readCameraFile: the camera file formats by path; resolveCameraImages: each photo found and its
// size checked from its header.
#include "texgrad/io/camera_reader.h"

#include "camera_formats.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"

namespace texgrad {
namespace {

/// COLMAP's text model in `folder`; points at COLMAP's converter when only the binary one is there.
std::vector<Camera> readColmapFolder(const std::filesystem::path& folder) {
  const std::filesystem::path camerasTxt = folder / "cameras.txt",
                              imagesTxt = folder / "images.txt";
  std::error_code ec;
  if (!std::filesystem::exists(camerasTxt, ec) && !std::filesystem::exists(imagesTxt, ec)) {
    const bool binary = std::filesystem::exists(folder / "cameras.bin", ec);
    throw IoError(folder.string() + " holds no COLMAP text model (cameras.txt and images.txt)" +
                  (binary ? "; it holds the binary one: convert it with colmap model_converter "
                            "--input_path F --output_path F --output_type TXT"
                          : "; pass the folder of a COLMAP model (e.g. sparse/0) or a .json "
                            "camera file"));
  }
  return cameras::readColmapText(camerasTxt, imagesTxt);
}

/// Width and height from an image file's header (no pixels are decoded).
std::pair<int, int> imageSize(const std::filesystem::path& path, const std::string& where) {
  try {
    return readImageSize(path);
  } catch (const Error& e) {
    throw InvalidInputError(where + "cannot read the photo's header (" + std::string(e.what()) +
                            "); check that it is an image file");
  }
}

/// The cameras of `path` by its kind, possibly none.
std::vector<Camera> readByKind(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw IoError("cannot open " + path.string() + ": no such file or folder; check the path");
  if (std::filesystem::is_directory(path, ec)) return readColmapFolder(path);
  const std::string file = path.filename().string();
  if (file == "cameras.txt" || file == "images.txt") return readColmapFolder(path.parent_path());
  if (path.extension() == ".json") return cameras::readCameraJson(path);
  if (path.extension() == ".mvs") return cameras::readOpenMvs(path);
  throw UnsupportedError(path.string() +
                         ": unknown camera file; pass a COLMAP text model (its folder, "
                         "cameras.txt or images.txt), a .json camera file (docs/photos.md) or an "
                         "OpenMVS .mvs scene");
}

}  // namespace

std::vector<Camera> readCameraFile(const std::filesystem::path& path) {
  std::vector<Camera> cameras = readByKind(path);
  if (cameras.empty())
    throw InvalidInputError(path.string() +
                            ": no calibrated photo (the file lists no image with a pose); pass "
                            "the camera file of a finished reconstruction");
  return cameras;
}

void resolveCameraImages(std::vector<Camera>& cameras, const std::filesystem::path& imagesDir,
                         const std::filesystem::path& cameraFile) {
  for (Camera& camera : cameras) {
    camera.imagePath = imagesDir / camera.name;
    const std::string where =
        cameraFile.string() + ": image '" + camera.name + "' (" + camera.imagePath.string() + "): ";
    std::error_code ec;
    if (!std::filesystem::is_regular_file(camera.imagePath, ec))
      throw IoError(where +
                    "no such file; pass the folder holding the photos as the images "
                    "folder, or remove the image from the camera file");
    const auto [width, height] = imageSize(camera.imagePath, where);
    if (width != camera.width || height != camera.height)
      throw InvalidInputError(where + "the photo is " + std::to_string(width) + " x " +
                              std::to_string(height) + " pixels but its camera is " +
                              std::to_string(camera.width) + " x " + std::to_string(camera.height) +
                              "; pass the photos the cameras were calibrated on (undistorted "
                              "photos need the undistorted model)");
  }
}

std::vector<Camera> readCameras(const std::filesystem::path& path,
                                const std::filesystem::path& imagesDir) {
  std::vector<Camera> cameras = readCameraFile(path);
  resolveCameraImages(cameras, imagesDir, path);
  return cameras;
}

}  // namespace texgrad
