// glTF assets over several images (issue 30): the reader's materials, per-face material, each
// image's materials and sampler wrap modes, the UV set option, and the write-back that replaces
// several images of a slot at once (re-read: the new pixels, every other image unchanged).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/gltf_writer.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/mesh_texture.h"
#include "texgrad/io/texture_page_report.h"
#include "texgrad/io/texture_pages.h"
#include "two_material_gltf.h"

namespace texgrad {
namespace {

namespace fs = std::filesystem;

/// The mesh's `slot` images, in the reader's order.
std::vector<const TextureRef*> pagesOf(const TexturedMesh& mesh, const std::string& slot) {
  std::vector<const TextureRef*> refs;
  for (const TextureRef& t : mesh.textures)
    if (t.slot == slot) refs.push_back(&t);
  return refs;
}

/// The `slot` image whose materials are exactly `materials`, or nullptr.
const TextureRef* pageWithMaterials(const TexturedMesh& mesh, const std::string& slot,
                                    const std::vector<int32_t>& materials) {
  for (const TextureRef* ref : pagesOf(mesh, slot))
    if (ref->materials == materials) return ref;
  return nullptr;
}

Image decodePage(const TextureRef& ref) {
  return ref.embedded.empty() ? readImage(ref.path) : readImageFromMemory(ref.embedded, ref.origin);
}

/// True if both images have the same shape and the same 8-bit levels everywhere.
bool sameLevels(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels) return false;
  for (size_t k = 0; k < a.pixels.size(); ++k)
    if (std::lround(a.pixels[k] * 255.0f) != std::lround(b.pixels[k] * 255.0f)) return false;
  return true;
}

std::string pagesReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void pagesWriteText(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

template <typename E, typename F>
std::string pagesErrorOf(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "no exception";
}

TEST(GltfPages, ReaderFillsMaterialsFacesImagesAndSamplers) {
  const fs::path dir = test::tempDir("gltf_pages_read");
  const TexturedMesh mesh = readMesh(test::TwoMaterialGltf{}.write(dir, "two"));
  EXPECT_EQ(mesh.materials, (std::vector<std::string>{"red", "material 1", "green"}));
  EXPECT_EQ(mesh.faceMaterial, (std::vector<int32_t>{0, 0, 1, 1, 2, 2, -1, -1}));

  const std::vector<const TextureRef*> base = pagesOf(mesh, "baseColor");
  ASSERT_EQ(base.size(), 2u);  // materials 1 and 2 show one image through two textures
  const TextureRef* red = pageWithMaterials(mesh, "baseColor", {0});
  const TextureRef* shared = pageWithMaterials(mesh, "baseColor", {1, 2});
  ASSERT_NE(red, nullptr);
  ASSERT_NE(shared, nullptr);
  EXPECT_EQ(red->path.filename(), "two_0.png");
  EXPECT_EQ(shared->path.filename(), "two_1.png");
  EXPECT_EQ(red->faces, 2u);
  EXPECT_EQ(shared->faces, 4u);
  EXPECT_EQ(red->wrapU, TextureWrap::ClampToEdge);
  EXPECT_EQ(red->wrapV, TextureWrap::MirroredRepeat);
  EXPECT_EQ(shared->wrapU, TextureWrap::Repeat);  // material 1's texture has no sampler
  EXPECT_EQ(shared->wrapV, TextureWrap::Repeat);

  const std::vector<const TextureRef*> normal = pagesOf(mesh, "normal");
  ASSERT_EQ(normal.size(), 1u);
  EXPECT_EQ(normal[0]->materials, (std::vector<int32_t>{0}));
  EXPECT_EQ(normal[0]->path.filename(), "two_2.png");
}

TEST(GltfPages, UdimPagesHaveNoGltfForm) {
  // The same pages called UDIM tiles: refused in one line, nothing written.
  const fs::path dir = test::tempDir("gltf_pages_udim");
  test::TwoMaterialGltf asset;
  asset.everyMaterial = true;
  const TexturedMesh mesh = readMesh(asset.write(dir, "two"));
  PageLayout layout = findTexturePages(mesh);
  readPageSizes(layout, mesh);
  const Image image = readTexturePages(layout, mesh);
  layout.udim = true;
  const std::string message = pagesErrorOf<UnsupportedError>(
      [&] { writeGltfTexturePages(dir / "u.glb", mesh, layout, image); });
  EXPECT_NE(message.find("UDIM tiles"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "u.glb"));
  fs::remove_all(dir);
}

TEST(GltfPages, UnknownWrapModeIsOneLineNamingTheSampler) {
  const fs::path dir = test::tempDir("gltf_pages_wrap");
  const fs::path path = test::TwoMaterialGltf{}.write(dir, "two");
  std::string json = pagesReadText(path);
  json.replace(json.find("33071"), 5, "12345");
  pagesWriteText(path, json);
  const std::string message = pagesErrorOf<InvalidInputError>([&] { readMesh(path); });
  EXPECT_NE(message.find("two.gltf: sampler 0 has wrap mode 12345"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
}

TEST(GltfPages, UvSetOneReadsTexcoord1) {
  const fs::path dir = test::tempDir("gltf_pages_uvset");
  const fs::path path = test::TwoMaterialGltf{}.write(dir, "two");
  const TexturedMesh first = readMesh(path);
  MeshReadOptions options;
  options.uvSet = 1;
  const TexturedMesh second = readMesh(path, options);
  ASSERT_EQ(second.uvs.size(), first.uvs.size());
  ASSERT_EQ(second.uvTriangles, first.uvTriangles);
  // TEXCOORD_1 = 0.25 + TEXCOORD_0 / 2 in glTF's v-down; the v flip keeps that form.
  for (size_t i = 0; i < first.uvs.size(); ++i)
    EXPECT_TRUE(second.uvs[i].isApprox(Eigen::Vector2d::Constant(0.25) + first.uvs[i] / 2))
        << i << ": " << second.uvs[i].transpose() << " from " << first.uvs[i].transpose();
}

TEST(GltfPages, MissingUvSetIsOneLineNamingMeshPrimitiveAndSet) {
  const fs::path dir = test::tempDir("gltf_pages_nouv");
  test::TwoMaterialGltf asset;
  asset.secondUvSet = false;
  const fs::path path = asset.write(dir, "two");
  MeshReadOptions options;
  options.uvSet = 1;
  const std::string message = pagesErrorOf<InvalidInputError>([&] { readMesh(path, options); });
  EXPECT_NE(message.find("two.gltf: mesh 0 ('quads') primitive 2 has no TEXCOORD_1"),
            std::string::npos)
      << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
  EXPECT_NO_THROW(readMesh(path));  // set 0 is everywhere

  options.uvSet = -1;
  EXPECT_THROW(readMesh(path, options), InvalidInputError);
  options.uvSet = 1;
  const fs::path obj = dir / "one.obj";
  pagesWriteText(obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
  EXPECT_NE(pagesErrorOf<InvalidInputError>([&] { readMesh(obj, options); }).find("UV set 1"),
            std::string::npos);
}

TEST(GltfPages, WriteBackReplacesBothImagesAndKeepsTheRest) {
  const fs::path dir = test::tempDir("gltf_pages_write");
  const TexturedMesh mesh = readMesh(test::TwoMaterialGltf{}.write(dir, "two"));
  const TextureRef* red = pageWithMaterials(mesh, "baseColor", {0});
  const TextureRef* shared = pageWithMaterials(mesh, "baseColor", {1, 2});
  ASSERT_NE(red, nullptr);
  ASSERT_NE(shared, nullptr);
  const Image newRed = test::fixtureImage(5), newShared = test::fixtureImage(6);
  const std::vector<GltfImageReplacement> both = {
      {red, [&]() -> const Image& { return newRed; }},
      {shared, [&]() -> const Image& { return newShared; }}};
  for (const char* name : {"out.gltf", "out.glb"}) {
    SCOPED_TRACE(name);
    const fs::path out = dir / "written" / name;
    fs::create_directories(out.parent_path());
    EXPECT_TRUE(writeGltfWithTextures(mesh.sourcePath, out, "baseColor", both).empty());
    const TexturedMesh back = readMesh(out);
    EXPECT_EQ(back.faceMaterial, mesh.faceMaterial);
    EXPECT_EQ(back.materials, mesh.materials);
    const TextureRef* backRed = pageWithMaterials(back, "baseColor", {0});
    const TextureRef* backShared = pageWithMaterials(back, "baseColor", {1, 2});
    ASSERT_NE(backRed, nullptr);
    ASSERT_NE(backShared, nullptr);
    EXPECT_TRUE(backRed->path.empty() && backShared->path.empty());  // embedded
    EXPECT_TRUE(sameLevels(decodePage(*backRed), newRed));
    EXPECT_TRUE(sameLevels(decodePage(*backShared), newShared));
    EXPECT_EQ(backRed->wrapU, TextureWrap::ClampToEdge);  // samplers kept
    EXPECT_EQ(backRed->wrapV, TextureWrap::MirroredRepeat);
    const std::vector<const TextureRef*> normal = pagesOf(back, "normal");
    ASSERT_EQ(normal.size(), 1u);
    EXPECT_TRUE(sameLevels(decodePage(*normal[0]), test::fixtureImage(2)));
  }

  // One image of the two: the other keeps its pixels.
  const fs::path one = dir / "one.glb";
  writeGltfWithTextures(mesh.sourcePath, one, "baseColor", {both[1]});
  const TexturedMesh back = readMesh(one);
  ASSERT_NE(pageWithMaterials(back, "baseColor", {0}), nullptr);
  ASSERT_NE(pageWithMaterials(back, "baseColor", {1, 2}), nullptr);
  EXPECT_TRUE(
      sameLevels(decodePage(*pageWithMaterials(back, "baseColor", {0})), test::fixtureImage(0)));
  EXPECT_TRUE(sameLevels(decodePage(*pageWithMaterials(back, "baseColor", {1, 2})), newShared));
}

TEST(GltfPages, ReportGivesTheSizeOfEmbeddedPages) {
  const fs::path dir = test::tempDir("gltf_pages_report");
  test::TwoMaterialGltf fixture;
  fixture.everyMaterial = true;  // every face on a page, so the slot has a layout
  const TexturedMesh mesh = readMesh(fixture.write(dir, "two"));
  const fs::path out = dir / "embedded.glb";
  writeGltfWithTextures(mesh.sourcePath, out, "baseColor", {});
  const std::vector<SlotPages> slots = reportTexturePages(readMesh(out));
  const PageLayout* layout = slotLayout(slots, "baseColor");
  ASSERT_NE(layout, nullptr);
  ASSERT_EQ(layout->pages.size(), 2u);
  const Image picture = test::fixtureImage(0);
  for (const TexturePage& page : layout->pages) {
    EXPECT_TRUE(page.path.empty()) << page.name;  // embedded
    EXPECT_EQ(page.width, picture.width) << page.name;
    EXPECT_EQ(page.height, picture.height) << page.name;
  }
}

TEST(GltfPages, WriteBackRefusesAmbiguousReplacements) {
  const fs::path dir = test::tempDir("gltf_pages_refuse");
  const TexturedMesh mesh = readMesh(test::TwoMaterialGltf{}.write(dir, "two"));
  const TextureRef* red = pageWithMaterials(mesh, "baseColor", {0});
  ASSERT_NE(red, nullptr);
  const Image image = test::fixtureImage(5);
  const auto picture = [&]() -> const Image& { return image; };
  const fs::path out = dir / "out.gltf";
  EXPECT_THROW(
      writeGltfWithTextures(mesh.sourcePath, out, "baseColor", {{red, picture}, {red, picture}}),
      InvalidInputError);
  EXPECT_THROW(writeGltfWithTextures(mesh.sourcePath, out, "normal", {{red, picture}}),
               InvalidInputError);  // a baseColor image given for the normal slot
  // One processed image for a slot of two images: refused, not written over the first.
  EXPECT_THROW(writeMeshTexture(out, mesh, image), UnsupportedError);
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace texgrad
