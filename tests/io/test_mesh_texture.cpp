// A mesh's textures as library API: readMeshTexture finds a slot's image on disk or embedded,
// writeMeshTexture writes an image file or glTF write-back, and the two round-trip.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/mesh_texture.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

namespace fs = std::filesystem;

const fs::path kAvocadoGltf = test::sharedData() / "Avocado/glTF/Avocado.gltf";

/// A W x H image of exact 8-bit levels whose rows and columns all differ (a flip shows).
Image exactLevels(int width, int height, int channels) {
  Image image(width, height, channels, PixelFormat::UInt8);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
      for (int c = 0; c < channels; ++c)
        image.at(i, j, c) = static_cast<float>((i * 7 + j * 29 + c * 61) % 256) / 255.0f;
  return image;
}

/// Number of samples whose 8-bit levels differ (all of them if the shapes differ).
size_t levelMismatches(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    return a.pixels.size() + b.pixels.size();
  size_t mismatches = 0;
  for (size_t k = 0; k < a.pixels.size(); ++k)
    mismatches += std::lround(a.pixels[k] * 255.0f) != std::lround(b.pixels[k] * 255.0f);
  return mismatches;
}

TEST(MeshTexture, SlotOnDiskIsTheFileTheAssetNames) {
  const TexturedMesh mesh = readMesh(kAvocadoGltf);
  const std::optional<Image> texture = readMeshTexture(mesh, "baseColor");
  ASSERT_TRUE(texture.has_value());
  const Image file = readImage(kAvocadoGltf.parent_path() / "Avocado_baseColor.png");
  EXPECT_EQ(levelMismatches(*texture, file), 0u);
  EXPECT_FALSE(readMeshTexture(mesh, "emissive").has_value()) << "Avocado has no emissive map";
}

TEST(MeshTexture, MeshWithoutTexturesHasNone) {
  EXPECT_FALSE(readMeshTexture(procedural::square()).has_value());
}

TEST(MeshTexture, GltfWriteBackReadsBackAsTheSlotTexture) {
  const fs::path dir = test::tempDir("mesh_texture_round_trip");
  const TexturedMesh source = readMesh(kAvocadoGltf);
  const Image image = exactLevels(40, 24, 3);
  for (const char* name : {"copy.glb", "copy.GLTF"}) {
    writeMeshTexture(dir / name, source, image, "normal");
    const TexturedMesh copy = readMesh(dir / name);
    const std::optional<Image> read = readMeshTexture(copy, "normal");
    ASSERT_TRUE(read.has_value()) << name;
    EXPECT_FALSE(copy.texture("normal")->embedded.empty()) << name << ": embedded";
    EXPECT_EQ(levelMismatches(*read, image), 0u) << name;
    EXPECT_EQ(levelMismatches(*readMeshTexture(copy, "baseColor"), *readMeshTexture(source)), 0u)
        << name << ": other slots unchanged";
  }
}

TEST(MeshTexture, ImagePathsWriteAnImageInTheAskedFormat) {
  const fs::path dir = test::tempDir("mesh_texture_image");
  const Image image = exactLevels(16, 8, 4);
  writeMeshTexture(dir / "out.PNG", procedural::square(), image);
  EXPECT_EQ(levelMismatches(readImage(dir / "out.PNG"), image), 0u);
  writeMeshTexture(dir / "wide.png", procedural::square(), image, "baseColor", PixelFormat::UInt16);
  EXPECT_EQ(readImage(dir / "wide.png").format, PixelFormat::UInt16);
}

TEST(MeshTexture, GltfOutputNeedsAMeshReadFromGltf) {
  const fs::path dir = test::tempDir("mesh_texture_not_gltf");
  try {
    writeMeshTexture(dir / "out.glb", procedural::square(), exactLevels(4, 4, 3));
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("out.glb"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(MeshTexture, UndecodableEmbeddedImageNamesMeshAndSlot) {
  TexturedMesh mesh = procedural::square();
  mesh.sourcePath = "model.glb";
  TextureRef ref;
  ref.slot = "normal";
  ref.embedded = {'n', 'o', 't', ' ', 'p', 'n', 'g'};
  ref.mimeType = "image/png";
  mesh.textures.push_back(ref);
  try {
    readMeshTexture(mesh, "normal");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("model.glb (embedded normal texture)"), std::string::npos)
        << e.what();
  }
}

TEST(MeshTexture, GltfPathsAreRecognisedInAnyCase) {
  EXPECT_TRUE(isGltfPath("a/b.gltf"));
  EXPECT_TRUE(isGltfPath("B.GLB"));
  EXPECT_FALSE(isGltfPath("b.png"));
  EXPECT_FALSE(isGltfPath("gltf"));
  EXPECT_FALSE(isGltfPath(""));
}

}  // namespace
}  // namespace texgrad
