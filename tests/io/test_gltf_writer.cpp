// glTF write-back: Avocado and BoomBox copied to .gltf and .glb with textures replaced, read back
// with readMesh (geometry unchanged, replaced slots decode to what was written, other slots still
// resolve), plus the error cases (missing slot, missing folder, bad arguments).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "silent_read_fixtures.h"
#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/gltf_writer.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kSlots = {"baseColor", "normal", "emissive", "metallicRoughness",
                                         "occlusion"};

/// A W x H gradient whose every sample is an exact 8-bit level; rows differ so a flip shows.
Image gradientImage(int width, int height, int channels, PixelFormat format = PixelFormat::UInt8) {
  Image image(width, height, channels, format);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
      for (int c = 0; c < channels; ++c) {
        const int level = (c == 0 ? i * 4 : c == 1 ? j * 4 : (i * 3 + j * 5 + c * 40)) % 256;
        image.at(i, j, c) = static_cast<float>(level) / 255.0f;
      }
  return image;
}

/// Decodes a slot's texture, embedded or on disk.
Image decodeSlot(const TexturedMesh& mesh, const std::string& slot) {
  const TextureRef* ref = mesh.texture(slot);
  if (ref == nullptr) throw InvalidInputError("no " + slot + " texture");
  return ref->embedded.empty() ? readImage(ref->path) : readImageFromMemory(ref->embedded, slot);
}

bool decodable(const TextureRef& ref) {
  return !ref.embedded.empty() || fs::exists(ref.path);
}

/// Largest |a - b| over all samples (infinity if the shapes differ).
double maxDifference(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels ||
      a.pixels.size() != b.pixels.size())
    return INFINITY;
  double worst = 0.0;
  for (size_t k = 0; k < a.pixels.size(); ++k)
    worst = std::max(worst, static_cast<double>(std::abs(a.pixels[k] - b.pixels[k])));
  return worst;
}

/// Exact comparison of 8-bit levels.
void expectSameLevels(const Image& read, const Image& written) {
  ASSERT_EQ(read.width, written.width);
  ASSERT_EQ(read.height, written.height);
  ASSERT_EQ(read.channels, written.channels);
  EXPECT_EQ(read.format, PixelFormat::UInt8);
  size_t mismatches = 0;
  for (size_t k = 0; k < read.pixels.size(); ++k)
    if (std::lround(read.pixels[k] * 255.0f) != std::lround(written.pixels[k] * 255.0f))
      ++mismatches;
  EXPECT_EQ(mismatches, 0u);
}

std::vector<std::string> filesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

void expectSameGeometry(const TexturedMesh& a, const TexturedMesh& b) {
  EXPECT_EQ(a.faceCount(), b.faceCount());
  ASSERT_EQ(a.positions.size(), b.positions.size());
  ASSERT_EQ(a.uvs.size(), b.uvs.size());
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.uvTriangles, b.uvTriangles);
  for (size_t v = 0; v < a.positions.size(); ++v)
    ASSERT_EQ(a.positions[v], b.positions[v]) << "vertex " << v;
  for (size_t v = 0; v < a.uvs.size(); ++v) ASSERT_EQ(a.uvs[v], b.uvs[v]) << "uv " << v;
}

struct Asset {
  std::string name;
  fs::path path;
};

struct WriteCase {
  Asset asset;
  std::string extension;  ///< ".gltf" or ".glb"
};

std::string caseName(const ::testing::TestParamInfo<WriteCase>& info) {
  return info.param.asset.name + "_" + info.param.extension.substr(1);
}

class GltfWriteBack : public ::testing::TestWithParam<WriteCase> {};

