// Photo projection onto the texel grid; the visibility rule and the confidence formula are in the
// header.
#include "texgrad/apps/photo_projection.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "depth_buffer.h"
#include "texgrad/apps/surface_normals.h"
#include "texgrad/core/error.h"
#include "texgrad/core/path_exists.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/image_sampling.h"

namespace texgrad {
namespace {

/// Near clipping plane of the z-buffer as a fraction of the scene's diagonal: only geometry
/// this close to the camera centre is cut away (and texels there are not seen).
constexpr double kNearFraction = 1e-6;

/// Where one texel's surface point lands in a photo, before the depth test.
struct Landing {
  Eigen::Vector3d cameraPoint;  ///< camera coordinates
  Eigen::Vector2d pixel;        ///< distorted pixel position (COLMAP convention)
  Eigen::Vector2d pinhole;      ///< undistorted pixel position (z-buffer plane)
};

double smoothstep(double x) {
  const double t = std::clamp(x, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

/// False where the radial distortion r (1 + k1 r^2 + k2 r^4) stops growing with r: points beyond
/// would fold back into the image.
bool inMonotonicRange(const LensDistortion& d, const Eigen::Vector2d& normalised) {
  if (d.model == DistortionModel::None) return true;
  const double r2 = normalised.squaredNorm();
  return 1.0 + 3.0 * d.k1 * r2 + 5.0 * d.k2 * r2 * r2 > 0.0;
}

/// Continuous texel coordinates in a texel-order image of a COLMAP pixel position.
Eigen::Vector2d photoTexel(const Eigen::Vector2d& pixel, int height) {
  return {pixel.x() - 0.5, height - pixel.y() - 0.5};
}

/// Colour channels of a photo (an alpha channel is dropped).
int colourChannels(const Image& photo) {
  return photo.channels == 2 || photo.channels == 4 ? photo.channels - 1 : photo.channels;
}

void checkPhotoSize(const Camera& camera, const Image& image, const std::string& what) {
  if (image.width != camera.width || image.height != camera.height)
    throw InvalidInputError(
        what + " of camera '" + camera.name + "' is " + std::to_string(image.width) + "x" +
        std::to_string(image.height) + " but the camera says " + std::to_string(camera.width) +
        "x" + std::to_string(camera.height) + "; give the photos the camera file was made from");
}

}  // namespace

void ProjectionOptions::validate() const {
  if (!(depthTolerance >= 0.0) || !std::isfinite(depthTolerance))
    throw InvalidInputError("depthTolerance must be a finite number >= 0");
  if (!(borderBand >= 0.0 && borderBand <= 0.5))
    throw InvalidInputError("borderBand must lie in [0, 0.5]");
  if (maxDepthSide < 1) throw InvalidInputError("maxDepthSide must be at least 1");
}

PhotoProjector::PhotoProjector(const TexelDomain& domain, const ProjectionOptions& options)
    : domain_(domain),
      options_(options),
      points_(texelSurfacePoints(domain)),
      normals_(texelNormals(domain)) {
  options_.validate();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const Eigen::Vector3d& p : domain.mesh().positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  diagonal_ = domain.mesh().positions.empty() ? 0.0 : (hi - lo).norm();
}

PhotoProjection PhotoProjector::project(const Camera& camera, const Image& photo,
                                        const Image* mask) const {
  checkPhotoSize(camera, photo, "the photo");
  if (mask) checkPhotoSize(camera, *mask, "the mask");
  const TexelGrid& grid = domain_.grid();
  const TexturedMesh& mesh = domain_.mesh();
  const int channels = colourChannels(photo);
  PhotoProjection out;
  out.partial = Image(grid.imageWidth, grid.imageHeight, channels, photo.format);
  out.confidence = Image(grid.imageWidth, grid.imageHeight, 1, PixelFormat::UInt16);
  const Eigen::Vector3d centre = camera.centre();
  const double zNear = kNearFraction * diagonal_;

  // Everything but the depth test: in front, front-facing, inside the image and the lens model.
  auto land = [&](int u) -> std::optional<Landing> {
    const int32_t face = points_.face[static_cast<size_t>(u)];
    if (face < 0) return std::nullopt;
    const Eigen::Vector3d p = points_.position.row(u).transpose();
    const Triangle& t = mesh.triangles[static_cast<size_t>(face)];
    const Eigen::Vector3d& p0 = mesh.positions[static_cast<size_t>(t[0])];
    const Eigen::Vector3d normal = (mesh.positions[static_cast<size_t>(t[1])] - p0)
                                       .cross(mesh.positions[static_cast<size_t>(t[2])] - p0);
    if (!(normal.dot(centre - p) > 0.0)) return std::nullopt;
    Landing l;
    l.cameraPoint = camera.toCamera(p);
    if (!(l.cameraPoint.z() > zNear)) return std::nullopt;
    const Eigen::Vector2d normalised = l.cameraPoint.head<2>() / l.cameraPoint.z();
    if (!inMonotonicRange(camera.distortion, normalised)) return std::nullopt;
    l.pixel = camera.projectCameraPoint(l.cameraPoint);
    if (!camera.inImage(l.pixel)) return std::nullopt;
    l.pinhole = {camera.fx * normalised.x() + camera.cx, camera.fy * normalised.y() + camera.cy};
    return l;
  };

  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (int u = 0; u < grid.unknownCount(); ++u)
    if (const auto l = land(u)) {
      lo = lo.cwiseMin(l->pinhole);
      hi = hi.cwiseMax(l->pinhole);
    }
  if (!(lo.x() <= hi.x())) return out;  // no texel lands in the photo
  lo -= Eigen::Vector2d::Ones();
  hi += Eigen::Vector2d::Ones();
  const double scale =
      std::min(1.0, options_.maxDepthSide / std::max(hi.x() - lo.x(), hi.y() - lo.y()));
  const DepthBuffer depth(mesh, camera, lo, hi, scale, zNear);

  const double tolerance = options_.depthTolerance * diagonal_;
  const double band = options_.borderBand * std::min(camera.width, camera.height);
  std::vector<float> confidence(static_cast<size_t>(grid.unknownCount()), 0.0f);
  tbb::parallel_for(0, grid.unknownCount(), [&](int u) {
    const auto l = land(u);
    if (!l) return;
    const int32_t face = points_.face[static_cast<size_t>(u)];
    const int32_t front = depth.faceAt(l->pinhole);
    if (front >= 0 && front != face) {
      // Depth of the front face's plane along this texel's viewing ray.
      const Triangle& t = mesh.triangles[static_cast<size_t>(front)];
      const Eigen::Vector3d a = camera.toCamera(mesh.positions[static_cast<size_t>(t[0])]);
      const Eigen::Vector3d n =
          (camera.toCamera(mesh.positions[static_cast<size_t>(t[1])]) - a)
              .cross(camera.toCamera(mesh.positions[static_cast<size_t>(t[2])]) - a);
      const Eigen::Vector3d ray = l->cameraPoint / l->cameraPoint.z();
      const double along = n.dot(ray);
      if (along != 0.0) {
        const double z = n.dot(a) / along;
        if (z > 0.0 && z + tolerance < l->cameraPoint.z()) return;
      }
    }
    const Eigen::Vector3d p = points_.position.row(u).transpose();
    const double cosine = normals_.row(u).dot((centre - p).normalized());
    if (!(cosine > 0.0)) return;
    const Eigen::Vector3d& q = l->cameraPoint;
    Eigen::Matrix<double, 2, 3> perspective;
    perspective << camera.fx / q.z(), 0.0, -camera.fx * q.x() / (q.z() * q.z()), 0.0,
        camera.fy / q.z(), -camera.fy * q.y() / (q.z() * q.z());
    const Eigen::Matrix2d footprint =
        perspective * camera.R * points_.jacobian[static_cast<size_t>(face)];
    const double pixelsPerTexel = std::abs(footprint.determinant());
    const Eigen::Vector2d& px = l->pixel;
    const double border = std::min({px.x(), px.y(), camera.width - px.x(), camera.height - px.y()});
    const Eigen::Vector2d at = photoTexel(px, camera.height);
    double maskValue = 1.0;
    if (mask) {
      const int maskChannels = std::min(colourChannels(*mask), 3);
      double sum = 0.0;
      for (int c = 0; c < maskChannels; ++c) sum += sampleBilinearTexel(*mask, at, c);
      maskValue = std::clamp(sum / maskChannels, 0.0, 1.0);
    }
    const double c = cosine * std::min(1.0, pixelsPerTexel) *
                     (band > 0.0 ? smoothstep(border / band) : 1.0) * maskValue;
    if (!(c > 0.0)) return;
    confidence[static_cast<size_t>(u)] = static_cast<float>(c);
    const int texel = grid.texelOfUnknown[static_cast<size_t>(u)];
    const int x = texel % grid.nx, y = texel / grid.nx;
    if (!grid.inImage(x, y)) return;
    for (int ch = 0; ch < channels; ++ch)
      out.partial.at(x + grid.x0, y + grid.y0, ch) = sampleBilinearTexel(photo, at, ch);
    out.confidence.at(x + grid.x0, y + grid.y0) = static_cast<float>(c);
  });
  out.seenTexels =
      std::count_if(confidence.begin(), confidence.end(), [](float c) { return c > 0.0f; });
  return out;
}

PhotoProjection projectPhotoFile(const PhotoProjector& projector, const Camera& camera,
                                 const std::filesystem::path& masksDir) {
  const Image photo = readImage(camera.imagePath);
  std::optional<Image> mask;
  if (!masksDir.empty() && pathExists(masksDir / camera.name))
    mask = readImage(masksDir / camera.name);
  return projector.project(camera, photo, mask ? &*mask : nullptr);
}

void BestViewComposite::add(const PhotoProjection& view, int viewIndex) {
  if (composite.empty()) {
    composite =
        Image(view.partial.width, view.partial.height, view.partial.channels, view.partial.format);
    segments = Image(view.partial.width, view.partial.height, 1);
    confidence = Image(view.partial.width, view.partial.height, 1, PixelFormat::UInt16);
  }
  if (view.partial.width != composite.width || view.partial.height != composite.height ||
      view.partial.channels != composite.channels)
    throw InvalidInputError("view " + std::to_string(viewIndex) +
                            " has another size or channel count than the views before it");
  for (int j = 0; j < composite.height; ++j)
    for (int i = 0; i < composite.width; ++i) {
      const float c = view.confidence.at(i, j);
      if (!(c > confidence.at(i, j))) continue;
      confidence.at(i, j) = c;
      segments.at(i, j) = static_cast<float>(viewIndex + 1);
      for (int ch = 0; ch < composite.channels; ++ch)
        composite.at(i, j, ch) = view.partial.at(i, j, ch);
    }
}

}  // namespace texgrad
