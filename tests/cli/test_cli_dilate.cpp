// `texgrad dilate` like the other processing commands: --json says what it did, and a .gltf/.glb
// output is a copy of the mesh's asset with the padded texture in the processed slot.
#include <gtest/gtest.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.h"
#include "silent_read_fixtures.h"
#include "test_paths.h"
#include "texgrad/io/image.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad::test::cli_dilate {
namespace {

namespace fs = std::filesystem;

/// A W x H RGB image whose texels all differ from their neighbours (so padding changes them).
Image ramp(int width, int height) {
  Image image(width, height, 3, PixelFormat::UInt8);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
      for (int c = 0; c < 3; ++c)
        image.at(i, j, c) = static_cast<float>((i * 7 + j * 13 + c * 50) % 256) / 255.0f;
  return image;
}

/// Texels (any channel) where two images differ; -1 if their shapes differ.
int64_t differingTexels(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels) return -1;
  int64_t count = 0;
  for (int j = 0; j < a.height; ++j)
    for (int i = 0; i < a.width; ++i)
      for (int c = 0; c < a.channels; ++c)
        if (a.at(i, j, c) != b.at(i, j, c)) {
          ++count;
          break;
        }
  return count;
}

TEST(CliDilate, JsonCountsTheActiveTexelsAndTheTexelsItChanged) {
  const fs::path dir = tempDir("cli_dilate_json");
  fixtures::write(dir, "square.obj", fixtures::squareObj(""));
  writeImage(dir / "tex.png", ramp(32, 32));
  const CliResult r = runCli({"dilate", "square.obj", "tex.png", "--radius", "2", "-o", "out.exr",
                              "--bit-depth", "float", "--json"},
                             dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["command"], "dilate");
  EXPECT_EQ(j["radius"], 2);
  EXPECT_EQ(j["output"], "out.exr");
  EXPECT_EQ(j["resolution"], nlohmann::json::array({32, 32}));
  EXPECT_TRUE(j["stages"].contains("write")) << j;
  const CliResult info = runCli({"info", "square.obj", "-r", "32", "--json"}, dir);
  ASSERT_EQ(info.status, 0) << info.err;
  const auto texels = nlohmann::json::parse(info.out)["texels"];
  EXPECT_EQ(j["texels"], texels["active"]) << texels;
  // A float output holds the padded values exactly (an 8-bit one could round a change away).
  const int64_t changed = differingTexels(readImage(dir / "tex.png"), readImage(dir / "out.exr"));
  EXPECT_GT(changed, 0);
  EXPECT_EQ(j["changed_texels"], changed);
}

TEST(CliDilate, GltfOutputIsTheAssetWithThePaddedSlot) {
  // The .gltf copy's normal texture decodes to what the same command writes as a PNG; the
  // baseColor texture is the source's, embedded.
  const fs::path dir = tempDir("cli_dilate_gltf");
  fixtures::write(dir, "m.gltf", fixtures::triangleGltf("color.png", "normal.png"));
  writeImage(dir / "color.png", ramp(16, 16));
  writeImage(dir / "normal.png", ramp(16, 8));
  for (const char* out : {"out.gltf", "out.png"}) {
    const CliResult r =
        runCli({"dilate", "m.gltf", "--texture-slot", "normal", "-q", "-o", out}, dir);
    ASSERT_EQ(r.status, 0) << out << ": " << r.err;
    EXPECT_EQ(r.err, "");
  }
  const TexturedMesh copy = readMesh(dir / "out.gltf");
  for (const char* slot : {"baseColor", "normal"}) {
    ASSERT_NE(copy.texture(slot), nullptr) << slot;
    EXPECT_FALSE(copy.texture(slot)->embedded.empty()) << slot;
  }
  const Image normal = readImageFromMemory(copy.texture("normal")->embedded, "normal");
  const Image padded = readImage(dir / "out.png");
  EXPECT_EQ(differingTexels(normal, padded), 0);
  EXPECT_GT(differingTexels(padded, readImage(dir / "normal.png")), 0) << "padding changed it";
  EXPECT_EQ(differingTexels(readImageFromMemory(copy.texture("baseColor")->embedded, "color"),
                            readImage(dir / "color.png")),
            0);
}

}  // namespace
}  // namespace texgrad::test::cli_dilate
