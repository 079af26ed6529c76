// Photos onto the atlas (`texgrad project`, `texgrad texture`): each calibrated photo becomes a
// partial texture and a confidence map, the pair stitchPartials takes (stitch.h).
#pragma once

#include <filesystem>
#include <memory>

#include "texgrad/apps/texel_domain.h"
#include "texgrad/apps/texel_surface_points.h"
#include "texgrad/io/camera.h"
#include "texgrad/io/image.h"

namespace texgrad {

/// How texels are seen in a photo and how much each view is trusted.
///
/// A texel is *seen* when its surface point (texelSurfacePoints) lies in front of the camera,
/// its face is front-facing (geometric normal towards the camera centre), its distorted pixel
/// lies inside the image and inside the lens model's monotonic range, the mask (if any) is not
/// black there, and the depth test passes: the mesh is rasterised in the camera's pinhole image
/// plane (one depth sample per photo pixel over the rectangle the seen texels span, coarser if a
/// side would exceed maxDepthSide samples); the face nearest the camera at the texel's pinhole
/// pixel is either the texel's own face or a face whose plane, along the texel's viewing ray,
/// lies no more than depthTolerance x (bounding-box diagonal) in front of the texel's point.
///
/// Confidence of a seen texel (0 for the others):
///   c = cos(theta) * min(1, a) * smoothstep(d / (borderBand * min(W, H))) * m
/// theta = angle between the smooth surface normal and the direction to the camera;
/// a = photo pixels per texel (|det| of the 2 x 2 Jacobian of the pinhole pixel position with
/// respect to texel coordinates): a view that resolves the texel with at least one pixel gets
/// full weight, a coarser one loses weight with its pixel area;
/// d = distance of the pixel to the nearest image border (photo edges do not win);
/// m = mask value there (mean of its colour channels, 1 without a mask).
struct ProjectionOptions {
  /// Depth-test slack as a fraction of the mesh's bounding-box diagonal.
  double depthTolerance = 1e-2;
  /// Width of the image-border ramp as a fraction of the photo's smaller side.
  double borderBand = 0.05;
  /// Largest side of the z-buffer in samples (memory: 8 bytes per sample).
  int maxDepthSide = 4096;
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// A photo projected onto the texture: the pair `texgrad stitch --partials/--confidence` takes.
struct PhotoProjection {
  Image partial;           ///< texture size, the photo's colour channels (0 where unseen)
  Image confidence;        ///< texture size, one channel in [0, 1]
  int64_t seenTexels = 0;  ///< unknowns with confidence > 0
};

/// Projects photos onto one TexelDomain. Construction finds every texel's surface point and
/// normal once; project() then handles one photo at a time (only the photo, its z-buffer and the
/// two output images are in memory). Keeps a reference to the domain.
class PhotoProjector {
 public:
  explicit PhotoProjector(const TexelDomain& domain, const ProjectionOptions& options = {});
  /// Projects `photo` (texel order as readImage gives it, camera.width x camera.height) taken by
  /// `camera`; `mask` (same size, white = usable) may be null. Throws InvalidInputError when a
  /// size does not match the camera.
  PhotoProjection project(const Camera& camera, const Image& photo,
                          const Image* mask = nullptr) const;
  /// Surface points of the unknowns (what project() samples).
  const TexelSurfacePoints& points() const { return points_; }

 private:
  const TexelDomain& domain_;
  ProjectionOptions options_;
  TexelSurfacePoints points_;
  Eigen::MatrixX3d normals_;
  double diagonal_ = 0.0;
};

/// Reads `camera`'s photo (camera.imagePath) and, when `masksDir` is not empty and holds a file
/// named like the photo (camera.name), that mask, then projects the photo: one photo in memory.
PhotoProjection projectPhotoFile(const PhotoProjector& projector, const Camera& camera,
                                 const std::filesystem::path& masksDir);

/// Per texel, the view with the highest confidence so far (`texgrad texture --select best`):
/// fed one projection at a time, it holds the composite texture and its segment image (channel
/// 0 = view index + 1, 0 = unseen), the pair stitchComposite takes.
struct BestViewComposite {
  Image composite;   ///< colour of the best view per texel
  Image segments;    ///< view index + 1 of the best view per texel, 0 where no view sees it
  Image confidence;  ///< the best view's confidence
  /// Takes `view` (numbered `viewIndex`) where its confidence beats the best so far.
  void add(const PhotoProjection& view, int viewIndex);
};

}  // namespace texgrad
