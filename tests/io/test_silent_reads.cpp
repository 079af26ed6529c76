// No silent partial reads (issue 27): each input a reader used to accept with part of it lost
// is refused with a typed exception whose message names the file and the line or element.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "silent_read_fixtures.h"
#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/mesh_texture.h"

namespace texgrad::silent_reads_test {

namespace fs = std::filesystem;
namespace fx = test::fixtures;

/// The message of the E that `action` throws ("" and a test failure if it throws none).
template <typename E, typename F>
std::string thrown(F&& action) {
  try {
    action();
  } catch (const E& e) {
    return e.what();
  }
  ADD_FAILURE() << "no exception of the expected type";
  return "";
}

/// Expects every one of `parts` in `message`.
void expectNames(const std::string& message, std::initializer_list<std::string> parts) {
  for (const std::string& part : parts)
    EXPECT_NE(message.find(part), std::string::npos) << "missing '" << part << "' in: " << message;
}

/// A small 8-bit RGB image (contents do not matter).
void writePng(const fs::path& path) {
  writeImage(path, Image(4, 4, 3, PixelFormat::UInt8));
}

TEST(SilentReads, ObjCutInAFaceLineNamesTheLine) {
  const fs::path obj = fx::write(test::tempDir("silent_cut"), "cut.obj", fx::truncatedObj());
  expectNames(thrown<InvalidInputError>([&] { readMesh(obj); }), {"cut.obj line 10", "2 corners"});
}

TEST(SilentReads, ObjMalformedCornersNameTheLine) {
  const fs::path dir = test::tempDir("silent_corner");
  for (const char* face :
       {"f 1/1 2/x 3/3\n", "f 1/1 2/2 3.5/3\n", "f 1/1 0/2 3/3\n", "f 1/1 2/2 -9/3\n",
        "f 1/1 2/2 -9223372036854775808/3\n", "f 1/1 2/2 3/3/3/3\n"}) {
    const fs::path obj = fx::write(dir, "bad.obj", fx::squareObj("", face));
    expectNames(thrown<InvalidInputError>([&] { readMesh(obj); }), {"bad.obj line 9"});
  }
  const fs::path far = fx::write(dir, "far.obj", fx::squareObj("", "f 1/1 2/2 3/7\n"));
  expectNames(thrown<InvalidInputError>([&] { readMesh(far); }),
              {"far.obj line 9", "texture coordinate 7", "has 4"});
}

/// two.obj: material 'red' on one triangle, 'blue' on a triangle and a quad (3 faces once fanned).
std::string unevenTwoMaterialObj() {
  return fx::squareObj("mtllib two.mtl\n", "usemtl red\n", "usemtl blue\nf 1/1 2/2 3/3 4/4\n");
}

TEST(SilentReads, TwoMaterialsWithTwoTexturesAreRefusedByNameAndFaceCount) {
  const fs::path dir = test::tempDir("silent_two");
  fx::write(dir, "two.mtl", fx::twoMaterialMtl("red.png", "blue.png"));
  writePng(dir / "red.png");
  writePng(dir / "blue.png");
  const TexturedMesh mesh = readMesh(fx::write(dir, "two.obj", unevenTwoMaterialObj()));
  EXPECT_EQ(mesh.faceCount(), 4u);
  expectNames(
      thrown<UnsupportedError>([&] { readMeshTexture(mesh, "baseColor"); }),
      {"two.obj", "2 different baseColor textures", "material 'red' (map_Kd 'red.png') on 1 face,",
       "material 'blue' (map_Kd 'blue.png') on 3 faces"});
}

TEST(SilentReads, TwoMaterialsSharingATextureAreRead) {
  const fs::path dir = test::tempDir("silent_shared");
  fx::write(dir, "two.mtl", fx::twoMaterialMtl("same.png", "same.png"));
  writePng(dir / "same.png");
  const TexturedMesh mesh = readMesh(fx::write(dir, "two.obj", unevenTwoMaterialObj()));
  ASSERT_NE(mesh.texture("baseColor"), nullptr);
  EXPECT_EQ(mesh.texture("baseColor")->faces, 4u) << "both materials' faces";
  const std::optional<Image> texture = readMeshTexture(mesh, "baseColor");
  ASSERT_TRUE(texture.has_value());
  EXPECT_EQ(texture->width, 4);
}

TEST(SilentReads, MissingMtlNamesTheMtllibLine) {
  const fs::path dir = test::tempDir("silent_mtl");
  const TexturedMesh mesh = readMesh(fx::write(dir, "nomtl.obj", fx::missingMtlObj()));
  ASSERT_EQ(mesh.missingFiles.size(), 1u);
  expectNames(thrown<IoError>([&] { readMeshTexture(mesh, "baseColor"); }),
              {"nomtl.obj line 1", "'gone.mtl'", "was not found"});
}

TEST(SilentReads, OverlongFileNamesInAnObjAreReportedAsNotFound) {
  // A name longer than the system's limit (NAME_MAX, 255 on Linux) made std::filesystem::exists
  // throw, which ended the process as an internal error (found by fuzz_obj in CI).
  const fs::path dir = test::tempDir("silent_long_name");
  const std::string longName(300, 'a');
  const TexturedMesh noLibrary =
      readMesh(fx::write(dir, "longlib.obj", fx::squareObj("mtllib " + longName + ".mtl\n")));
  ASSERT_EQ(noLibrary.missingFiles.size(), 1u);
  EXPECT_NE(noLibrary.missingFiles[0].find("was not found"), std::string::npos);

  fx::write(dir, "long.mtl", "newmtl paint\nmap_Kd " + longName + ".png\n");
  const TexturedMesh mesh =
      readMesh(fx::write(dir, "longmap.obj", fx::squareObj("mtllib long.mtl\n", "usemtl paint\n")));
  expectNames(thrown<IoError>([&] { readMeshTexture(mesh, "baseColor"); }),
              {"longmap.obj", "was not found"});
}

TEST(SilentReads, MissingGltfImageNamesAssetIndexAndUri) {
  const fs::path dir = test::tempDir("silent_gltf_read");
  const fs::path gltf = fx::write(dir, "m.gltf", fx::triangleGltf("gone.png", "normal.png"));
  writePng(dir / "normal.png");
  const TexturedMesh mesh = readMesh(gltf);
  expectNames(thrown<IoError>([&] { readMeshTexture(mesh, "baseColor"); }),
              {"m.gltf", "image 0", "URI 'gone.png'"});
  EXPECT_TRUE(readMeshTexture(mesh, "normal").has_value());  // only the slot processed matters
  EXPECT_EQ(mesh.texture("normal")->faces, 1u);
}

/// The text of a written file.
std::string fileText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

TEST(SilentReads, GltfWriteBackLeavesAMissingImageOutWithAWarning) {
  // The normal map's file is missing; processing baseColor writes a copy whose normal slot has no
  // texture (never a dangling URI) and returns one warning naming the image.
  const fs::path dir = test::tempDir("silent_gltf_write");
  const fs::path gltf = fx::write(dir, "m.gltf", fx::triangleGltf("color.png", "gone.png"));
  writePng(dir / "color.png");
  const TexturedMesh mesh = readMesh(gltf);
  const Image image = *readMeshTexture(mesh, "baseColor");
  for (const char* name : {"out.gltf", "out.glb"}) {
    SCOPED_TRACE(name);
    const WrittenTexture written = writeMeshTexture(dir / name, mesh, image);
    ASSERT_EQ(written.warnings.size(), 1u);
    expectNames(written.warnings[0], {"m.gltf", "image 1", "URI 'gone.png'", name});
    EXPECT_EQ(fileText(dir / name).find("gone.png"), std::string::npos);
    const TexturedMesh copy = readMesh(dir / name);
    EXPECT_EQ(copy.texture("normal"), nullptr);
    ASSERT_NE(copy.texture("baseColor"), nullptr);
    EXPECT_FALSE(copy.texture("baseColor")->embedded.empty());
  }
}

TEST(SilentReads, GltfWriteBackRenumbersWhatFollowsAMissingImage) {
  // Images color (0), gone (1, missing), sheen (2); a clearcoat extension refers to textures 1
  // and 2. The copy keeps images/textures 0 and 2 (now 1), drops the extension's reference to
  // the missing one and renumbers the other.
  const fs::path dir = test::tempDir("silent_gltf_renumber");
  std::string asset = fx::triangleGltf("color.png", "gone.png");
  const auto replace = [&](const std::string& from, const std::string& to) {
    asset.replace(asset.find(from), from.size(), to);
  };
  replace(R"("normalTexture":{"index":1})",
          R"("normalTexture":{"index":1},"extensions":{"KHR_materials_clearcoat":)"
          R"({"clearcoatTexture":{"index":1},"clearcoatRoughnessTexture":{"index":2}}})");
  replace(R"({"source":1}])", R"({"source":1},{"source":2}])");
  replace(R"({"uri":"gone.png"}])", R"({"uri":"gone.png"},{"uri":"sheen.png"}])");
  replace(R"("scene":0,)", R"("scene":0,"extensionsUsed":["KHR_materials_clearcoat"],)");
  const fs::path gltf = fx::write(dir, "m.gltf", asset);
  writePng(dir / "color.png");
  writePng(dir / "sheen.png");
  const TexturedMesh mesh = readMesh(gltf);
  ASSERT_EQ(writeMeshTexture(dir / "out.gltf", mesh, *readMeshTexture(mesh)).warnings.size(), 1u);
  const std::string text = fileText(dir / "out.gltf");
  EXPECT_EQ(text.find("gone.png"), std::string::npos);
  const nlohmann::json out = nlohmann::json::parse(text);
  EXPECT_EQ(out["images"].size(), 2u);
  ASSERT_EQ(out["textures"].size(), 2u);
  EXPECT_EQ(out["textures"][1]["source"], 1);
  const nlohmann::json& material = out["materials"][0];
  EXPECT_FALSE(material.contains("normalTexture")) << material;
  const nlohmann::json& clearcoat = material["extensions"]["KHR_materials_clearcoat"];
  EXPECT_FALSE(clearcoat.contains("clearcoatTexture")) << material;
  EXPECT_EQ(clearcoat["clearcoatRoughnessTexture"]["index"], 1) << material;
}

}  // namespace texgrad::silent_reads_test
