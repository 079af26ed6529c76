// OpenMVS scenes (.mvs): archives built byte by byte here after OpenMVS's Interface.h, read for
// every archive version; platform poses composed as OpenMVS does; truncated and inconsistent
// files refused naming the element.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>
#include <fstream>

#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/camera_reader.h"

namespace texgrad {
namespace {

using test::tempDir;

/// An OpenMVS archive written field by field (little-endian, as Interface.h's ArchiveSave).
class MvsBytes {
 public:
  explicit MvsBytes(uint32_t version) : version_(version) {
    if (version > 0) {
      bytes_ += "MVSI";
      u32(version);
      u32(0);
    }
  }
  uint32_t version() const { return version_; }
  void u32(uint32_t v) { raw(&v, sizeof v); }
  void u64(uint64_t v) { raw(&v, sizeof v); }
  void f32(float v) { raw(&v, sizeof v); }
  void f64(double v) { raw(&v, sizeof v); }
  void string(const std::string& s) {
    u64(s.size());
    bytes_ += s;
  }
  void matrix(const Eigen::Matrix3d& m) {  // row-major
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) f64(m(i, j));
  }
  void point(const Eigen::Vector3d& p) {
    for (int i = 0; i < 3; ++i) f64(p(i));
  }
  const std::string& bytes() const { return bytes_; }

 private:
  void raw(const void* data, size_t size) { bytes_.append(static_cast<const char*>(data), size); }
  uint32_t version_;
  std::string bytes_;
};

/// A camera on a platform, a platform pose and an image, as the scene's parts.
struct MvsCameraSpec {
  uint32_t width = 640, height = 480;
  Eigen::Matrix3d K;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
};
struct MvsPoseSpec {
  Eigen::Matrix3d R;
  Eigen::Vector3d C;
};
struct MvsImageSpec {
  std::string name;
  uint32_t platform = 0, camera = 0, pose = 0;
};

Eigen::Matrix3d intrinsics(double fx, double fy, double cx, double cy) {
  Eigen::Matrix3d K;
  K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return K;
}

/// One platform holding `cameras` and `poses`, then `images`, then an empty point cloud.
std::string mvsScene(uint32_t version, const std::vector<MvsCameraSpec>& cameras,
                     const std::vector<MvsPoseSpec>& poses,
                     const std::vector<MvsImageSpec>& images) {
  MvsBytes b(version);
  b.u64(1);  // platforms
  b.string("platform000");
  b.u64(cameras.size());
  for (const MvsCameraSpec& c : cameras) {
    b.string("PINHOLE");
    if (version > 3) b.string("RGB");
    if (version > 0) {
      b.u32(c.width);
      b.u32(c.height);
    }
    b.matrix(c.K);
    b.matrix(c.R);
    b.point(c.C);
  }
  b.u64(poses.size());
  for (const MvsPoseSpec& p : poses) {
    b.matrix(p.R);
    b.point(p.C);
  }
  b.u64(images.size());
  for (const MvsImageSpec& image : images) {
    b.string(image.name);
    if (version > 4) b.string("");  // mask
    b.u32(image.platform);
    b.u32(image.camera);
    b.u32(image.pose);
    if (version > 2) b.u32(7);  // global id
    if (version > 6) {
      b.f32(1);
      b.f32(2);
      b.f32(3);
      b.u64(1);  // one view score: ID, points, scale, angle, area, score
      b.u32(0);
      b.u32(10);
      for (int k = 0; k < 4; ++k) b.f32(0.5f);
    }
  }
  for (int k = 0; k < 3; ++k) b.u64(0);  // vertices, normals, colours (not read)
  return b.bytes();
}

std::filesystem::path mvsFile(const std::string& test, const std::string& bytes) {
  const std::filesystem::path path = tempDir("camera_mvs_" + test) / "scene.mvs";
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

constexpr uint32_t kNoId = 0xffffffffu;

/// A camera 5 units out on +x looking at the origin (rows of R: its axes in world coordinates).
MvsPoseSpec lookingAtOrigin() {
  MvsPoseSpec pose;
  pose.R << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  pose.C = {5, 0, 0};
  return pose;
}

TEST(OpenMvs, ReadsCalibratedImagesOfEveryVersion) {
  for (uint32_t version : {1u, 2u, 3u, 4u, 5u, 6u, 7u}) {
    SCOPED_TRACE("archive version " + std::to_string(version));
    MvsCameraSpec camera;
    camera.K = intrinsics(500, 510, 319.5, 239.5);
    const std::string bytes = mvsScene(version, {camera}, {lookingAtOrigin()},
                                       {{"a.jpg", 0, 0, 0}, {"uncalibrated.jpg", 0, 0, kNoId}});
    const std::vector<Camera> cameras = readCameraFile(mvsFile("versions", bytes));
    ASSERT_EQ(cameras.size(), 1u);  // the image without a pose is left out, as OpenMVS does
    const Camera& c = cameras[0];
    EXPECT_EQ(c.name, "a.jpg");
    EXPECT_EQ(c.width, 640);
    EXPECT_EQ(c.height, 480);
    EXPECT_EQ(c.fx, 500);
    EXPECT_EQ(c.fy, 510);
    // OpenMVS's pixel centres are at integers: its principal point 319.5 is Camera's 320.
    EXPECT_EQ(c.cx, 320);
    EXPECT_EQ(c.cy, 240);
    EXPECT_LT((c.centre() - Eigen::Vector3d(5, 0, 0)).norm(), 1e-12);
    const auto right = c.project(Eigen::Vector3d(0, 0, 1));  // world +z: the camera's right
    ASSERT_TRUE(right);
    EXPECT_LT((*right - Eigen::Vector2d(320 + 500 / 5.0, 240)).norm(), 1e-9);
  }
}

/// A camera mounted on the platform with its own pose: world -> platform -> camera, each step
/// X' = R (X - C), checked on points against that chain written out here.
TEST(OpenMvs, CameraPoseOnPlatformIsComposed) {
  MvsCameraSpec camera;
  camera.K = intrinsics(800, 800, 400, 300);
  camera.R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0, 0, 1)).toRotationMatrix();
  camera.C = {0.1, -0.2, 0.05};
  MvsPoseSpec pose;
  pose.R = Eigen::AngleAxisd(-0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  pose.C = {1, 2, 3};
  const std::vector<Camera> cameras =
      readCameraFile(mvsFile("rig", mvsScene(5, {camera}, {pose}, {{"rig.png", 0, 0, 0}})));
  ASSERT_EQ(cameras.size(), 1u);
  for (const Eigen::Vector3d& X : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, -1, 7)}) {
    const Eigen::Vector3d onPlatform = pose.R * (X - pose.C);
    const Eigen::Vector3d inCamera = camera.R * (onPlatform - camera.C);
    EXPECT_LT((cameras[0].toCamera(X) - inCamera).norm(), 1e-12);
  }
}

