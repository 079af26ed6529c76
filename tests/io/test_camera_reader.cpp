// Camera files: COLMAP's text model read as written by hand and by COLMAP, its quaternion
// convention against independent rotations, writer -> reader round trips, the photos resolved
// with their sizes checked, and one clear line (file, line) for each kind of bad input.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>

#include "camera_fixtures.h"
#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/camera_reader.h"
#include "texgrad/io/camera_writer.h"
#include "texgrad/io/image_io.h"

namespace texgrad {
namespace {

using test::expectSameCameras;
using test::randomCameras;
using test::tempDir;

void writeTextFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

/// A COLMAP model folder holding the two given files.
std::filesystem::path colmapModel(const std::string& test, const std::string& camerasTxt,
                                  const std::string& imagesTxt) {
  const std::filesystem::path dir = tempDir("cameras_" + test);
  writeTextFile(dir / "cameras.txt", camerasTxt);
  writeTextFile(dir / "images.txt", imagesTxt);
  return dir;
}

const std::string kCamerasTxt =
    "# Camera list with one line of data per camera:\n"
    "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
    "\n"
    "1 SIMPLE_PINHOLE 640 480 500 320 240\n"
    "2 PINHOLE 800 600 700 710 401.5 299.5\r\n"
    "3 SIMPLE_RADIAL 640 480 510 321 239 -0.05\n"
    "  4 RADIAL 640 480 520 322 238 -0.1 0.02\n"
    "5 OPENCV 1024 768 900 905 512.25 383.75 -0.2 0.05 0.001 -0.002\n";

const std::string kImagesTxt =
    "# Image list with two lines of data per image:\n"
    "1 1 0 0 0 0 0 0 1 a.jpg\n"
    "\n"
    "2 1 0 0 0 1 2 3 2 sub/b.jpg\n"
    "10.5 20.5 -1 30 40 7\n"
    "# a comment between images\n"
    "3 0.7071067811865476 0 0.7071067811865476 0 0 0 5 3 c d.png\n"
    "\n"
    "4 1 0 0 0 0 0 0 4 e.jpg\n"
    "\n"
    "5 1 0 0 0 0 0 0 5 f.jpg\n";

TEST(ColmapText, ReadsEverySupportedModel) {
  const auto cameras = readCameraFile(colmapModel("models", kCamerasTxt, kImagesTxt));
  ASSERT_EQ(cameras.size(), 5u);
  EXPECT_EQ(cameras[0].name, "a.jpg");
  EXPECT_EQ(cameras[0].width, 640);
  EXPECT_EQ(cameras[0].fx, 500);
  EXPECT_EQ(cameras[0].fy, 500);  // SIMPLE_PINHOLE: one focal length
  EXPECT_EQ(cameras[0].cx, 320);
  EXPECT_EQ(cameras[0].distortion.model, DistortionModel::None);

  EXPECT_EQ(cameras[1].name, "sub/b.jpg");
  EXPECT_EQ(cameras[1].height, 600);
  EXPECT_EQ(cameras[1].fy, 710);
  EXPECT_EQ(cameras[1].cy, 299.5);  // the CRLF line end is not part of the number
  EXPECT_EQ(cameras[1].t, Eigen::Vector3d(1, 2, 3));

  EXPECT_EQ(cameras[2].name, "c d.png");  // names may hold spaces
  EXPECT_EQ(cameras[2].distortion.model, DistortionModel::SimpleRadial);
  EXPECT_EQ(cameras[2].distortion.k1, -0.05);
  EXPECT_EQ(cameras[2].fy, 510);

  EXPECT_EQ(cameras[3].distortion.model, DistortionModel::Radial);
  EXPECT_EQ(cameras[3].distortion.k2, 0.02);
  EXPECT_EQ(cameras[3].cx, 322);

  const Camera& opencv = cameras[4];
  EXPECT_EQ(opencv.distortion.model, DistortionModel::OpenCV);
  EXPECT_EQ(opencv.fx, 900);
  EXPECT_EQ(opencv.fy, 905);
  EXPECT_EQ(opencv.cx, 512.25);
  EXPECT_EQ(opencv.cy, 383.75);
  EXPECT_EQ(opencv.distortion.k1, -0.2);
  EXPECT_EQ(opencv.distortion.k2, 0.05);
  EXPECT_EQ(opencv.distortion.p1, 0.001);
  EXPECT_EQ(opencv.distortion.p2, -0.002);
}

TEST(ColmapText, EitherFileNamesTheModel) {
  const std::filesystem::path dir = colmapModel("either", kCamerasTxt, kImagesTxt);
  EXPECT_EQ(readCameraFile(dir / "cameras.txt").size(), 5u);
  EXPECT_EQ(readCameraFile(dir / "images.txt").size(), 5u);
}

/// A camera 5 units out on +x looking at the origin, y down along world y: its axes in world
/// coordinates are x = +z, y = +y, z = -x (a rotation of +90 degrees about y), written as the
/// quaternion (cos 45°, 0, sin 45°, 0) of that rotation.
TEST(ColmapText, QuaternionIsHamiltonWorldToCamera) {
  const std::string images = "1 0.70710678118654752 0 0.70710678118654752 0 0 0 5 1 look.jpg\n\n";
  const auto cameras =
      readCameraFile(colmapModel("quaternion", "1 PINHOLE 640 480 500 500 320 240\n", images));
  ASSERT_EQ(cameras.size(), 1u);
  const Camera& c = cameras[0];
  EXPECT_LT((c.centre() - Eigen::Vector3d(5, 0, 0)).norm(), 1e-12);
  const auto origin = c.project(Eigen::Vector3d::Zero());
  ASSERT_TRUE(origin);
  EXPECT_LT((*origin - Eigen::Vector2d(320, 240)).norm(), 1e-9);
  // World +z is the camera's right: one unit at distance 5 is 500 / 5 pixels right of centre.
  const auto right = c.project(Eigen::Vector3d(0, 0, 1));
  ASSERT_TRUE(right);
  EXPECT_LT((*right - Eigen::Vector2d(420, 240)).norm(), 1e-9);
  const auto below = c.project(Eigen::Vector3d(0, 1, 0));  // world +y is the camera's down
  ASSERT_TRUE(below);
  EXPECT_LT((*below - Eigen::Vector2d(320, 340)).norm(), 1e-9);
}

/// A general rotation, its quaternion written from the axis-angle formula (w = cos θ/2,
/// v = sin θ/2 axis) rather than from a matrix, read back as that rotation world -> camera.
TEST(ColmapText, QuaternionMatchesAxisAngle) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  const double angle = 1.1;
  const Eigen::Vector3d v = std::sin(angle / 2) * axis;
  std::ostringstream images;
  images << std::setprecision(17) << "7 " << std::cos(angle / 2) << " " << v.x() << " " << v.y()
         << " " << v.z() << " 0.5 -1 2 1 r.jpg\n";
  const auto cameras =
      readCameraFile(colmapModel("axis_angle", "1 PINHOLE 64 48 50 50 32 24\n", images.str()));
  ASSERT_EQ(cameras.size(), 1u);
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  EXPECT_LT((cameras[0].R - expected).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(ColmapText, WriterReaderRoundTrip) {
  const std::vector<Camera> cameras = randomCameras(29);
  const std::filesystem::path dir = tempDir("cameras_round_trip") / "sparse";
  writeColmapText(dir, cameras);
  EXPECT_TRUE(std::filesystem::exists(dir / "points3D.txt"));  // COLMAP loads the folder
  expectSameCameras(readCameraFile(dir), cameras);
}

TEST(ColmapText, RadialModelWithTwoFocalLengthsIsWrittenAsOpenCV) {
  std::vector<Camera> cameras = randomCameras(3);
  cameras.resize(3);  // None, SimpleRadial, Radial
  for (Camera& c : cameras) c.fy = c.fx * 1.01;
  const std::filesystem::path dir = tempDir("cameras_two_focals");
  writeColmapText(dir, cameras);
  const std::vector<Camera> read = readCameraFile(dir);
  ASSERT_EQ(read.size(), 3u);
  for (size_t i = 1; i < 3; ++i) {
    EXPECT_EQ(read[i].distortion.model, DistortionModel::OpenCV);
    const Eigen::Vector3d point(0.4, -0.3, 1.5);  // camera coordinates, off both axes
    EXPECT_LT((read[i].projectCameraPoint(point) - cameras[i].projectCameraPoint(point)).norm(),
              1e-9);
  }
}

TEST(ColmapText, WriterRefusesWhatCannotBeReadBack) {
  std::vector<Camera> cameras = randomCameras(4);
  cameras[2].name = "two\nlines.png";
  EXPECT_THROW(writeColmapText(tempDir("cameras_bad_name"), cameras), InvalidInputError);
  cameras[2].name = "ok.png";
  cameras[3].t.x() = std::nan("");
  EXPECT_THROW(writeColmapText(tempDir("cameras_nan"), cameras), InvalidInputError);
  cameras[3].t.x() = 0;
  cameras[3].R(0, 0) = 2;
  EXPECT_THROW(writeColmapText(tempDir("cameras_not_rotation"), cameras), InvalidInputError);
}

/// A bad COLMAP model: the file and line the message must name and words it must hold.
struct BadColmap {
  const char* label;
  std::string camerasTxt, imagesTxt;
  const char* file;  // "cameras.txt" or "images.txt"
  int line;
  const char* says;
};

const std::string kGoodCamera = "1 PINHOLE 64 48 50 50 32 24\n";
const std::string kGoodImage = "1 1 0 0 0 0 0 0 1 a.jpg\n\n";

std::vector<BadColmap> badColmapModels() {
  return {
      {"unknown_model", "1 PINHOLE 64 48 50 50 32 24\n2 PINHOLO 64 48 50 50 32 24\n", kGoodImage,
       "cameras.txt", 2, "unknown camera model 'PINHOLO'"},
      {"fisheye", "# c\n1 OPENCV_FISHEYE 64 48 50 50 32 24 0 0 0 0\n", kGoodImage, "cameras.txt", 2,
       "OPENCV_FISHEYE is not supported"},
      {"full_opencv", "1 FULL_OPENCV 64 48 50 50 32 24 0 0 0 0 0 0 0 0\n", kGoodImage,
       "cameras.txt", 1, "FULL_OPENCV is not supported"},
      {"parameter_count", "1 OPENCV 64 48 50 50 32 24 0.1\n", kGoodImage, "cameras.txt", 1,
       "has 8 parameters, the line gives 5"},
      {"nan_parameter", "1 PINHOLE 64 48 nan 50 32 24\n", kGoodImage, "cameras.txt", 1,
       "'nan', which is not finite"},
      {"inf_parameter", "1 PINHOLE 64 48 50 50 inf 24\n", kGoodImage, "cameras.txt", 1,
       "which is not finite"},
      {"huge_parameter", "1 PINHOLE 64 48 50 50 1e999 24\n", kGoodImage, "cameras.txt", 1,
       "'1e999', which is out of range"},
      {"word_parameter", "1 PINHOLE 64 48 50 fifty 32 24\n", kGoodImage, "cameras.txt", 1,
       "which is not a number"},
      {"fractional_width", "1 PINHOLE 64.5 48 50 50 32 24\n", kGoodImage, "cameras.txt", 1,
       "WIDTH is '64.5'"},
      {"zero_height", "1 PINHOLE 64 0 50 50 32 24\n", kGoodImage, "cameras.txt", 1,
       "must be positive"},
      {"negative_focal", "1 PINHOLE 64 48 -50 50 32 24\n", kGoodImage, "cameras.txt", 1,
       "focal length must be positive"},
      {"short_camera", "1 PINHOLE 64\n", kGoodImage, "cameras.txt", 1, "found 3 words"},
      {"duplicate_camera", kGoodCamera + kGoodCamera, kGoodImage, "cameras.txt", 2,
       "camera 1 is defined twice"},
      {"missing_camera", kGoodCamera, "\n1 1 0 0 0 0 0 0 2 a.jpg\n\n", "images.txt", 2,
       "refers to camera 2, which"},
      {"duplicate_name", kGoodCamera, kGoodImage + "2 1 0 0 0 0 0 0 1 a.jpg\n\n", "images.txt", 3,
       "'a.jpg' is listed twice (also on line 1)"},
      {"duplicate_image_id", kGoodCamera, kGoodImage + "1 1 0 0 0 0 0 0 1 b.jpg\n\n", "images.txt",
       3, "image id 1 is used twice"},
      {"one_line_per_image", kGoodCamera, "1 1 0 0 0 0 0 0 1 a.jpg\n2 1 0 0 0 0 0 0 1 b.jpg\n",
       "images.txt", 2, "images.txt holds two lines per image"},
      {"tab_in_name", kGoodCamera, "1 1 0 0 0 0 0 0 1 a\tb.jpg\n\n", "images.txt", 1,
       "control character"},
      {"short_image", kGoodCamera, "1 1 0 0 0 0 0 0 1\n", "images.txt", 1, "found 9 words"},
      {"nan_translation", kGoodCamera, "1 1 0 0 0 0 nan 0 1 a.jpg\n\n", "images.txt", 1,
       "TY is 'nan', which is not finite"},
      {"not_unit_quaternion", kGoodCamera, "1 2 0 0 0 0 0 0 1 a.jpg\n\n", "images.txt", 1,
       "has norm 2, not 1"},
      {"negative_id", kGoodCamera, "-1 1 0 0 0 0 0 0 1 a.jpg\n\n", "images.txt", 1,
       "IMAGE_ID is '-1'"},
  };
}

TEST(ColmapText, BadInputGetsOneLineNamingFileAndLine) {
  for (const BadColmap& bad : badColmapModels()) {
    SCOPED_TRACE(bad.label);
    const std::filesystem::path dir = colmapModel(bad.label, bad.camerasTxt, bad.imagesTxt);
    try {
      readCameraFile(dir);
      ADD_FAILURE() << "no exception";
    } catch (const Error& e) {
      const std::string message = e.what();
      const std::string where =
          (dir / bad.file).string() + " line " + std::to_string(bad.line) + ": ";
      EXPECT_EQ(message.rfind(where, 0), 0u) << message;
      EXPECT_NE(message.find(bad.says), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
}

TEST(ColmapText, UnsupportedModelsAreUnsupportedErrors) {
  const std::filesystem::path dir = colmapModel("fov", "1 FOV 64 48 50 50 32 24 0.1\n", kGoodImage);
  EXPECT_THROW(readCameraFile(dir), UnsupportedError);
}

TEST(ColmapText, FolderWithoutTextModelSaysHowToConvert) {
  const std::filesystem::path dir = tempDir("cameras_binary_model");
  writeTextFile(dir / "cameras.bin", "binary");
  try {
    readCameraFile(dir);
    ADD_FAILURE() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("model_converter"), std::string::npos) << e.what();
  }
}

/// Writes an image of the given size (all grey) as dir / name.
void writePhoto(const std::filesystem::path& path, int width, int height) {
  std::filesystem::create_directories(path.parent_path());
  Image image(width, height, 3, PixelFormat::UInt8);
  for (float& v : image.pixels) v = 0.5f;
  writeImage(path, image);
}

TEST(CameraImages, ResolvedUnderTheImagesFolderWithSizesChecked) {
  const std::filesystem::path dir =
      colmapModel("photos", "1 PINHOLE 64 48 50 50 32 24\n",
                  "1 1 0 0 0 0 0 0 1 a.png\n\n2 1 0 0 0 0 0 0 1 sub/b.png\n\n");
  writePhoto(dir / "images" / "a.png", 64, 48);
  writePhoto(dir / "images" / "sub" / "b.png", 64, 48);
  const auto cameras = readCameras(dir, dir / "images");
  ASSERT_EQ(cameras.size(), 2u);
  EXPECT_EQ(cameras[1].imagePath, dir / "images" / "sub" / "b.png");
}

TEST(CameraImages, MissingPhotoNamesCameraFileAndImage) {
  const std::filesystem::path dir = colmapModel("missing_photo", kGoodCamera, kGoodImage);
  try {
    readCameras(dir, dir / "images");
    ADD_FAILURE() << "no exception";
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(dir.string() + ": image 'a.jpg' (", 0), 0u) << message;
    EXPECT_NE(message.find("no such file"), std::string::npos) << message;
  }
}

TEST(CameraImages, PhotoOfAnotherSizeIsRefused) {
  const std::filesystem::path dir =
      colmapModel("photo_size", kGoodCamera, "1 1 0 0 0 0 0 0 1 a.png\n\n");
  writePhoto(dir / "a.png", 48, 64);  // rotated: width and height swapped
  try {
    readCameras(dir / "images.txt", dir);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidInputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind((dir / "images.txt").string() + ": image 'a.png'", 0), 0u) << message;
    EXPECT_NE(message.find("the photo is 48 x 64 pixels but its camera is 64 x 48"),
              std::string::npos)
        << message;
  }
}

TEST(CameraImages, UnreadablePhotoIsRefused) {
  const std::filesystem::path dir =
      colmapModel("photo_garbage", kGoodCamera, "1 1 0 0 0 0 0 0 1 a.png\n\n");
  writeTextFile(dir / "a.png", "not an image");
  EXPECT_THROW(readCameras(dir, dir), InvalidInputError);
}

TEST(CameraFiles, FileWithoutCamerasIsRefused) {
  const std::filesystem::path dir = colmapModel("no_images", kGoodCamera, "# no images\n");
  try {
    readCameraFile(dir / "images.txt");
    ADD_FAILURE() << "no exception";
  } catch (const InvalidInputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind((dir / "images.txt").string() + ": no calibrated photo", 0), 0u)
        << message;
  }
}

TEST(CameraFiles, UnknownKindIsRefused) {
  const std::filesystem::path dir = tempDir("cameras_unknown_kind");
  writeTextFile(dir / "cams.xml", "<cameras/>");
  EXPECT_THROW(readCameraFile(dir / "cams.xml"), UnsupportedError);
  EXPECT_THROW(readCameraFile(dir / "missing"), IoError);
}

}  // namespace
}  // namespace texgrad
