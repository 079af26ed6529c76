// OpenMVS's interface file (.mvs, libs/MVS/Interface.h of OpenMVS, archive versions 0 to 7) read
// into Camera values: platforms (cameras with intrinsics and a pose on the platform, platform
// poses) and images (name, platform, camera, pose); the point cloud after them is not read.
//
// The archive is little-endian: optional header "MVSI", uint32 version, uint32 reserved; strings
// and arrays are a uint64 count then the items; matrices are 9 row-major doubles, points 3.
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include "camera_formats.h"
#include "texgrad/core/error.h"

namespace texgrad::cameras {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the .mvs reader copies OpenMVS's little-endian numbers as they are");

/// Newest archive version whose layout this reader knows (OpenMVS MVSI_PROJECT_VER).
constexpr uint32_t kNewestVersion = 7;
/// Image pose id meaning "not calibrated" (OpenMVS NO_ID).
constexpr uint32_t kNoId = std::numeric_limits<uint32_t>::max();
/// OpenMVS puts pixel centres at integer coordinates, Camera at +0.5 (top-left corner origin).
constexpr double kPixelCentreShift = 0.5;

/// Sequential reads from the file's bytes; any read past the end names the element.
class Archive {
 public:
  Archive(std::string_view bytes, const std::filesystem::path& file) : bytes_(bytes), file_(file) {}

  uint32_t version = 0;

  [[noreturn]] void fail(const std::string& element, const std::string& problem) const {
    throw InvalidInputError(file_.string() + ": " + element + ": " + problem);
  }
  [[noreturn]] void unsupported(const std::string& element, const std::string& problem) const {
    throw UnsupportedError(file_.string() + ": " + element + ": " + problem);
  }