TEST(OpenMvs, EveryTruncationIsRefused) {
  MvsCameraSpec camera;
  camera.K = intrinsics(500, 500, 320, 240);
  const std::string bytes =
      mvsScene(7, {camera}, {lookingAtOrigin()}, {{"a.jpg", 0, 0, 0}, {"b.jpg", 0, 0, 0}});
  // The images end 24 bytes before the end (three empty point arrays are not read).
  const size_t imagesEnd = bytes.size() - 24;
  const std::filesystem::path path = tempDir("camera_mvs_truncated") / "scene.mvs";
  for (size_t size = 0; size < imagesEnd; ++size) {
    SCOPED_TRACE("first " + std::to_string(size) + " bytes");
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes.substr(0, size);
    EXPECT_THROW(readCameraFile(path), InvalidInputError);
  }
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes.substr(0, imagesEnd);
  EXPECT_EQ(readCameraFile(path).size(), 2u);  // the cut is exactly where the images end
}

/// Reads a bad scene and returns the message, which must name the file.
std::string mvsError(const std::string& test, const std::string& bytes) {
  const std::filesystem::path path = mvsFile(test, bytes);
  try {
    readCameraFile(path);
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    return message;
  }
  ADD_FAILURE() << "no exception";
  return "";
}

TEST(OpenMvs, BadScenesNameTheElement) {
  MvsCameraSpec camera;
  camera.K = intrinsics(500, 500, 320, 240);
  const MvsPoseSpec pose = lookingAtOrigin();
  const auto has = [](const std::string& message, const std::string& words) {
    return message.find(words) != std::string::npos;
  };
  EXPECT_TRUE(has(mvsError("platform", mvsScene(5, {camera}, {pose}, {{"a.jpg", 2, 0, 0}})),
                  "images[0]: platform 2 does not exist"));
  EXPECT_TRUE(has(mvsError("pose", mvsScene(5, {camera}, {pose}, {{"a.jpg", 0, 0, 1}})),
                  "images[0]: camera 0 or pose 1 does not exist"));
  EXPECT_TRUE(has(mvsError("duplicate",
                           mvsScene(5, {camera}, {pose}, {{"a.jpg", 0, 0, 0}, {"a.jpg", 0, 0, 0}})),
                  "images[1].name: photo 'a.jpg' is listed twice"));
  MvsPoseSpec scaled = pose;
  scaled.R *= 2;
  EXPECT_TRUE(has(mvsError("rotation", mvsScene(5, {camera}, {scaled}, {{"a.jpg", 0, 0, 0}})),
                  "platforms[0].poses[0].R: not a rotation"));
  MvsCameraSpec nan = camera;
  nan.K(0, 2) = std::nan("");
  EXPECT_TRUE(has(mvsError("nan", mvsScene(5, {nan}, {pose}, {{"a.jpg", 0, 0, 0}})),
                  "platforms[0].cameras[0].K: holds a number that is not finite"));
  MvsCameraSpec skewed = camera;
  skewed.K(0, 1) = 0.5;
  EXPECT_THROW(readCameraFile(mvsFile("skew", mvsScene(5, {skewed}, {pose}, {{"a.jpg", 0, 0, 0}}))),
               UnsupportedError);
  MvsCameraSpec normalised = camera;
  normalised.width = normalised.height = 0;
  EXPECT_TRUE(has(mvsError("normalised", mvsScene(5, {normalised}, {pose}, {{"a.jpg", 0, 0, 0}})),
                  "normalised intrinsics"));
  EXPECT_TRUE(has(mvsError("version0", mvsScene(0, {camera}, {pose}, {{"a.jpg", 0, 0, 0}})),
                  "normalised intrinsics"));
  EXPECT_TRUE(has(mvsError("no_pose", mvsScene(5, {camera}, {pose}, {{"a.jpg", 0, 0, kNoId}})),
                  "no calibrated photo"));
  std::string newer = mvsScene(5, {camera}, {pose}, {{"a.jpg", 0, 0, 0}});
  newer[4] = 8;  // the version field
  EXPECT_TRUE(has(mvsError("newer", newer), "archive version 8 is newer"));
  std::string huge = mvsScene(5, {camera}, {pose}, {{"a.jpg", 0, 0, 0}});
  const uint64_t claimed = uint64_t(1) << 60;
  std::memcpy(huge.data() + 12, &claimed, sizeof claimed);  // the platform count
  EXPECT_TRUE(has(mvsError("huge", huge), "platforms: the file claims 1152921504606846976"));
}

}  // namespace
}  // namespace texgrad
