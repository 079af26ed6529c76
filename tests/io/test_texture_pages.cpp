// Texture pages: discovery (UDIM tiles, materials), layout, placement of UVs, compose / split,
// reading every page and naming outputs; and the OBJ reader's materials.
#include <gtest/gtest.h>

#include <fstream>

#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/procedural.h"
#include "texgrad/io/texture_pages.h"

namespace texgrad {
namespace {

/// A w x h image whose texel (i, j) holds (base + i, j).
Image rampImage(int w, int h, float base) {
  Image image(w, h, 2);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      image.at(i, j, 0) = base + float(i);
      image.at(i, j, 1) = float(j);
    }
  return image;
}

/// A layout of pages of the given sizes, arranged.
PageLayout sizedLayout(const std::vector<std::pair<int, int>>& sizes) {
  PageLayout layout;
  for (const auto& [w, h] : sizes) {
    TexturePage page;
    page.name = std::to_string(layout.pages.size());
    page.width = w;
    page.height = h;
    layout.pages.push_back(page);
  }
  arrangePages(layout);
  return layout;
}

/// Writes `text` to dir / name.
void writeText(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir / name) << text;
}

/// The unit square's two faces, face f moved by tile (k_f, l_f); UV corners not shared.
TexturedMesh squareOnTiles(const std::array<std::array<int, 2>, 2>& tiles) {
  TexturedMesh mesh = procedural::square();
  const TexturedMesh base = mesh;
  mesh.uvs.clear();
  for (size_t f = 0; f < 2; ++f)
    for (int32_t& t : mesh.uvTriangles[f]) {
      mesh.uvs.push_back(base.uvs[static_cast<size_t>(t)] +
                         Eigen::Vector2d(tiles[f][0], tiles[f][1]));
      t = static_cast<int32_t>(mesh.uvs.size() - 1);
    }
  return mesh;
}

TEST(TexturePages, UdimTokensAndTilePaths) {
  EXPECT_TRUE(hasUdimToken("a/tex.<UDIM>.png"));
  EXPECT_TRUE(hasUdimToken("tex.%04d.exr"));
  EXPECT_FALSE(hasUdimToken("tex.1001.png"));
  EXPECT_EQ(udimTilePath("a/tex.<UDIM>.png", 1012), std::filesystem::path("a/tex.1012.png"));
  EXPECT_EQ(udimTilePath("tex.%04d.exr", 1001), std::filesystem::path("tex.1001.exr"));
}

TEST(TexturePages, UdimTileOfEachFaceIsTheFloorOfItsCentroid) {
  const TexturedMesh mesh = squareOnTiles({{{1, 1}, {0, 0}}});
  const PageLayout layout = findTexturePages(mesh, "baseColor", "t.<UDIM>.png");
  ASSERT_EQ(layout.pages.size(), 2u);
  EXPECT_TRUE(layout.udim);
  EXPECT_EQ(layout.pages[0].name, "1001");
  EXPECT_EQ(layout.pages[1].name, "1012");
  EXPECT_EQ(layout.pages[1].path, std::filesystem::path("t.1012.png"));
  EXPECT_EQ(layout.pages[1].tileU, 1);
  EXPECT_EQ(layout.pages[1].tileV, 1);
  EXPECT_EQ(layout.facePage, (std::vector<int32_t>{1, 0}));
}

TEST(TexturePages, FaceStraddlingTilesOrOutsideTheUdimRangeIsRefused) {
  TexturedMesh straddling = procedural::square(1.0, 1.0, 0.5, 0.0);  // u in [0.5, 1.5]
  try {
    findTexturePages(straddling, "baseColor", "t.<UDIM>.png");
    FAIL() << "a face across u = 1 was accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("straddles UDIM tiles"), std::string::npos) << e.what();
  }
  const TexturedMesh outside = squareOnTiles({{{10, 0}, {0, 0}}});
  try {
    findTexturePages(outside, "baseColor", "t.<UDIM>.png");
    FAIL() << "tile u = 10 was accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("1001..1100"), std::string::npos) << e.what();
  }
}