// Source -> copy with baseColor replaced (8-bit RGBA) -> copy of the copy with the normal map
// replaced (16-bit RGB), in a nested folder; every texture of each copy is embedded.
TEST_P(GltfWriteBack, ReplacedSlotsDecodeAndEverythingElseSurvives) {
  const WriteCase& c = GetParam();
  const fs::path dir = test::tempDir("gltf_writer_" + caseName({c, 0}));
  fs::create_directories(dir / "nested");
  const fs::path first = dir / ("first" + c.extension);
  const fs::path second = dir / "nested" / ("second" + c.extension);

  const Image baseColor = gradientImage(64, 64, 4);
  const Image normal = gradientImage(48, 32, 3, PixelFormat::UInt16);
  // One warning per missing source image: BoomBox lacks one, the first copy lacks none.
  EXPECT_EQ(writeGltfWithTexture(c.asset.path, first, "baseColor", baseColor).size(),
            c.asset.name == "BoomBox" ? 1u : 0u);
  EXPECT_TRUE(writeGltfWithTexture(first, second, "normal", normal).empty());
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{"first" + c.extension, "nested"}))
      << "one file per asset, no sidecars or temporaries";
  EXPECT_EQ(filesIn(dir / "nested"), std::vector<std::string>{"second" + c.extension});

  const TexturedMesh original = readMesh(c.asset.path);
  for (const fs::path& written : {first, second}) {
    SCOPED_TRACE(written.string());
    const TexturedMesh copy = readMesh(written);
    expectSameGeometry(original, copy);

    const TextureRef* base = copy.texture("baseColor");
    ASSERT_NE(base, nullptr);
    EXPECT_FALSE(base->embedded.empty()) << "the new texture is embedded";
    EXPECT_EQ(base->mimeType, "image/png");
    expectSameLevels(decodeSlot(copy, "baseColor"), baseColor);

    for (const std::string& slot : kSlots) {
      const TextureRef* before = original.texture(slot);
      const TextureRef* after = copy.texture(slot);
      if (before == nullptr || !decodable(*before)) {
        // BoomBox's occlusion/roughness/metallic map is absent from the shared data: the copy
        // leaves that texture out instead of referring to a missing file.
        EXPECT_EQ(after, nullptr) << slot;
        continue;
      }
      ASSERT_NE(after, nullptr) << slot;
      EXPECT_FALSE(after->embedded.empty()) << slot << " embedded (the output is self-contained)";
      if (slot == "baseColor" || (slot == "normal" && written == second)) continue;
      EXPECT_EQ(maxDifference(decodeSlot(copy, slot), decodeSlot(original, slot)), 0.0) << slot;
    }
  }

  const TexturedMesh last = readMesh(second);
  const Image normalRead = decodeSlot(last, "normal");
  EXPECT_EQ(normalRead.format, PixelFormat::UInt16) << "16-bit formats are written as 16-bit PNG";
  EXPECT_LE(maxDifference(normalRead, normal), 0.5 / 65535 + 1e-7);
}

const Asset kAvocado{"Avocado", test::sharedData() / "Avocado/glTF/Avocado.gltf"};
const Asset kBoomBox{"BoomBox", test::sharedData() / "BoomBox/glTF/BoomBox.gltf"};

INSTANTIATE_TEST_SUITE_P(Assets, GltfWriteBack,
                         ::testing::Values(WriteCase{kAvocado, ".gltf"},
                                           WriteCase{kAvocado, ".glb"},
                                           WriteCase{kBoomBox, ".gltf"},
                                           WriteCase{kBoomBox, ".glb"}),
                         caseName);

TEST(GltfWriter, OutputIsSelfContainedAfterMoving) {
  // Moved two folders deeper than where it was written, each output still resolves every image:
  // nothing refers to the source folder.
  const fs::path dir = test::tempDir("gltf_writer_moved");
  const Image image = gradientImage(16, 8, 3);
  fs::create_directories(dir / "elsewhere" / "deeper");
  for (const std::string extension : {".gltf", ".glb"}) {
    SCOPED_TRACE(extension);
    writeGltfWithTexture(kAvocado.path, dir / ("a" + extension), "baseColor", image);
    const fs::path moved = dir / "elsewhere" / "deeper" / ("b" + extension);
    fs::rename(dir / ("a" + extension), moved);
    const TexturedMesh copy = readMesh(moved);
    for (const std::string slot : {"baseColor", "normal", "metallicRoughness"}) {
      const TextureRef* ref = copy.texture(slot);
      ASSERT_NE(ref, nullptr) << slot;
      EXPECT_FALSE(ref->embedded.empty()) << slot;
      EXPECT_NO_THROW(decodeSlot(copy, slot)) << slot;
    }
    expectSameLevels(decodeSlot(copy, "baseColor"), image);
  }
}

