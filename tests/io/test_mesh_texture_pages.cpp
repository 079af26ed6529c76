// One image or several pages, read and written in one call (mesh_texture_pages.h): one image is
// what readImage reads; pages written are read back as they were.
#include <gtest/gtest.h>

#include <fstream>

#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/mesh_texture_pages.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

/// A w x h RGB image, 8-bit, whose texels differ from each other's and from other seeds'.
Image patternImage(int w, int h, int seed) {
  Image image(w, h, 3, PixelFormat::UInt8);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      for (int c = 0; c < 3; ++c)
        image.at(i, j, c) = float((seed * 37 + i * 7 + j * 13 + c * 5) % 256) / 255.0f;
  return image;
}

/// A texture callback for meshes that must name their texture.
Image noTextureExpected() {
  throw InvalidInputError("the mesh's own texture was expected");
}

/// The square's two faces on materials 'left' (l.png) and 'right' (r.png): two pages.
TexturedMesh twoMaterialSquare(const std::filesystem::path& dir) {
  std::ofstream(dir / "m.mtl") << "newmtl left\nmap_Kd l.png\nnewmtl right\nmap_Kd r.png\n";
  std::ofstream(dir / "m.obj") << "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                  "vt 0.1 0.1\nvt 0.9 0.1\nvt 0.9 0.9\nvt 0.1 0.9\n"
                                  "usemtl left\nf 1/1 2/2 3/3\nusemtl right\nf 1/1 3/3 4/4\n";
  writeImage(dir / "l.png", patternImage(40, 20, 1), PixelFormat::UInt8);
  writeImage(dir / "r.png", patternImage(24, 30, 2), PixelFormat::UInt8);
  return readMesh(dir / "m.obj");
}

/// Writes the layout image of `read` to `out` and expects every page file to hold its page.
void expectPagesWrittenAsRead(const TexturedMesh& mesh, const MeshTexturePages& read,
                              const std::filesystem::path& out) {
  const WrittenTexturePages written = writeMeshTexturePages(out, mesh, read.layout, read.image);
  ASSERT_EQ(written.files.size(), read.layout.pages.size());
  for (size_t p = 0; p < written.files.size(); ++p) {
    EXPECT_EQ(written.files[p], pageOutputPath(out, read.layout, p));
    EXPECT_EQ(readImage(written.files[p]).pixels, pageImage(read.layout, read.image, p).pixels)
        << written.files[p];
  }
  EXPECT_EQ(readPagedImage(read.layout, out).pixels, read.image.pixels);
}

TEST(MeshTexturePages, OneImageIsOnePageEqualToReadImage) {
  const auto dir = test::tempDir("mesh_pages_one");
  const TexturedMesh mesh = procedural::cube();
  const std::filesystem::path file = dir / "texture.png";
  writeImage(file, patternImage(48, 32, 3), PixelFormat::UInt8);
  const MeshTexturePages read = readMeshTexturePages(mesh, "baseColor", file, noTextureExpected);
  ASSERT_TRUE(read.layout.single());
  EXPECT_FALSE(read.placed);  // the mesh's own UVs
  EXPECT_EQ(read.image.pixels, readImage(file).pixels);
  EXPECT_EQ(read.layout.width, 48);
  EXPECT_EQ(read.layout.height, 32);
  expectPagesWrittenAsRead(mesh, read, dir / "out.png");
  EXPECT_TRUE(std::filesystem::exists(dir / "out.png"));  // one page: `out` itself

  int calls = 0;  // a mesh naming no texture: the callback's image is the page
  const MeshTexturePages made = readMeshTexturePages(mesh, "baseColor", {}, [&] {
    ++calls;
    return patternImage(16, 8, 4);
  });
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(made.image.pixels, patternImage(16, 8, 4).pixels);
  EXPECT_EQ(made.layout.width, 16);
  std::filesystem::remove_all(dir);
}

TEST(MeshTexturePages, MaterialPagesWrittenAreReadBackAsTheyWere) {
  const auto dir = test::tempDir("mesh_pages_materials");
  const TexturedMesh mesh = twoMaterialSquare(dir);
  const MeshTexturePages read = readMeshTexturePages(mesh, "baseColor", {}, noTextureExpected);
  ASSERT_EQ(read.layout.pages.size(), 2u);
  ASSERT_TRUE(read.placed);
  EXPECT_EQ(read.placed->uvs, placeOnPages(mesh, read.layout).uvs);
  EXPECT_EQ(pageImage(read.layout, read.image, 0).pixels, readImage(dir / "l.png").pixels);
  EXPECT_EQ(pageImage(read.layout, read.image, 1).pixels, readImage(dir / "r.png").pixels);
  expectPagesWrittenAsRead(mesh, read, dir / "out.png");

  const MeshPages sized = placeMeshOnPages(mesh, "baseColor", {}, std::nullopt);  // headers
  EXPECT_EQ(sized.layout.width, read.layout.width);
  EXPECT_EQ(sized.layout.height, read.layout.height);
  const MeshPages made = placeMeshOnPages(mesh, "baseColor", {}, std::pair(16, 8));
  for (const TexturePage& page : made.layout.pages) {
    EXPECT_EQ(page.width, 16);
    EXPECT_EQ(page.height, 8);
  }
  std::filesystem::remove_all(dir);
}

TEST(MeshTexturePages, UdimTilesWrittenAreReadBackAsTheyWere) {
  const auto dir = test::tempDir("mesh_pages_udim");
  const std::filesystem::path tiles = dir / "t.<UDIM>.png";
  writeImage(dir / "t.1001.png", patternImage(32, 16, 5), PixelFormat::UInt8);
  writeImage(dir / "t.1002.png", patternImage(20, 16, 6), PixelFormat::UInt8);
  // One tile (1001): a single() layout, but read through its tile's name.
  const TexturedMesh one = procedural::square();
  const MeshTexturePages first = readMeshTexturePages(one, "baseColor", tiles, noTextureExpected);
  EXPECT_TRUE(first.layout.udim);
  EXPECT_EQ(first.image.pixels, readImage(dir / "t.1001.png").pixels);
  // Two tiles: the square's UVs over [0, 2] x [0, 1], cut at the tile border.
  const TexturedMesh two = meshForPages(procedural::square(2.0), UvWrap{}, "baseColor", tiles).mesh;
  const MeshTexturePages read = readMeshTexturePages(two, "baseColor", tiles, noTextureExpected);
  ASSERT_EQ(read.layout.pages.size(), 2u);
  EXPECT_EQ(pageImage(read.layout, read.image, 1).pixels, readImage(dir / "t.1002.png").pixels);
  expectPagesWrittenAsRead(two, read, dir / "out.<UDIM>.png");
  EXPECT_TRUE(std::filesystem::exists(dir / "out.1002.png"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace texgrad