TEST(TexturePages, PagesAreAlignedAndApart) {
  const PageLayout layout = sizedLayout({{100, 50}, {30, 80}, {64, 10}, {56, 20}});
  for (size_t p = 0; p < layout.pages.size(); ++p) {
    EXPECT_EQ(layout.pages[p].offset % kPageAlignment, 0) << p;
    if (p > 0) {
      EXPECT_GE(layout.pages[p].offset - layout.pages[p - 1].offset - layout.pages[p - 1].width,
                kPageGap)
          << p;
    }
  }
  EXPECT_EQ(layout.pages[1].offset, 128);
  EXPECT_EQ(layout.pages[2].offset, 192);
  EXPECT_EQ(layout.pages[3].offset, 320);  // 192 + 64 + 8 = 264 -> 320
  EXPECT_EQ(layout.width, 320 + 56);
  EXPECT_EQ(layout.height, 80);
}

TEST(TexturePages, FacesReachingPastASideWidenTheGapAndOwnTheirColumns) {
  // Page 1's faces reach 0.1 (12 texels) past its left side, page 0's 0.05 (6) past its right.
  PageLayout layout = sizedLayout({{120, 8}, {120, 8}});
  EXPECT_EQ(layout.pages[1].offset, 128);  // without reach: 8 columns apart suffice
  layout.pages[0].uMax = 1.05;
  layout.pages[1].uMin = -0.1;
  arrangePages(layout);
  const auto [left, ignored] = pageReach(layout.pages[1]);
  const int rightOfPage0 = pageReach(layout.pages[0]).second;
  EXPECT_GE(left, 12);
  EXPECT_GE(rightOfPage0, 6);
  const int boundary = pageBoundary(layout, 0);
  // Every column page 1's faces reach is page 1's, every column page 0's reach is page 0's.
  EXPECT_LE(boundary, layout.pages[1].offset - left);
  EXPECT_GT(boundary, layout.pages[0].width + rightOfPage0 - 1);
  EXPECT_EQ(layout.pages[1].offset % kPageAlignment, 0);
}

TEST(TexturePages, ComposeClampsToTheNearestPageAndSplitRoundTrips) {
  const PageLayout layout = sizedLayout({{100, 50}, {30, 80}});
  const std::vector<Image> pages{rampImage(100, 50, 0.0f), rampImage(30, 80, 1000.0f)};
  const Image composed = composePages(layout, pages);
  ASSERT_EQ(composed.width, 158);
  const int middle = (100 + 128) / 2;  // the gap is columns 100..127
  for (int j = 0; j < composed.height; ++j)
    for (int x = 0; x < composed.width; ++x) {
      const size_t p = x < middle ? 0 : 1;
      const TexturePage& page = layout.pages[p];
      // What the page alone reads at its own texel (x - offset, j): the edge texel past a border.
      const Image& image = pages[p];
      const int i = std::clamp(x - page.offset, 0, page.width - 1);
      const int row = std::min(j, page.height - 1);
      ASSERT_EQ(composed.at(x, j, 0), image.at(i, row, 0)) << x << "," << j;
      ASSERT_EQ(composed.at(x, j, 1), image.at(i, row, 1)) << x << "," << j;
    }
  const std::vector<Image> split = splitPages(layout, composed);
  for (size_t p = 0; p < pages.size(); ++p) EXPECT_EQ(split[p].pixels, pages[p].pixels) << p;
}

