// Flags and the per-photo loop shared by `texgrad project` and `texgrad texture`.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

#include "texgrad/apps/photo_projection.h"
#include "texgrad/io/camera.h"

namespace texgrad::cli {

/// --cameras, --images, --masks and the projection options.
struct PhotoArgs {
  std::string cameras, images, masks;
  ProjectionOptions options;
};

/// Registers the photo flags on `cmd`.
void addPhotoOptions(CLI::App* cmd, PhotoArgs& args);

/// Reads the camera file and checks every photo (readCameras); throws before any heavy work.
std::vector<Camera> readPhotoCameras(const PhotoArgs& args);

/// Projects every camera's photo in turn (one photo in memory) and calls `sink` with the
/// camera's index and its projection for cameras that see some texel; a camera that sees none
/// gets a warning line on stderr (unless quiet) and is skipped. Reports stage "project" to
/// `progress`. Returns the number of views kept.
int projectEachPhoto(const PhotoProjector& projector, const std::vector<Camera>& cameras,
                     const PhotoArgs& args, const ProgressCallback& progress, bool quiet,
                     const std::function<void(size_t, PhotoProjection&&)>& sink);

}  // namespace texgrad::cli
