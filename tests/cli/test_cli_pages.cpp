// Texture pages through the CLI: a mesh re-exported with two materials (half the charts each,
// the same image twice) filters to what the one-texture original gives, one image per page;
// UDIM tiles by the TEXTURE argument's token; `info` lists the pages; a missing page is named;
// a chart straddling two UDIM tiles stays continuous across their border; `texture` from photos
// over UDIM tiles gives, tile by tile, what it gives on the single image of the same charts, and
// so do `project` (each view written per tile) and `stitch` (reading them back per tile).
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>

#include "cli_runner.h"
#include "photo_scene.h"
#include "straddling_strip.h"
#include "test_paths.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/io/camera_writer.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/procedural.h"
#include "texgrad/io/texture_pages.h"
#include "two_material_gltf.h"

namespace texgrad::test {
namespace {

/// Float outputs of the two runs agree to this (they solve the same system).
constexpr double kPagesCliTolerance = 1e-6;

/// Writes `mesh` as an OBJ whose face f uses material `names[material(f)]`, each material's
/// map_Kd the matching entry of `images` (one material and image: the plain original; none: an
/// OBJ without materials).
void writeObjWithMaterials(const std::filesystem::path& obj, const TexturedMesh& mesh,
                           const std::vector<int>& faceMaterial,
                           const std::vector<std::string>& images) {
  if (!images.empty()) {
    std::ofstream mtl(obj.parent_path() / (obj.stem().string() + ".mtl"));
    for (size_t m = 0; m < images.size(); ++m)
      mtl << "newmtl m" << m << "\nmap_Kd " << images[m] << "\n";
  }
  std::ofstream out(obj);
  out.precision(17);
  if (!images.empty()) out << "mtllib " << obj.stem().string() << ".mtl\n";
  for (const Eigen::Vector3d& p : mesh.positions)
    out << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (const Eigen::Vector2d& uv : mesh.uvs) out << "vt " << uv.x() << " " << uv.y() << "\n";
  int current = -1;
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    if (!images.empty() && faceMaterial[f] != current)
      out << "usemtl m" << (current = faceMaterial[f]) << "\n";
    out << "f";
    for (int k = 0; k < 3; ++k)
      out << " " << mesh.triangles[f][k] + 1 << "/" << mesh.uvTriangles[f][k] + 1;
    out << "\n";
  }
}

/// Per face: 0 for the first half of the charts, 1 for the others.
std::vector<int> halfTheCharts(const TexturedMesh& mesh) {
  const Atlas atlas = buildAtlas(mesh);
  const auto half = static_cast<int32_t>(atlas.charts.size() / 2);
  std::vector<int> material(mesh.faceCount());
  for (size_t f = 0; f < mesh.faceCount(); ++f) material[f] = atlas.chartOfFace[f] < half ? 0 : 1;
  return material;
}

/// Filters `mesh` (texture `texture`) once as one texture and once as two materials using the
/// same image, and checks that every texel of the original's output is on one of the pages.
void expectTwoMaterialsFilterLikeOne(const TexturedMesh& mesh, const Image& texture,
                                     const std::string& name) {
  const auto dir = tempDir(name);
  writeImage(dir / "t.png", texture, PixelFormat::UInt8);
  writeObjWithMaterials(dir / "one.obj", mesh, std::vector<int>(mesh.faceCount(), 0), {"t.png"});
  std::filesystem::copy_file(dir / "t.png", dir / "u.png");
  writeObjWithMaterials(dir / "two.obj", mesh, halfTheCharts(mesh), {"t.png", "u.png"});
  const std::vector<std::string> options{"--beta",      "0.3",   "--solver", "direct",
                                         "--bit-depth", "float", "-q"};
  std::vector<std::string> one{"filter", "one.obj", "--out", "one.exr"}, two = one;
  two[1] = "two.obj";
  two[3] = "two.exr";
  one.insert(one.end(), options.begin(), options.end());
  two.insert(two.end(), options.begin(), options.end());
  const CliResult a = runCli(one, dir), b = runCli(two, dir);
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  const Image single = readImage(dir / "one.exr"), input = readImage(dir / "t.png");
  const Image m0 = readImage(dir / "two.m0.exr"), m1 = readImage(dir / "two.m1.exr");
  ASSERT_EQ(m0.width, single.width);
  ASSERT_EQ(m1.height, single.height);
  // Each page changes the texels of its charts and keeps the others; together they are the
  // original's output.
  size_t changed0 = 0, changed1 = 0;
  double worst = 0.0;
  for (size_t k = 0; k < single.pixels.size(); ++k) {
    const bool on0 = m0.pixels[k] != input.pixels[k], on1 = m1.pixels[k] != input.pixels[k];
    changed0 += on0;
    changed1 += on1;
    const float merged = on0 ? m0.pixels[k] : m1.pixels[k];
    worst = std::max(worst, std::abs(double(merged) - single.pixels[k]));
  }
  EXPECT_GT(changed0, 100u);
  EXPECT_GT(changed1, 100u);
  EXPECT_LT(worst, kPagesCliTolerance);
  std::filesystem::remove_all(dir);
}

TEST(CliPages, TwoMaterialsFilterLikeOneTexture) {
  // Every chart moved 0.07 left: the atlas' left column reaches 4.8 texels past the image's
  // left side, on each page (the layout widens the gap before the second page to hold that).
  TexturedMesh mesh = procedural::cubeSphere(8);
  for (Eigen::Vector2d& uv : mesh.uvs) uv.x() -= 0.07;
  expectTwoMaterialsFilterLikeOne(mesh, procedural::sampleTexture(120, 120), "cli_pages_two");
}

TEST(CliPagesSlow, SharedMeshWithTwoMaterialsFiltersLikeTheOriginal) {
  const auto obj = sharedData() / "spot/spot_triangulated.obj";
  if (!std::filesystem::exists(obj)) GTEST_SKIP() << "no shared data at " << obj;
  Image texture = readImage(sharedData() / "spot/spot_texture.png");
  expectTwoMaterialsFilterLikeOne(readMesh(obj), texture, "cli_pages_spot");
}

/// cubeSphere(4) with chart c moved to UDIM tile 1001 + (c % 2) + 10 ((c / 2) % 2).
TexturedMesh tiledSphere() {
  TexturedMesh mesh = procedural::cubeSphere(4);
  const Atlas atlas = buildAtlas(mesh);
  std::vector<bool> moved(mesh.uvs.size(), false);
  for (size_t f = 0; f < mesh.faceCount(); ++f)
    for (int32_t t : mesh.uvTriangles[f]) {
      if (moved[static_cast<size_t>(t)]) continue;
      moved[static_cast<size_t>(t)] = true;
      const int c = atlas.chartOfFace[f];
      mesh.uvs[static_cast<size_t>(t)] += Eigen::Vector2d(c % 2, (c / 2) % 2);
    }
  return mesh;
}

TEST(CliPages, UdimTilesAreListedProcessedAndAMissingTileNamed) {
  const auto dir = tempDir("cli_pages_udim");
  writeObjWithMaterials(dir / "tiles.obj", tiledSphere(),
                        std::vector<int>(tiledSphere().faceCount(), 0), {"t.<UDIM>.png"});
  for (const char* tile : {"1001", "1002", "1011"})
    writeImage(dir / ("t." + std::string(tile) + ".png"), procedural::sampleTexture(64, 64));

  const CliResult missing = runCli({"filter", "tiles.obj", "--out", "f.png", "-q"}, dir);
  EXPECT_EQ(missing.status, 1);
  EXPECT_EQ(lineCount(missing.err), 1) << missing.err;
  EXPECT_NE(missing.err.find("t.1012.png was not found"), std::string::npos) << missing.err;
  EXPECT_NE(missing.err.find("UDIM tile 1012"), std::string::npos) << missing.err;
  const CliResult infoMissing = runCli({"info", "tiles.obj"}, dir);
  EXPECT_NE(infoMissing.out.find("t.1012.png was not found"), std::string::npos) << infoMissing.out;

  writeImage(dir / "t.1012.png", procedural::sampleTexture(64, 64));
  const CliResult info = runCli({"info", "tiles.obj", "--json"}, dir);
  ASSERT_EQ(info.status, 0) << info.err;
  const nlohmann::json report = nlohmann::json::parse(info.out);
  // The tiles' UVs lie in their tiles: none is outside (of its tile).
  for (const nlohmann::json& issue : report["issues"])
    EXPECT_NE(issue["kind"].get<std::string>(), "uvs-outside-unit-square") << issue.dump();
  const nlohmann::json pages = report["pages"]["baseColor"];
  EXPECT_TRUE(pages["udim"].get<bool>());
  ASSERT_EQ(pages["pages"].size(), 4u);
  EXPECT_EQ(pages["pages"][3]["name"], "1012");
  EXPECT_EQ(pages["pages"][3]["width"], 64);
  EXPECT_GT(pages["pages"][3]["faces"].get<int>(), 0);
  const CliResult text = runCli({"info", "tiles.obj"}, dir);
  EXPECT_NE(text.out.find("baseColor pages 4 (UDIM tiles)"), std::string::npos) << text.out;

  const CliResult filter =
      runCli({"filter", "tiles.obj", "--out", "out.<UDIM>.png", "--beta", "0.3", "-q"}, dir);
  ASSERT_EQ(filter.status, 0) << filter.err;
  for (const char* tile : {"1001", "1002", "1011", "1012"})
    EXPECT_EQ(readImage(dir / ("out." + std::string(tile) + ".png")).width, 64) << tile;
  // Every command that makes or reads the texture writes one image per tile.
  const std::vector<std::vector<std::string>> commands{
      {"dilate", "tiles.obj", "--out", "d.<UDIM>.png"},
      {"seams", "tiles.obj", "--out", "s.<UDIM>.png"},
      {"geodesic", "tiles.obj", "--source-vertex", "0", "--out", "g.<UDIM>.exr"},
      {"lic", "tiles.obj", "-r", "64", "--out", "l.<UDIM>.png"},
      {"react", "tiles.obj", "-r", "64", "--steps", "20", "--out", "r.<UDIM>.png"}};
  for (const std::vector<std::string>& command : commands) {
    const CliResult run = runCli(command, dir);
    ASSERT_EQ(run.status, 0) << command[0] << ": " << run.err;
    const std::string pattern = command.back();
    for (const char* tile : {"1001", "1002", "1011", "1012"}) {
      std::string file = pattern;
      file.replace(file.find("<UDIM>"), 6, tile);
      EXPECT_EQ(readImage(dir / file).width, 64) << file;
    }
  }
  const CliResult gltf = runCli({"filter", "tiles.obj", "--out", "out.glb", "-q"}, dir);
  EXPECT_EQ(gltf.status, 1);
  EXPECT_EQ(lineCount(gltf.err), 1) << gltf.err;
  std::filesystem::remove_all(dir);
}

/// The embedded image of `ref` (a glTF copy texgrad wrote embeds every image).
Image embeddedImage(const TextureRef& ref) {
  EXPECT_TRUE(ref.path.empty()) << ref.path;
  return readImageFromMemory(ref.embedded, "embedded " + ref.slot);
}

TEST(CliPages, GltfOutputReplacesTheImageOfEveryMaterialPage) {
  // Two base-colour images (materials 0 | 1 and 2) are two pages: a glTF --out gets each page
  // in place of the image it came from, the same texels the image output writes for that page;
  // the normal image stays as it was.
  const auto dir = tempDir("cli_pages_gltf");
  TwoMaterialGltf fixture;
  fixture.everyMaterial = true;
  const TexturedMesh source = readMesh(fixture.write(dir, "two"));
  const PageLayout layout = findTexturePages(source);
  ASSERT_EQ(layout.pages.size(), 2u);
  for (const char* out : {"out.gltf", "out.png"}) {
    const CliResult run = runCli({"filter", "two.gltf", "--out", out, "--beta", "0.3", "-q"}, dir);
    ASSERT_EQ(run.status, 0) << out << ": " << run.err;
  }
  const TexturedMesh written = readMesh(dir / "out.gltf");
  ASSERT_EQ(written.textures.size(), source.textures.size());
  size_t replaced = 0, kept = 0;
  for (const TextureRef& ref : written.textures) {
    const Image picture = embeddedImage(ref);
    size_t same = source.textures.size();  // the source image the written one stands for
    for (size_t t = 0; t < source.textures.size(); ++t)
      if (source.textures[t].slot == ref.slot && source.textures[t].materials == ref.materials)
        same = t;
    ASSERT_LT(same, source.textures.size()) << ref.slot;
    const Image before = readImage(source.textures[same].path);
    for (size_t p = 0; p < layout.pages.size(); ++p) {
      if (ref.slot != "baseColor" || layout.pages[p].texture != static_cast<int>(same)) continue;
      const Image page = readImage(pageOutputPath(dir / "out.png", layout, p));
      EXPECT_EQ(picture.pixels, page.pixels) << layout.pages[p].name;
      EXPECT_NE(picture.pixels, before.pixels) << "the filter left page " << p << " unchanged";
      ++replaced;
    }
    if (ref.slot != "baseColor") {
      EXPECT_EQ(picture.pixels, before.pixels) << ref.slot;
      ++kept;
    }
  }
  EXPECT_EQ(replaced, 2u);
  EXPECT_EQ(kept, 1u);
  std::filesystem::remove_all(dir);
}

TEST(CliPages, InfoListsMaterialPages) {
  const auto dir = tempDir("cli_pages_info");
  const TexturedMesh mesh = procedural::cubeSphere(4);
  writeObjWithMaterials(dir / "two.obj", mesh, halfTheCharts(mesh), {"a.png", "b.png"});
  writeImage(dir / "a.png", procedural::sampleTexture(32, 16));
  const CliResult missing = runCli({"info", "two.obj"}, dir);
  EXPECT_NE(missing.out.find("b.png was not found: it is page 'm1'"), std::string::npos)
      << missing.out;
  writeImage(dir / "b.png", procedural::sampleTexture(48, 16));
  const CliResult info = runCli({"info", "two.obj"}, dir);
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_NE(info.out.find("baseColor pages 2 (one per image)"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("page m0: " + (dir / "a.png").string() + ", 32x16, "), std::string::npos)
      << info.out;
  EXPECT_NE(info.out.find("page m1: " + (dir / "b.png").string() + ", 48x16, "), std::string::npos)
      << info.out;
  // stitch reads its texture-space inputs per page: a.png is not a.m0.png, named in one line.
  const CliResult stitch = runCli(
      {"stitch", "two.obj", "--composite", "a.png", "--segments", "a.png", "--out", "s.png"}, dir);
  EXPECT_EQ(stitch.status, 1);
  EXPECT_EQ(lineCount(stitch.err), 1) << stitch.err;
  EXPECT_NE(stitch.err.find("a.m0.png"), std::string::npos) << stitch.err;
  std::filesystem::remove_all(dir);
}

TEST(CliPages, UdimTilesNamedOnTheCommandLineAreListedAndProcessed) {
  // The mesh's own texture is one image; the TEXTURE argument's UDIM token makes the tiles the
  // pages, so the UVs must stay in their tiles (not be wrapped into the first one).
  const auto dir = tempDir("cli_pages_udim_argument");
  writeObjWithMaterials(dir / "tiles.obj", tiledSphere(),
                        std::vector<int>(tiledSphere().faceCount(), 0), {"plain.png"});
  for (const char* tile : {"1001", "1002", "1011", "1012"})
    writeImage(dir / ("t." + std::string(tile) + ".png"), procedural::sampleTexture(64, 64));
  const CliResult info = runCli({"info", "tiles.obj", "--texture", "t.<UDIM>.png", "--json"}, dir);
  ASSERT_EQ(info.status, 0) << info.err;
  const auto pages = nlohmann::json::parse(info.out)["pages"]["baseColor"];
  EXPECT_TRUE(pages["udim"].get<bool>());
  EXPECT_EQ(pages["pages"].size(), 4u) << info.out;
  const CliResult filter = runCli(
      {"filter", "tiles.obj", "t.<UDIM>.png", "--out", "out.<UDIM>.png", "--beta", "0.3", "-q"},
      dir);
  ASSERT_EQ(filter.status, 0) << filter.err;
  for (const char* tile : {"1001", "1002", "1011", "1012"})
    EXPECT_TRUE(std::filesystem::exists(dir / ("out." + std::string(tile) + ".png"))) << tile;
  // The viewer shows one page: several are refused in one line, before any server starts.
  const CliResult view = runCli({"view", "tiles.obj", "t.<UDIM>.png"}, dir);
  EXPECT_EQ(view.status, 1);
  EXPECT_EQ(lineCount(view.err), 1) << view.err;
  EXPECT_NE(view.err.find("texgrad view is not supported yet"), std::string::npos) << view.err;
  std::filesystem::remove_all(dir);
}

/// A square 8-bit RGB image of uniform random texels in [lo, hi] (seeded).
Image randomTile(int size, unsigned seed, int lo, int hi) {
  Image image(size, size, 3, PixelFormat::UInt8);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> level(lo, hi);
  for (float& p : image.pixels) p = static_cast<float>(level(rng)) / 255.0f;
  return image;
}

/// RMS, over the rows whose centres the straddling strip's seam at u = 1 crosses (v in
/// [0.1, 0.9], the same rows whichever way rows run), of the difference between what a renderer
/// reads on its two sides: tile `left` at u = 1 (its last column, clamped to the edge) and tile
/// `right` at u = 0 (its first column).
double jumpAcrossTileBorder(const Image& left, const Image& right) {
  double sum = 0.0;
  int count = 0;
  for (int j = 0; j < left.height; ++j) {
    const double v = (j + 0.5) / left.height;
    if (v < 0.1 || v > 0.9) continue;
    for (int c = 0; c < left.channels; ++c, ++count)
      sum += std::pow(double(left.at(left.width - 1, j, c)) - right.at(0, j, c), 2);
  }
  return std::sqrt(sum / count);
}

TEST(CliPages, AChartStraddlingTwoUdimTilesStaysContinuousAcrossTheirBorder) {
  const auto dir = tempDir("cli_pages_straddle");
  const TexturedMesh strip = StraddlingStrip().straddling();
  writeObjWithMaterials(dir / "strip.obj", strip, std::vector<int>(strip.faceCount(), 0), {});
  constexpr int kSize = 64;
  // Dark noise left of the border, bright noise right of it: charts smoothed apart would each
  // keep their own mean, so only a seam joining them makes the output continuous.
  writeImage(dir / "tex.1001.png", randomTile(kSize, 1, 0, 127));
  writeImage(dir / "tex.1002.png", randomTile(kSize, 2, 128, 255));
  // beta 0 with a weak screening (alpha 100) smooths the noise away on both sides.
  const CliResult filter =
      runCli({"filter", "strip.obj", "tex.<UDIM>.png", "--out", "out.<UDIM>.png", "--beta", "0",
              "--alpha", "100", "--solver", "direct", "-q"},
             dir);
  ASSERT_EQ(filter.status, 0) << filter.err;
  const Image out1 = readImage(dir / "out.1001.png"), out2 = readImage(dir / "out.1002.png");
  ASSERT_EQ(out1.width, kSize);
  ASSERT_EQ(out2.width, kSize);
  const double before =
      jumpAcrossTileBorder(readImage(dir / "tex.1001.png"), readImage(dir / "tex.1002.png"));
  const double after = jumpAcrossTileBorder(out1, out2);
  EXPECT_GT(before, 0.4);
  EXPECT_LT(after, 0.25 * before) << "before " << before << ", after " << after;
  std::filesystem::remove_all(dir);
}

/// Texels per UDIM tile of the photo tests: the charts keep >= 3 texels from every tile border.
constexpr int kTileTexels = 128;

/// In `dir`: tiles.obj (tiledSphere on t.<UDIM>.png), single.obj (the same charts as the
/// quadrants of one image), photos of a sample texture on it (images/) and cameras.json.
void writeTiledPhotoScene(const std::filesystem::path& dir) {
  const TexturedMesh tiles = tiledSphere();
  TexturedMesh single = tiles;  // the 2 x 2 tiles as the quadrants of one image
  for (Eigen::Vector2d& uv : single.uvs) uv /= 2.0;
  writeObjWithMaterials(dir / "tiles.obj", tiles, std::vector<int>(tiles.faceCount(), 0),
                        {"t.<UDIM>.png"});
  writeObjWithMaterials(dir / "single.obj", single, {}, {});
  const Capture capture = captureAround(single, 6, 160, 160);
  const Image truth = procedural::sampleTexture(2 * kTileTexels, 2 * kTileTexels);
  std::filesystem::create_directories(dir / "images");
  for (size_t k = 0; k < capture.cameras.size(); ++k) {
    Image photo = renderPhoto(single, truth, capture.cameras[k], capture.looks[k]);
    photo.format = PixelFormat::UInt8;
    writeImage(dir / "images" / capture.cameras[k].name, photo);
  }
  writeCameraJson(dir / "cameras.json", capture.cameras);
}

/// The scene's mesh: tiles.obj, or single.obj.
std::string sceneMesh(bool tiles) {
  return tiles ? "tiles.obj" : "single.obj";
}

/// The scene's -r: one tile's size for tiles.obj, the four tiles' image for single.obj.
std::string sceneResolution(bool tiles) {
  return std::to_string(tiles ? kTileTexels : 2 * kTileTexels);
}

/// `head` followed by `tail`.
std::vector<std::string> joined(std::vector<std::string> head,
                                const std::vector<std::string>& tail) {
  head.insert(head.end(), tail.begin(), tail.end());
  return head;
}

/// The largest difference between the 2 x 2 tiles `tiles` (NAME -> file) and the quadrants of
/// `whole`, and the largest magnitude in `whole`.
std::pair<double, double> tilesVersusQuadrants(const std::function<Image(const char*)>& tiles,
                                               const Image& whole) {
  double worst = 0.0, range = 0.0;
  for (const auto& [name, k, l] : {std::tuple{"1001", 0, 0}, std::tuple{"1002", 1, 0},
                                   std::tuple{"1011", 0, 1}, std::tuple{"1012", 1, 1}}) {
    const Image tile = tiles(name);
    EXPECT_EQ(tile.width, kTileTexels) << name;
    if (tile.width != kTileTexels || tile.height != kTileTexels) return {1e30, 0.0};
    for (int j = 0; j < kTileTexels; ++j)
      for (int i = 0; i < kTileTexels; ++i)
        for (int c = 0; c < tile.channels; ++c) {
          const double w = whole.at(k * kTileTexels + i, l * kTileTexels + j, c);
          worst = std::max(worst, std::abs(double(tile.at(i, j, c)) - w));
          range = std::max(range, std::abs(w));
        }
  }
  return {worst, range};
}

/// The float outputs t.TILE.exr in `dir` equal the quadrants of s.exr (to kPagesCliTolerance)
/// and hold the stitched photos (a value range above 0.1).
void expectTilesMatchTheSingleImage(const std::filesystem::path& dir) {
  const auto [worst, range] = tilesVersusQuadrants(
      [&](const char* name) { return readImage(dir / ("t." + std::string(name) + ".exr")); },
      readImage(dir / "s.exr"));
  EXPECT_GT(range, 0.1);
  EXPECT_LT(worst, kPagesCliTolerance);
}

TEST(CliPages, TextureFromPhotosOverUdimTilesMatchesTheSingleImage) {
  const auto dir = tempDir("cli_pages_texture");
  writeTiledPhotoScene(dir);
  const std::vector<std::string> options{
      "--cameras", "cameras.json", "--images", "images", "--dilate-radius", "0", "--solver",
      "direct",    "--bit-depth",  "float",    "-q"};
  const auto texture = [&](bool tiles, const std::string& out) {
    return runCli(
        joined({"texture", sceneMesh(tiles), "-r", sceneResolution(tiles), "--out", out}, options),
        dir);
  };
  const CliResult a = texture(true, "t.<UDIM>.exr"), b = texture(false, "s.exr");
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  expectTilesMatchTheSingleImage(dir);
  std::filesystem::remove_all(dir);
}

TEST(CliPages, ProjectAndStitchOverUdimTilesMatchTheSingleImage) {
  const auto dir = tempDir("cli_pages_stitch");
  writeTiledPhotoScene(dir);
  const std::vector<std::string> photos{"--cameras", "cameras.json", "--images", "images", "-q"};
  const auto project = [&](bool tiles, const std::string& outDir) {
    return runCli(
        joined({"project", sceneMesh(tiles), "-r", sceneResolution(tiles), "--out-dir", outDir},
               photos),
        dir);
  };
  const CliResult pa = project(true, "pt"), pb = project(false, "ps");
  ASSERT_EQ(pa.status, 0) << pa.err;
  ASSERT_EQ(pb.status, 0) << pb.err;
  // Each view's partial is written per tile: its tiles are the single image's quadrants.
  const auto [partialWorst, partialRange] = tilesVersusQuadrants(
      [&](const char* name) {
        return readImage(dir / "pt" / ("partial-01." + std::string(name) + ".png"));
      },
      readImage(dir / "ps" / "partial-01.png"));
  EXPECT_GT(partialRange, 0.1);
  EXPECT_LT(partialWorst, kPagesCliTolerance);
  const std::vector<std::string> solve{"--solver", "direct", "--bit-depth", "float", "-q"};
  const auto stitch = [&](bool tiles, const std::string& views, const std::string& out) {
    return joined({"stitch", sceneMesh(tiles), "--partials", views + "/partial-%02d.png",
                   "--confidence", views + "/confidence-%02d.png", "--out", out},
                  solve);
  };
  const std::vector<std::string> stitchTiles = stitch(true, "pt", "t.<UDIM>.exr");
  const CliResult a = runCli(stitchTiles, dir), b = runCli(stitch(false, "ps", "s.exr"), dir);
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  expectTilesMatchTheSingleImage(dir);
  // In a --partials pattern %04d is the view number, not a UDIM token: the views renamed
  // q-0000.1001.png, ... stitch to the same tiles.
  for (const auto& entry : std::filesystem::directory_iterator(dir / "pt")) {
    const std::string name = entry.path().filename().string();  // partial-NN.TILE.png
    const std::string view = name.substr(name.find('-') + 1);
    std::filesystem::copy_file(entry.path(),
                               dir / "pt" / ((name[0] == 'p' ? "q-00" : "r-00") + view));
  }
  std::vector<std::string> renamed = stitchTiles;
  renamed[3] = "pt/q-%04d.png";
  renamed[5] = "pt/r-%04d.png";
  renamed[7] = "u.<UDIM>.exr";
  const CliResult c = runCli(renamed, dir);
  ASSERT_EQ(c.status, 0) << c.err;
  for (const char* tile : {"1001", "1002", "1011", "1012"})
    EXPECT_EQ(readImage(dir / ("u." + std::string(tile) + ".exr")).pixels,
              readImage(dir / ("t." + std::string(tile) + ".exr")).pixels)
        << tile;
  // A missing page of one view's partial is one line naming its file.
  std::filesystem::remove(dir / "pt" / "partial-01.1012.png");
  const CliResult missing = runCli(stitchTiles, dir);
  EXPECT_EQ(missing.status, 1);
  EXPECT_EQ(lineCount(missing.err), 1) << missing.err;
  EXPECT_NE(missing.err.find("partial-01.1012.png"), std::string::npos) << missing.err;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace texgrad::test
