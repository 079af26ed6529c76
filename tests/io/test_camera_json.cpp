// texgrad's camera JSON: the documented example, the same cameras as COLMAP's text model giving
// the same values, writer -> reader round trips, and one line (file, element) per bad input.
#include <gtest/gtest.h>

#include <fstream>

#include "camera_fixtures.h"
#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/camera_reader.h"
#include "texgrad/io/camera_writer.h"

namespace texgrad {
namespace {

using test::expectSameCameras;
using test::randomCameras;
using test::tempDir;

std::filesystem::path jsonFile(const std::string& test, const std::string& text) {
  const std::filesystem::path path = tempDir("camera_json_" + test) / "cameras.json";
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

/// The example of docs/photos.md: a camera 5 units out on +x looking at the origin (its axes in
/// world coordinates x = +z, y = +y, z = -x), given by its centre, and one given by t.
const std::string kExample = R"({
  "cameras": [
    {
      "file": "IMG_0001.jpg",
      "width": 640, "height": 480,
      "K": [[500, 0, 320], [0, 500, 240], [0, 0, 1]],
      "R": [[0, 0, 1], [0, 1, 0], [-1, 0, 0]],
      "C": [5, 0, 0],
      "distortion": {"model": "opencv", "k1": -0.1, "k2": 0.01, "p1": 0.001, "p2": -0.002}
    },
    {
      "file": "IMG_0002.jpg",
      "width": 640, "height": 480,
      "K": [[510, 0, 321.5], [0, 505, 239.5], [0, 0, 1]],
      "R": [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
      "t": [0, 0, 5]
    }
  ]
})";

/// The same two cameras in COLMAP's text model, written by hand: the first rotation is
/// +90 degrees about y, quaternion (cos 45°, 0, sin 45°, 0); t = -R C = (0, 0, 5).
const std::string kExampleCamerasTxt =
    "1 OPENCV 640 480 500 500 320 240 -0.1 0.01 0.001 -0.002\n"
    "2 PINHOLE 640 480 510 505 321.5 239.5\n";
const std::string kExampleImagesTxt =
    "1 0.70710678118654752 0 0.70710678118654752 0 0 0 5 1 IMG_0001.jpg\n\n"
    "2 1 0 0 0 0 0 5 2 IMG_0002.jpg\n\n";

TEST(CameraJson, ReadsTheDocumentedExample) {
  const auto cameras = readCameraFile(jsonFile("example", kExample));
  ASSERT_EQ(cameras.size(), 2u);
  const Camera& c = cameras[0];
  EXPECT_EQ(c.name, "IMG_0001.jpg");
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.fx, 500);
  EXPECT_EQ(c.cy, 240);
  EXPECT_EQ(c.t, Eigen::Vector3d(0, 0, 5));  // -R C
  EXPECT_EQ(c.distortion.model, DistortionModel::OpenCV);
  EXPECT_EQ(c.distortion.p2, -0.002);
  const auto origin = c.project(Eigen::Vector3d::Zero());
  ASSERT_TRUE(origin);
  EXPECT_EQ(*origin, Eigen::Vector2d(320, 240));
  EXPECT_EQ(cameras[1].fy, 505);
  EXPECT_EQ(cameras[1].distortion.model, DistortionModel::None);
}

TEST(CameraJson, SameCamerasAsColmapTextReadToTheSameValues) {
  const std::filesystem::path colmap = tempDir("camera_json_vs_colmap");
  std::ofstream(colmap / "cameras.txt") << kExampleCamerasTxt;
  std::ofstream(colmap / "images.txt") << kExampleImagesTxt;
  expectSameCameras(readCameraFile(jsonFile("vs_colmap", kExample)), readCameraFile(colmap));
}

TEST(CameraJson, WriterReaderRoundTrip) {
  const std::vector<Camera> cameras = randomCameras(17);
  const std::filesystem::path path = tempDir("camera_json_round_trip") / "cams.json";
  writeCameraJson(path, cameras);
  expectSameCameras(readCameraFile(path), cameras);
}

TEST(CameraJson, WrittenJsonAndColmapReadToTheSameCameras) {
  const std::vector<Camera> cameras = randomCameras(5);
  const std::filesystem::path dir = tempDir("camera_json_both_writers");
  writeCameraJson(dir / "cameras.json", cameras);
  writeColmapText(dir / "sparse", cameras);
  expectSameCameras(readCameraFile(dir / "cameras.json"), readCameraFile(dir / "sparse"));
}

TEST(CameraJson, WriterRefusesNamesThatAreNotUtf8) {
  std::vector<Camera> cameras = randomCameras(6);
  cameras[1].name = "caf\xe9.jpg";  // Latin-1
  EXPECT_THROW(writeCameraJson(tempDir("camera_json_latin1") / "c.json", cameras),
               InvalidInputError);
}

/// A bad camera JSON: the element the message must name and words it must hold.
struct BadJson {
  const char* label;
  std::string text;
  const char* element;
  const char* says;
};

/// A camera entry with one key replaced (or added) by `change` and `remove` dropped.
std::string entry(const std::string& change = "", const std::string& remove = "") {
  std::vector<std::pair<std::string, std::string>> keys = {
      {"file", R"("a.jpg")"},
      {"width", "64"},
      {"height", "48"},
      {"K", "[[50, 0, 32], [0, 50, 24], [0, 0, 1]]"},
      {"R", "[[1, 0, 0], [0, 1, 0], [0, 0, 1]]"},
      {"C", "[0, 0, -5]"}};
  std::string text = "{";
  const std::string changedKey = change.substr(0, change.find(':'));
  for (const auto& [key, value] : keys)
    if (key != remove && "\"" + key + "\"" != changedKey)
      text += (text.size() > 1 ? ", " : "") + ("\"" + key + "\": " + value);
  if (!change.empty()) text += ", " + change;
  return text + "}";
}

std::string cameraList(const std::string& entries) {
  return R"({"cameras": [)" + entries + "]}";
}

std::vector<BadJson> badJsonFiles() {
  return {
      {"not_json", "{\"cameras\": [", "not valid JSON", "parse error at line 1"},
      {"deep", std::string(100, '[') + std::string(100, ']'), "JSON nested deeper than", ""},
      {"top_array", "[]", "top level", "expected an object, found an array"},
      {"top_key", R"({"cameras": [], "camera": []})", "top level", "unknown key \"camera\""},
      {"no_cameras", "{}", "top level", "\"cameras\" is missing"},
      {"cameras_object", R"({"cameras": {}})", "cameras", "expected an array of cameras"},
      {"unknown_key", cameraList(entry(R"("Kmatrix": 1)")), "cameras[0]",
       "unknown key \"Kmatrix\""},
      {"no_file", cameraList(entry("", "file")), "cameras[0]", "\"file\" is missing"},
      {"file_number", cameraList(entry(R"("file": 7)")), "cameras[0].file", "found 7"},
      {"file_lines", cameraList(entry(R"("file": "a\nb.jpg")")), "cameras[0].file",
       "control character"},
      {"file_empty", cameraList(entry(R"("file": "")")), "cameras[0].file",
       "the image name is empty"},
      {"C_far",
       cameraList(entry(
           R"("C": [1.5e308, 1.5e308, 0], "R": [[0.6, 0.8, 0], [-0.8, 0.6, 0], [0, 0, 1]])", "R")),
       "cameras[0].C", "too far out"},
      {"zero_width", cameraList(entry(R"("width": 0)")), "cameras[0].width", "found 0"},
      {"fractional_height", cameraList(entry(R"("height": 48.5)")), "cameras[0].height",
       "positive whole number"},
      {"string_width", cameraList(entry(R"("width": "64")")), "cameras[0].width", "found \"64\""},
      {"K_rows", cameraList(entry(R"("K": [[50, 0, 32], [0, 50, 24]])")), "cameras[0].K",
       "expected 3 rows of 3 numbers"},
      {"K_short_row", cameraList(entry(R"("K": [[50, 0, 32], [0, 50], [0, 0, 1]])")),
       "cameras[0].K[1]", "expected 3 rows of 3 numbers"},
      {"K_last_row", cameraList(entry(R"("K": [[50, 0, 32], [0, 50, 24], [0, 0, 2]])")),
       "cameras[0].K", "[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]"},
      {"K_null", cameraList(entry(R"("K": [[50, 0, 32], [0, null, 24], [0, 0, 1]])")),
       "cameras[0].K[1][1]", "expected a number, found null"},
      {"K_overflow", cameraList(entry(R"("K": [[1e999, 0, 32], [0, 50, 24], [0, 0, 1]])")),
       "not valid JSON", "number overflow parsing '1e999'"},
      {"K_negative_focal", cameraList(entry(R"("K": [[-50, 0, 32], [0, 50, 24], [0, 0, 1]])")),
       "cameras[0].K", "must be positive"},
      {"R_scaled", cameraList(entry(R"("R": [[2, 0, 0], [0, 2, 0], [0, 0, 2]])")), "cameras[0].R",
       "not a rotation"},
      {"R_mirror", cameraList(entry(R"("R": [[-1, 0, 0], [0, 1, 0], [0, 0, 1]])")), "cameras[0].R",
       "not a rotation"},
      {"C_and_t", cameraList(entry(R"("t": [0, 0, 5])")), "cameras[0]", "not both"},
      {"neither_C_nor_t", cameraList(entry("", "C")), "cameras[0]",
       "the camera centre \"C\" (or the translation \"t\") is missing"},
      {"C_word", cameraList(entry(R"("C": [0, "one", 0])")), "cameras[0].C[1]", "found \"one\""},
      {"distortion_model", cameraList(entry(R"("distortion": {"model": "fisheye"})")),
       "cameras[0].distortion.model", "unknown distortion model \"fisheye\""},
      {"distortion_extra", cameraList(entry(R"("distortion": {"model": "radial", "k1": 0, "k2": 0,
       "p1": 0})")),
       "cameras[0].distortion", "\"p1\" is not a coefficient of the radial model"},
      {"distortion_missing", cameraList(entry(R"("distortion": {"model": "radial", "k1": 0.1})")),
       "cameras[0].distortion", "\"k2\" is missing"},
      {"duplicate_file", cameraList(entry() + ", " + entry()), "cameras[1].file",
       "'a.jpg' is listed twice (also cameras[0])"},
      {"no_cameras_listed", R"({"cameras": []})", "no calibrated photo", ""},
      {"second_entry", cameraList(entry() + ", 3"), "cameras[1]", "expected an object, found 3"},
  };
}

TEST(CameraJson, BadInputGetsOneLineNamingFileAndElement) {
  for (const BadJson& bad : badJsonFiles()) {
    SCOPED_TRACE(bad.label);
    const std::filesystem::path path = jsonFile(bad.label, bad.text);
    try {
      readCameraFile(path);
      ADD_FAILURE() << "no exception";
    } catch (const InvalidInputError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(path.string() + ": " + bad.element, 0), 0u) << message;
      EXPECT_NE(message.find(bad.says), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
}

TEST(CameraJson, SkewIsUnsupported) {
  const std::filesystem::path path =
      jsonFile("skew", cameraList(entry(R"("K": [[50, 0.5, 32], [0, 50, 24], [0, 0, 1]])")));
  EXPECT_THROW(readCameraFile(path), UnsupportedError);
}

}  // namespace
}  // namespace texgrad