TEST(GltfWriter, RepeatedGlbWriteBackDropsTheOldBytes) {
  // A noisy image compresses badly, so its PNG is large; replacing it again with a small image
  // must shrink the GLB by about that much (the old bytes are cut out, not left orphaned).
  const fs::path dir = test::tempDir("gltf_writer_repeat");
  Image noisy(256, 256, 3, PixelFormat::UInt8);
  uint32_t state = 12345;
  for (float& v : noisy.pixels) {
    state = state * 1664525u + 1013904223u;
    v = static_cast<float>(state >> 24) / 255.0f;
  }
  writeGltfWithTexture(kAvocado.path, dir / "a.glb", "baseColor", noisy);
  const Image small = gradientImage(8, 8, 3);
  writeGltfWithTexture(dir / "a.glb", dir / "b.glb", "baseColor", small);
  writeGltfWithTexture(dir / "b.glb", dir / "c.glb", "baseColor", small);
  const auto sizeA = fs::file_size(dir / "a.glb"), sizeB = fs::file_size(dir / "b.glb");
  EXPECT_LT(sizeB + 150000, sizeA) << "256x256x3 of noise is ~196 kB of PNG";
  EXPECT_EQ(fs::file_size(dir / "c.glb"), sizeB) << "same replacement, same size";
  const TexturedMesh original = readMesh(kAvocado.path);
  for (const char* name : {"b.glb", "c.glb"}) {
    const TexturedMesh copy = readMesh(dir / name);
    expectSameGeometry(original, copy);
    expectSameLevels(decodeSlot(copy, "baseColor"), small);
    EXPECT_EQ(maxDifference(decodeSlot(copy, "normal"), decodeSlot(original, "normal")), 0.0);
  }
}

TEST(GltfWriter, SharedTextureOfAnotherSlotIsNotModified) {
  // One texture serves normal and occlusion; replacing occlusion must leave the normal slot with
  // the original image (embedded in the copy).
  const fs::path dir = test::tempDir("gltf_writer_shared");
  std::string asset = test::fixtures::triangleGltf("color.png", "shared.png");
  const std::string normal = R"("normalTexture":{"index":1})";
  asset.replace(asset.find(normal), normal.size(), normal + R"(,"occlusionTexture":{"index":1})");
  const fs::path source = test::fixtures::write(dir, "m.gltf", asset);
  writeImage(dir / "color.png", gradientImage(8, 8, 3));
  writeImage(dir / "shared.png", gradientImage(4, 4, 3));
  const Image image = gradientImage(32, 32, 1);
  EXPECT_TRUE(writeGltfWithTexture(source, dir / "out.gltf", "occlusion", image).empty());
  const TexturedMesh copy = readMesh(dir / "out.gltf");
  expectSameLevels(decodeSlot(copy, "occlusion"), image);
  expectSameLevels(decodeSlot(copy, "normal"), gradientImage(4, 4, 3));
  expectSameLevels(decodeSlot(copy, "baseColor"), gradientImage(8, 8, 3));
}

TEST(GltfWriter, ImageAloneInItsOwnBufferIsReplacedReadably) {
  // The base colour image fills buffer 1 on its own: its replacement goes into buffer 0, and
  // buffer 1 must not be left empty (glTF readers refuse a buffer of no bytes).
  const fs::path dir = test::tempDir("gltf_writer_own_buffer");
  writeImage(dir / "color.png", gradientImage(8, 8, 3));
  std::ifstream in(dir / "color.png", std::ios::binary);
  const std::string png{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::string asset = test::fixtures::triangleGltf("color.png", "normal.png");
  const std::string image = R"({"uri":"color.png"})";
  asset.replace(asset.find(image), image.size(), R"({"bufferView":3,"mimeType":"image/png"})");
  const std::string views = R"({"buffer":0,"byteOffset":60,"byteLength":6})";
  asset.replace(asset.find(views), views.size(),
                views + R"(,{"buffer":1,"byteOffset":0,"byteLength":)" +
                    std::to_string(png.size()) + "}");
  const std::string buffersEnd = R"("}],
  "bufferViews")";
  asset.replace(asset.find(buffersEnd), buffersEnd.size(),
                R"("},{"byteLength":)" + std::to_string(png.size()) +
                    R"(,"uri":"data:application/octet-stream;base64,)" +
                    test::fixtures::base64(png) + R"("}],
  "bufferViews")");
  const fs::path source = test::fixtures::write(dir, "m.gltf", asset);
  writeImage(dir / "normal.png", gradientImage(4, 4, 3));
  expectSameLevels(decodeSlot(readMesh(source), "baseColor"), gradientImage(8, 8, 3));
  const Image replacement = gradientImage(16, 16, 3);
  writeGltfWithTexture(source, dir / "out.gltf", "baseColor", replacement);
  const TexturedMesh copy = readMesh(dir / "out.gltf");
  expectSameLevels(decodeSlot(copy, "baseColor"), replacement);
  expectSameLevels(decodeSlot(copy, "normal"), gradientImage(4, 4, 3));
}