  template <typename T>
  T value(const std::string& element) {
    if (bytes_.size() - pos_ < sizeof(T))
      fail(element, "the file ends at byte " + std::to_string(bytes_.size()) +
                        "; it is truncated or not an OpenMVS scene");
    T out;
    std::memcpy(&out, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return out;
  }

  /// An array length, refused when even `minItemBytes` per item would run past the file's end.
  uint64_t count(const std::string& element, uint64_t minItemBytes) {
    const uint64_t n = value<uint64_t>(element + " count");
    if (n > (bytes_.size() - pos_) / minItemBytes)
      fail(element, "the file claims " + std::to_string(n) +
                        " items, more than it holds; it is truncated or not an OpenMVS scene");
    return n;
  }

  std::string string(const std::string& element) {
    const uint64_t n = count(element, 1);
    std::string out(bytes_.substr(pos_, n));
    pos_ += n;
    return out;
  }

  void skip(uint64_t n, const std::string& element) {
    if (bytes_.size() - pos_ < n) fail(element, "the file ends early; it is truncated");
    pos_ += n;
  }

  Eigen::Matrix3d matrix(const std::string& element) {
    Eigen::Matrix3d m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m(i, j) = finite(element);
    return m;
  }

  Eigen::Vector3d point(const std::string& element) {
    Eigen::Vector3d p;
    for (int i = 0; i < 3; ++i) p(i) = finite(element);
    return p;
  }

 private:
  double finite(const std::string& element) {
    const double x = value<double>(element);
    if (!std::isfinite(x)) fail(element, "holds a number that is not finite");
    return x;
  }

  std::string_view bytes_;
  const std::filesystem::path& file_;
  size_t pos_ = 0;
};

struct MvsCamera {
  uint32_t width = 0, height = 0;
  Eigen::Matrix3d K, R;
  Eigen::Vector3d C;
};
struct MvsPose {
  Eigen::Matrix3d R;
  Eigen::Vector3d C;
};
struct MvsPlatform {
  std::vector<MvsCamera> cameras;
  std::vector<MvsPose> poses;
};

/// Smallest sizes of a serialised camera, pose and platform (empty strings and arrays).
uint64_t cameraBytes(uint32_t version) {
  return 8 + (version > 3 ? 8 : 0) + (version > 0 ? 8 : 0) + 2 * 72 + 24;
}
constexpr uint64_t kPoseBytes = 72 + 24;
constexpr uint64_t kPlatformBytes = 3 * 8;

std::vector<MvsPlatform> readPlatforms(Archive& a) {
  std::vector<MvsPlatform> platforms(a.count("platforms", kPlatformBytes));
  for (size_t p = 0; p < platforms.size(); ++p) {
    const std::string at = "platforms[" + std::to_string(p) + "]";
    a.string(at + ".name");
    platforms[p].cameras.resize(a.count(at + ".cameras", cameraBytes(a.version)));
    for (size_t c = 0; c < platforms[p].cameras.size(); ++c) {
      const std::string atCamera = at + ".cameras[" + std::to_string(c) + "]";
      MvsCamera& camera = platforms[p].cameras[c];
      a.string(atCamera + ".name");
      if (a.version > 3) a.string(atCamera + ".bandName");
      if (a.version > 0) {
        camera.width = a.value<uint32_t>(atCamera + ".width");
        camera.height = a.value<uint32_t>(atCamera + ".height");
      }
      camera.K = a.matrix(atCamera + ".K");
      camera.R = a.matrix(atCamera + ".R");
      camera.C = a.point(atCamera + ".C");
    }
    platforms[p].poses.resize(a.count(at + ".poses", kPoseBytes));
    for (size_t k = 0; k < platforms[p].poses.size(); ++k) {
      const std::string atPose = at + ".poses[" + std::to_string(k) + "]";
      platforms[p].poses[k].R = a.matrix(atPose + ".R");
      platforms[p].poses[k].C = a.point(atPose + ".C");
    }
  }
  return platforms;
}

/// The intrinsics of an OpenMVS camera, checked.
void setIntrinsics(const MvsCamera& c, const std::string& at, const Archive& a, Camera& out) {
  if (c.width == 0 || c.height == 0)
    a.unsupported(at,
                  "normalised intrinsics (no image size) are not supported; export the scene "
                  "with image sizes (e.g. InterfaceCOLMAP without --normalize)");
  const Eigen::Matrix3d& K = c.K;
  if (K(0, 1) != 0) a.unsupported(at + ".K", "a skewed K (K[0][1] != 0) is not supported");
  if (K(1, 0) != 0 || K(2, 0) != 0 || K(2, 1) != 0 || K(2, 2) != 1 || !(K(0, 0) > 0) ||
      !(K(1, 1) > 0))
    a.fail(at + ".K", "expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0");
  if (c.width > static_cast<uint32_t>(std::numeric_limits<int>::max()) ||
      c.height > static_cast<uint32_t>(std::numeric_limits<int>::max()))
    a.fail(at, "the image size is out of range");
  out.width = static_cast<int>(c.width);
  out.height = static_cast<int>(c.height);
  out.fx = K(0, 0);
  out.fy = K(1, 1);
  out.cx = K(0, 2) + kPixelCentreShift;
  out.cy = K(1, 2) + kPixelCentreShift;
}

/// The cameras of the calibrated images (pose id set), in file order.
std::vector<Camera> readImages(Archive& a, const std::vector<MvsPlatform>& platforms) {
  constexpr uint64_t kImageBytes = 8 + 3 * 4;  // empty name, three ids
  const uint64_t n = a.count("images", kImageBytes);
  std::vector<Camera> out;
  std::map<std::string, size_t> names;
  for (size_t i = 0; i < n; ++i) {
    const std::string at = "images[" + std::to_string(i) + "]";
    Camera camera;
    camera.name = a.string(at + ".name");
    if (a.version > 4) a.string(at + ".maskName");
    const uint32_t platformId = a.value<uint32_t>(at + ".platformID");
    const uint32_t cameraId = a.value<uint32_t>(at + ".cameraID");
    const uint32_t poseId = a.value<uint32_t>(at + ".poseID");
    if (a.version > 2) a.value<uint32_t>(at + ".ID");
    if (a.version > 6) {  // depth range and view scores (ID, points, scale, angle, area, score)
      a.skip(3 * sizeof(float), at + ".depths");
      constexpr uint64_t kViewScoreBytes = 2 * 4 + 4 * 4;
      a.skip(a.count(at + ".viewScores", kViewScoreBytes) * kViewScoreBytes, at + ".viewScores");
    }
    if (poseId == kNoId) continue;  // not calibrated: OpenMVS skips it too
    if (platformId >= platforms.size())
      a.fail(at, "platform " + std::to_string(platformId) + " does not exist (the scene has " +
                     std::to_string(platforms.size()) + ")");
    const MvsPlatform& platform = platforms[platformId];
    if (cameraId >= platform.cameras.size() || poseId >= platform.poses.size())
      a.fail(at, "camera " + std::to_string(cameraId) + " or pose " + std::to_string(poseId) +
                     " does not exist on platform " + std::to_string(platformId) + " (it has " +
                     std::to_string(platform.cameras.size()) + " cameras, " +
                     std::to_string(platform.poses.size()) + " poses)");
    if (const std::string problem = nameProblem(camera.name); !problem.empty())
      a.fail(at + ".name", problem);
    const std::string atCamera =
        "platforms[" + std::to_string(platformId) + "].cameras[" + std::to_string(cameraId) + "]";
    const std::string atPose =
        "platforms[" + std::to_string(platformId) + "].poses[" + std::to_string(poseId) + "]";
    const MvsCamera& c = platform.cameras[cameraId];
    const MvsPose& pose = platform.poses[poseId];
    setIntrinsics(c, atCamera, a, camera);
    if (!isRotation(c.R)) a.fail(atCamera + ".R", "not a rotation");
    if (!isRotation(pose.R)) a.fail(atPose + ".R", "not a rotation");
    // World -> platform: R_p (X - C_p); platform -> camera: R_c (X_p - C_c) (Interface.h GetPose).
    camera.R = c.R * pose.R;
    const Eigen::Vector3d centre = pose.R.transpose() * c.C + pose.C;
    camera.t = -camera.R * centre;
    if (!camera.t.allFinite()) a.fail(atPose + ".C", "the camera centre is too far out");
    const auto [previous, fresh] = names.emplace(camera.name, i);
    if (!fresh)
      a.fail(at + ".name", "photo '" + camera.name + "' is listed twice (also images[" +
                               std::to_string(previous->second) + "]); keep one entry per photo");
    out.push_back(std::move(camera));
  }
  return out;
}

}  // namespace

std::vector<Camera> readOpenMvs(const std::filesystem::path& path) {
  const std::string bytes = readWholeFile(path);
  Archive archive(bytes, path);
  if (bytes.compare(0, 4, "MVSI") == 0) {
    archive.skip(4, "header");
    archive.version = archive.value<uint32_t>("header version");
    archive.value<uint32_t>("header");
    if (archive.version > kNewestVersion)
      archive.unsupported("header", "archive version " + std::to_string(archive.version) +
                                        " is newer than texgrad reads (up to " +
                                        std::to_string(kNewestVersion) +
                                        "); export the cameras as COLMAP text instead");
  }
  const std::vector<MvsPlatform> platforms = readPlatforms(archive);
  return readImages(archive, platforms);
}

}  // namespace texgrad::cameras