TEST(TexturePages, PlacementMapsPageTexelsToLayoutTexelsAndDuplicatesSharedUvs) {
  TexturedMesh mesh = procedural::square();  // both faces share the UVs of corners 0 and 2
  mesh.uvs = {{0.25, 0.25}, {0.75, 0.25}, {0.75, 0.75}, {0.25, 0.75}};
  mesh.materials = {"a", "b"};
  mesh.faceMaterial = {0, 1};
  PageLayout layout;
  layout.pages = {TexturePage{}, TexturePage{}};
  layout.pages[0].width = 40, layout.pages[0].height = 20;
  layout.pages[1].width = 16, layout.pages[1].height = 32;
  layout.facePage = {0, 1};
  arrangePages(layout);
  const TexturedMesh placed = placeOnPages(mesh, layout);
  EXPECT_EQ(placed.uvs.size(), 6u);  // corners 0 and 2 are on both pages
  for (size_t f = 0; f < 2; ++f) {
    const TexturePage& page = layout.pages[f];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d& local = mesh.uvs[static_cast<size_t>(mesh.uvTriangles[f][k])];
      const Eigen::Vector2d& uv = placed.uvs[static_cast<size_t>(placed.uvTriangles[f][k])];
      // Texel coordinates on the page and in the layout differ by the page's offset only.
      EXPECT_NEAR(uv.x() * layout.width, local.x() * page.width + page.offset, 1e-12);
      EXPECT_NEAR(uv.y() * layout.height, local.y() * page.height, 1e-12);
    }
  }
}

TEST(TexturePages, OnePageIsTheImageItself) {
  const TexturedMesh mesh = procedural::cube();
  PageLayout layout = findTexturePages(mesh, "baseColor", "texture.png");
  ASSERT_TRUE(layout.single());
  layout.pages[0].width = 64, layout.pages[0].height = 32;
  arrangePages(layout);
  EXPECT_EQ(layout.width, 64);
  EXPECT_EQ(layout.height, 32);
  EXPECT_EQ(placeOnPages(mesh, layout).uvs, mesh.uvs);
  EXPECT_EQ(pageOutputPath("out.png", layout, 0), std::filesystem::path("out.png"));
}

TEST(TexturePages, OutputNamesCarryTheTileOrThePageName) {
  PageLayout layout = sizedLayout({{8, 8}, {8, 8}});
  layout.pages[0].name = "1001";
  layout.pages[1].name = "wood";
  EXPECT_EQ(pageOutputPath("dir/out.png", layout, 0), std::filesystem::path("dir/out.1001.png"));
  EXPECT_EQ(pageOutputPath("dir/out.png", layout, 1), std::filesystem::path("dir/out.wood.png"));
  EXPECT_EQ(pageOutputPath("out.<UDIM>.exr", layout, 0), std::filesystem::path("out.1001.exr"));
  EXPECT_EQ(pageOutputPath("out_%04d.tif", layout, 0), std::filesystem::path("out_1001.tif"));
}

/// A two-material OBJ: the square's faces use materials 'left' and 'right' (texture l.png,
/// clamped, and r.png).
std::filesystem::path writeTwoMaterialObj(const std::filesystem::path& dir) {
  writeText(dir, "m.mtl",
            "newmtl left\nmap_Kd -clamp on l.png\nnewmtl right\nmap_Kd r.png\n"
            "newmtl unused\nmap_Kd r.png\n");
  writeText(dir, "m.obj",
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
            "vt 0.1 0.1\nvt 0.9 0.1\nvt 0.9 0.9\nvt 0.1 0.9\n"
            "usemtl left\nf 1/1 2/2 3/3\nusemtl right\nf 1/1 3/3 4/4\n");
  return dir / "m.obj";
}

TEST(TexturePages, ObjMaterialsAndTheirImagesArePages) {
  const auto dir = test::tempDir("pages_obj");
  const TexturedMesh mesh = readMesh(writeTwoMaterialObj(dir));
  EXPECT_EQ(mesh.materials, (std::vector<std::string>{"left", "right", "unused"}));
  EXPECT_EQ(mesh.faceMaterial, (std::vector<int32_t>{0, 1}));
  ASSERT_EQ(mesh.textures.size(), 2u);
  EXPECT_EQ(mesh.textures[0].materials, (std::vector<int32_t>{0}));
  EXPECT_EQ(mesh.textures[0].wrapU, TextureWrap::ClampToEdge);
  EXPECT_EQ(mesh.textures[0].wrapV, TextureWrap::ClampToEdge);
  EXPECT_EQ(mesh.textures[1].materials, (std::vector<int32_t>{1, 2}));
  EXPECT_EQ(mesh.textures[1].wrapU, TextureWrap::Repeat);

  const PageLayout layout = findTexturePages(mesh);
  ASSERT_EQ(layout.pages.size(), 2u);
  EXPECT_FALSE(layout.udim);
  EXPECT_EQ(layout.pages[0].name, "left");
  EXPECT_EQ(layout.pages[1].name, "r");  // two materials use r.png: named after the image
  EXPECT_EQ(layout.facePage, (std::vector<int32_t>{0, 1}));
  std::filesystem::remove_all(dir);
}