TEST(GltfWriter, FloatImageIsStoredAs16Bit) {
  const fs::path dir = test::tempDir("gltf_writer_float");
  Image image = gradientImage(8, 8, 3, PixelFormat::Float);
  image.at(1, 2, 0) = 0.123456f;
  writeGltfWithTexture(kAvocado.path, dir / "a.glb", "baseColor", image);
  const Image read = decodeSlot(readMesh(dir / "a.glb"), "baseColor");
  EXPECT_EQ(read.format, PixelFormat::UInt16);
  EXPECT_LE(maxDifference(read, image), 0.5 / 65535 + 1e-7);

  writeGltfWithTexture(kAvocado.path, dir / "b.glb", "baseColor", image, PixelFormat::UInt8);
  EXPECT_EQ(decodeSlot(readMesh(dir / "b.glb"), "baseColor").format, PixelFormat::UInt8)
      << "an explicit format wins";
}

TEST(GltfWriter, MissingSlotThrowsNamingAssetAndSlot) {
  const fs::path dir = test::tempDir("gltf_writer_missing_slot");
  try {
    writeGltfWithTexture(kAvocado.path, dir / "a.gltf", "emissive", gradientImage(4, 4, 3));
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("Avocado.gltf"), std::string::npos) << message;
    EXPECT_NE(message.find("emissive"), std::string::npos) << message;
  }
  EXPECT_TRUE(filesIn(dir).empty());
}

TEST(GltfWriter, MissingFolderThrowsIoErrorAndLeavesNothing) {
  const fs::path dir = test::tempDir("gltf_writer_missing_folder");
  for (const char* name : {"a.gltf", "a.glb"}) {
    const fs::path target = dir / "missing" / name;
    EXPECT_THROW(writeGltfWithTexture(kAvocado.path, target, "baseColor", gradientImage(4, 4, 3)),
                 IoError);
    EXPECT_FALSE(fs::exists(dir / "missing"));
  }
  EXPECT_TRUE(filesIn(dir).empty());
}

TEST(GltfWriter, BadArgumentsAreRejected) {
  const fs::path dir = test::tempDir("gltf_writer_bad_arguments");
  const Image image = gradientImage(4, 4, 3);
  EXPECT_THROW(writeGltfWithTexture(kAvocado.path, dir / "a.gltf", "diffuse", image),
               InvalidInputError);
  EXPECT_THROW(writeGltfWithTexture(kAvocado.path, dir / "a.obj", "baseColor", image),
               UnsupportedError);
  EXPECT_THROW(writeGltfWithTexture(kAvocado.path, dir / "a.gltf", "baseColor", Image()),
               InvalidInputError);
  EXPECT_THROW(writeGltfWithTexture(dir / "none.gltf", dir / "a.gltf", "baseColor", image),
               IoError);
  EXPECT_TRUE(filesIn(dir).empty());
}

TEST(GltfWriter, OverwritesAnExistingTargetAtomically) {
  const fs::path dir = test::tempDir("gltf_writer_overwrite");
  { std::ofstream(dir / "a.glb") << "old content"; }
  writeGltfWithTexture(kAvocado.path, dir / "a.glb", "normal", gradientImage(8, 8, 3));
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"a.glb"});
  expectSameLevels(decodeSlot(readMesh(dir / "a.glb"), "normal"), gradientImage(8, 8, 3));
}

}  // namespace
}  // namespace texgrad
