// Photo flags and the per-photo loop; see the header.
#include "photo_args.h"

#include <iostream>

#include "cli_common.h"
#include "texgrad/io/camera_reader.h"

namespace texgrad::cli {

void addPhotoOptions(CLI::App* cmd, PhotoArgs& args) {
  cmd->add_option("--cameras", args.cameras,
                  "Camera file: a COLMAP text model folder (cameras.txt + images.txt) or either "
                  "file, texgrad camera JSON (.json), or an OpenMVS scene (.mvs); see "
                  "docs/photos.md")
      ->required();
  cmd->add_option("--images", args.images, "Folder holding the photos the camera file names")
      ->required();
  cmd->add_option("--masks", args.masks,
                  "Folder of optional masks named like the photos (white = usable); photos "
                  "without a mask file are used whole");
  cmd->add_option("--depth-tolerance", args.options.depthTolerance,
                  "Depth-test slack as a fraction of the mesh's bounding-box diagonal: surfaces "
                  "closer than this behind another count as visible")
      ->default_val(ProjectionOptions{}.depthTolerance)
      ->check(nonNegativeValidator());
  cmd->add_option("--border-band", args.options.borderBand,
                  "Confidence ramps from 0 at a photo's border to full at this fraction of its "
                  "smaller side, so photo edges do not win")
      ->default_val(ProjectionOptions{}.borderBand)
      ->check(CLI::Range(0.0, 0.5));
}

std::vector<Camera> readPhotoCameras(const PhotoArgs& args) {
  args.options.validate();
  return readCameras(args.cameras, args.images);
}

int projectEachPhoto(const PhotoProjector& projector, const std::vector<Camera>& cameras,
                     const PhotoArgs& args, const ProgressCallback& progress, bool quiet,
                     const std::function<void(size_t, PhotoProjection&&)>& sink) {
  int kept = 0;
  for (size_t k = 0; k < cameras.size(); ++k) {
    reportProgress(progress, "project",
                   static_cast<double>(k) / static_cast<double>(cameras.size()));
    PhotoProjection view = projectPhotoFile(projector, cameras[k], args.masks);
    if (view.seenTexels == 0) {
      if (!quiet)
        std::cerr << "texgrad: warning: camera '" << cameras[k].name
                  << "' sees no texel of the mesh (behind it, facing away or aimed elsewhere); "
                     "skipped\n";
      continue;
    }
    ++kept;
    sink(k, std::move(view));
  }
  reportProgress(progress, "project", 1.0);
  return kept;
}

}  // namespace texgrad::cli
