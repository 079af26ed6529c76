// `texgrad project` and `texgrad texture` on a synthetic capture of spot (photos rendered by the
// test support's ray caster, cameras written as a COLMAP text model and as camera JSON).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_runner.h"
#include "photo_renderer.h"
#include "photo_scene.h"
#include "test_paths.h"
#include "texgrad/io/camera_writer.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad::test {
namespace {

constexpr int kTexels = 256;

/// Writes a capture of spot to `dir`: images/view*.png (8-bit), sparse/ (COLMAP text model) and
/// cameras.json; returns the band-limited true texture.
Image writeCapture(const std::filesystem::path& dir, const TexturedMesh& mesh,
                   std::vector<Camera>& cameras) {
  const Image truth = tentBlur(
      boxDownsample(readImage(sharedData() / "spot/spot_texture.png"), kTexels, kTexels), 2);
  const Capture capture = captureAround(mesh, 8, 320, 320);
  std::filesystem::create_directories(dir / "images");
  for (size_t k = 0; k < capture.cameras.size(); ++k) {
    Image photo = renderPhoto(mesh, truth, capture.cameras[k], capture.looks[k]);
    photo.format = PixelFormat::UInt8;
    writeImage(dir / "images" / capture.cameras[k].name, photo);
  }
  cameras = capture.cameras;
  return truth;
}

TEST(CliPhoto, CameraThatSeesNothingIsAWarningNotAFailure) {
  const auto dir = tempDir("cli_photo_coverage");
  const Camera front = lookAtCamera("front.png", {0.0, 0.0, 4.0}, Eigen::Vector3d::Zero(),
                                    Eigen::Vector3d::UnitY(), 64, 48, 60.0);
  Camera away = front;
  away.name = "away.png";
  away.R = Eigen::Vector3d(-1.0, 1.0, -1.0).asDiagonal() * front.R;
  away.t = -away.R * front.centre();
  std::filesystem::create_directories(dir / "images");
  for (const Camera& c : {front, away})
    writeImage(dir / "images" / c.name, Image(c.width, c.height, 3, PixelFormat::UInt8));
  writeCameraJson(dir / "both.json", {front, away});
  writeCameraJson(dir / "away.json", {away});

  const CliResult r = runCli({"project", "builtin:cube", "--cameras", "both.json", "--images",
                              "images", "-r", "64", "--out-dir", "views"},
                             dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("texgrad: warning: camera 'away.png' sees no texel"), std::string::npos)
      << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "views/partial-00.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "views/partial-01.png"));

  // No camera sees the mesh: texture stops with one error line after the warning.
  const CliResult none = runCli({"texture", "builtin:cube", "--cameras", "away.json", "--images",
                                 "images", "-r", "64", "--out", "t.png"},
                                dir);
  EXPECT_EQ(none.status, 1);
  EXPECT_NE(none.err.find("texgrad: error: no camera"), std::string::npos) << none.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "t.png"));
}