TEST(TexturePages, ReadingEveryPageAndAMissingOneNamed) {
  const auto dir = test::tempDir("pages_read");
  const TexturedMesh mesh = readMesh(writeTwoMaterialObj(dir));
  PageLayout layout = findTexturePages(mesh);
  writeImage(dir / "l.png", rampImage(40, 20, 0.0f), PixelFormat::Float);
  try {
    readPageSizes(layout, mesh);
    FAIL() << "r.png is missing";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir / "r.png").string()), std::string::npos) << what;
    EXPECT_NE(what.find("page 'r'"), std::string::npos) << what;
    EXPECT_NE(what.find("1 face"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  writeImage(dir / "l.png", Image(40, 20, 3), PixelFormat::UInt8);
  Image right(24, 30, 3);
  right.pixels.assign(right.pixels.size(), 1.0f);
  writeImage(dir / "r.png", right, PixelFormat::UInt8);
  readPageSizes(layout, mesh);
  EXPECT_EQ(layout.pages[1].offset, 64);
  const Image image = readTexturePages(layout, mesh);
  EXPECT_EQ(image.width, 64 + 24);
  EXPECT_EQ(image.height, 30);
  EXPECT_EQ(pageImage(layout, image, 1).pixels, right.pixels);
  EXPECT_EQ(image.at(40, 0), 0.0f);  // the gap's left half clamps page 0 (black)
  EXPECT_EQ(image.at(63, 0), 1.0f);  // the right half page 1 (white)
  std::filesystem::remove_all(dir);
}

TEST(TexturePages, PagedImagesAreReadByTheirOutputNamesWithLabelGapsEmpty) {
  const auto dir = test::tempDir("pages_paged_read");
  PageLayout written = sizedLayout({{100, 50}, {30, 80}});
  written.pages[0].name = "1001";
  written.pages[1].name = "wood";
  const std::vector<Image> pages{rampImage(100, 50, 1.0f), rampImage(30, 80, 1000.0f)};
  const std::filesystem::path name = dir / "labels-03.exr";
  for (size_t p = 0; p < pages.size(); ++p)
    writeImage(pageOutputPath(name, written, p), pages[p], PixelFormat::Float);
  PageLayout layout = written;
  for (TexturePage& page : layout.pages) page.width = page.height = page.offset = 0;
  readPagedImageSizes(layout, name);
  for (size_t p = 0; p < pages.size(); ++p) {
    EXPECT_EQ(layout.pages[p].width, written.pages[p].width) << p;
    EXPECT_EQ(layout.pages[p].offset, written.pages[p].offset) << p;
  }
  EXPECT_EQ(readPagedImage(layout, name).pixels, composePages(layout, pages).pixels);
  const Image labels = readPagedImage(layout, name, PageGapFill::Zero);
  for (int j = 0; j < layout.height; ++j)
    for (int x = 0; x < layout.width; ++x) {
      bool inside = false;  // a texel of a page: its value; any other: no label
      for (size_t p = 0; p < pages.size(); ++p) {
        const TexturePage& page = layout.pages[p];
        if (x < page.offset || x >= page.offset + page.width || j >= page.height) continue;
        inside = true;
        ASSERT_EQ(labels.at(x, j, 0), pages[p].at(x - page.offset, j, 0)) << x << "," << j;
      }
      if (!inside) {
        ASSERT_EQ(labels.at(x, j, 0), 0.0f) << x << "," << j;
      }
    }
  std::filesystem::remove(dir / "labels-03.wood.exr");
  try {
    (void)readPagedImage(layout, name);
    FAIL() << "page 'wood' is missing";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir / "labels-03.wood.exr").string()), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace texgrad
