// CLI contract for the inputs readers used to accept with part of them silently lost (issue 27):
// one line on stderr naming the file and line or element, non-zero status, no output file.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "cli_runner.h"
#include "silent_read_fixtures.h"
#include "test_paths.h"
#include "texgrad/io/image.h"
#include "texgrad/io/image_io.h"

namespace texgrad::test::cli_silent_reads {

namespace fs = std::filesystem;

/// Runs `args` in `dir` and expects the bad-input contract with every one of `parts` named.
void expectRefused(const std::vector<std::string>& args, const fs::path& dir,
                   const std::string& output, std::initializer_list<std::string> parts) {
  const CliResult r = runCli(args, dir);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(lineCount(r.err), 1) << r.err;
  for (const std::string& part : parts)
    EXPECT_NE(r.err.find(part), std::string::npos) << "missing '" << part << "' in: " << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  if (!output.empty()) {
    EXPECT_FALSE(fs::exists(dir / output));
  }
}

void writePng(const fs::path& path) {
  writeImage(path, Image(8, 8, 3, PixelFormat::UInt8));
}

TEST(CliSilentReads, TruncatedFaceIsAnErrorNotDropped) {
  const fs::path dir = tempDir("cli_silent_cut");
  fixtures::write(dir, "cut.obj", fixtures::truncatedObj());
  expectRefused({"info", "cut.obj"}, dir, "", {"cut.obj line 10", "2 corners"});
  expectRefused({"mask", "cut.obj", "-r", "8", "--out", "out.png"}, dir, "out.png",
                {"cut.obj line 10"});
}

TEST(CliSilentReads, TwoMaterialsWithTwoTexturesArePagesListedByInfo) {
  // Each material's image is a texture page (texture_pages.h): processed together, written one
  // image per page, never the first material's texture applied to every face.
  const fs::path dir = tempDir("cli_silent_two");
  fixtures::write(dir, "two.mtl", fixtures::twoMaterialMtl("red.png", "blue.png"));
  fixtures::write(dir, "two.obj", fixtures::twoMaterialObj());
  writePng(dir / "red.png");
  writePng(dir / "blue.png");
  const CliResult filter = runCli({"filter", "two.obj", "--out", "out.png"}, dir);
  EXPECT_EQ(filter.status, 0) << filter.err;
  EXPECT_TRUE(fs::exists(dir / "out.red.png"));
  EXPECT_TRUE(fs::exists(dir / "out.blue.png"));
  EXPECT_FALSE(fs::exists(dir / "out.png"));
  const CliResult info = runCli({"info", "two.obj"}, dir);
  EXPECT_EQ(info.status, 0) << info.err;
  for (const char* part : {"red.png, named by material 'red' (map_Kd 'red.png'), on 1 face",
                           "blue.png, named by material 'blue' (map_Kd 'blue.png'), on 1 face",
                           "baseColor pages 2 (one per image)", "page red: ", "page blue: "})
    EXPECT_NE(info.out.find(part), std::string::npos)
        << "missing '" << part << "' in: " << info.out;
}

TEST(CliSilentReads, MissingMtlNamesTheMtllibLine) {
  const fs::path dir = tempDir("cli_silent_mtl");
  fixtures::write(dir, "nomtl.obj", fixtures::missingMtlObj());
  expectRefused({"filter", "nomtl.obj", "--out", "out.png"}, dir, "out.png",
                {"nomtl.obj line 1", "'gone.mtl'", "was not found"});
  const CliResult info = runCli({"info", "nomtl.obj"}, dir);
  EXPECT_EQ(info.status, 0) << info.err;
  EXPECT_NE(info.out.find("gone.mtl"), std::string::npos) << info.out;
  EXPECT_EQ(info.out.find("no problems found"), std::string::npos) << info.out;
}

TEST(CliSilentReads, MissingGltfImageIsNamedAndNeverWrittenBack) {
  // The processed slot's image missing: refused. Another image missing: one warning line (none
  // with --quiet), and the copy leaves that image out instead of referring to it.
  const fs::path dir = tempDir("cli_silent_gltf");
  fixtures::write(dir, "nocolor.gltf", fixtures::triangleGltf("gone.png", "normal.png"));
  writePng(dir / "normal.png");
  expectRefused({"filter", "nocolor.gltf", "--out", "out.gltf"}, dir, "out.gltf",
                {"nocolor.gltf", "image 0", "URI 'gone.png'"});
  const CliResult info = runCli({"info", "nocolor.gltf"}, dir);
  EXPECT_EQ(info.status, 0) << info.err;
  EXPECT_NE(info.out.find("image 0 (URI 'gone.png')) was not found"), std::string::npos)
      << info.out;
  EXPECT_EQ(info.out.find("no problems found"), std::string::npos) << info.out;
  fixtures::write(dir, "nonormal.gltf", fixtures::triangleGltf("color.png", "gone.png"));
  writePng(dir / "color.png");
  const CliResult warned = runCli({"filter", "nonormal.gltf", "--out", "out.gltf"}, dir);
  EXPECT_EQ(warned.status, 0) << warned.err;
  EXPECT_EQ(lineCount(warned.err), 2) << "the warning and the summary line: " << warned.err;
  for (const char* part : {"warning: ", "nonormal.gltf", "image 1", "URI 'gone.png'", "out.gltf"})
    EXPECT_NE(warned.err.find(part), std::string::npos)
        << "missing '" << part << "' in: " << warned.err;
  ASSERT_TRUE(fs::exists(dir / "out.gltf"));
  std::ifstream written(dir / "out.gltf");
  const std::string text{std::istreambuf_iterator<char>(written), {}};
  EXPECT_EQ(text.find("gone.png"), std::string::npos) << "a dangling URI";
  const CliResult quiet = runCli({"filter", "nonormal.gltf", "--out", "q.gltf", "--quiet"}, dir);
  EXPECT_EQ(quiet.status, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "");
}

}  // namespace texgrad::test::cli_silent_reads