TEST(CliPhoto, TextureFromSyntheticCaptureBeatsBestViewSlow) {
  const auto dir = tempDir("cli_photo_texture");
  const std::string spot = (sharedData() / "spot/spot_triangulated.obj").string();
  const TexelDomain domain(readMesh(spot), kTexels, kTexels);
  std::vector<Camera> cameras;
  const Image truth = writeCapture(dir, domain.mesh(), cameras);
  // A ninth camera where the first is, turned around: sees nothing, warns, is skipped.
  Camera away = cameras[0];
  away.name = "away.png";
  away.R = Eigen::Vector3d(-1.0, 1.0, -1.0).asDiagonal() * cameras[0].R;
  away.t = -away.R * cameras[0].centre();
  writeImage(dir / "images" / away.name, Image(away.width, away.height, 3, PixelFormat::UInt8));
  cameras.push_back(away);
  writeColmapText(dir / "sparse", cameras);
  writeCameraJson(dir / "cameras.json", cameras);

  const CliResult projected = runCli({"project", spot, "--cameras", "sparse", "--images", "images",
                                      "--resolution", "256", "--out-dir", "views", "--json"},
                                     dir);
  ASSERT_EQ(projected.status, 0) << projected.err;
  EXPECT_NE(projected.err.find("warning: camera 'away.png' sees no texel"), std::string::npos)
      << projected.err;
  const auto summary = nlohmann::json::parse(projected.out);
  ASSERT_EQ(summary["views"].size(), 8u);
  // The best-view composite, from the files `project` wrote.
  Image composite, segments, seen;
  for (int k = 0; k < 8; ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "views/partial-%02d.png", k);
    const Image partial = readImage(dir / name);
    std::snprintf(name, sizeof name, "views/confidence-%02d.png", k);
    const Image confidence = readImage(dir / name);
    if (k == 0) {
      composite = partial;
      segments = Image(kTexels, kTexels, 1);
      seen = Image(kTexels, kTexels, 1);
    }
    for (size_t p = 0; p < seen.pixels.size(); ++p)
      if (confidence.pixels[p] > seen.pixels[p]) {
        seen.pixels[p] = confidence.pixels[p];
        segments.pixels[p] = static_cast<float>(k + 1);
        for (size_t c = 0; c < 3; ++c) composite.pixels[3 * p + c] = partial.pixels[3 * p + c];
      }
  }

  const CliResult textured = runCli({"texture", spot, "--cameras", "sparse", "--images", "images",
                                     "--resolution", "256", "--out", "colmap.png", "--json"},
                                    dir);
  ASSERT_EQ(textured.status, 0) << textured.err;
  const auto stages = nlohmann::json::parse(textured.out)["stages"];
  for (const char* stage : {"read", "operators", "project", "stitch", "dilate", "write"})
    EXPECT_TRUE(stages.contains(stage)) << stage;
  const Image result = readImage(dir / "colmap.png");
  const double error = fittedRms(domain, result, truth, seen);
  const double compositeError = fittedRms(domain, composite, truth, seen);
  const double jump = regionBoundaryJump(domain, result, truth, segments);
  const double compositeJump = regionBoundaryJump(domain, composite, truth, segments);
  std::cout << "texture: fitted RMS " << error << " vs best view " << compositeError
            << "; region-boundary jump " << jump << " vs " << compositeJump << "\n";
  EXPECT_LE(error, compositeError / 3.0);
  EXPECT_LE(jump, compositeJump / 10.0);

  // The same capture through the camera JSON gives the same texture.
  const CliResult fromJson = runCli({"texture", spot, "--cameras", "cameras.json", "--images",
                                     "images", "--resolution", "256", "--out", "json.png", "-q"},
                                    dir);
  ASSERT_EQ(fromJson.status, 0) << fromJson.err;
  EXPECT_EQ(readImage(dir / "json.png").pixels, result.pixels);

  // --select best: one view per texel, jumps between the regions removed. The composite mode
  // drops every gradient across a region boundary (paper Sec. 7.2), the true texture's too, so
  // its boundary jump stays above the blended result's.
  const CliResult selected =
      runCli({"texture", spot, "--cameras", "sparse", "--images", "images", "--resolution", "256",
              "--select", "best", "--out", "best.png", "-q"},
             dir);
  ASSERT_EQ(selected.status, 0) << selected.err;
  const Image bestResult = readImage(dir / "best.png");
  const double bestError = fittedRms(domain, bestResult, truth, seen);
  const double bestJump = regionBoundaryJump(domain, bestResult, truth, segments);
  std::cout << "texture --select best: fitted RMS " << bestError << ", jump " << bestJump << "\n";
  EXPECT_LE(bestError, compositeError / 2.0);
  EXPECT_LE(bestJump, compositeJump / 2.0);
}

}  // namespace
}  // namespace texgrad::test
