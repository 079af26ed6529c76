// End-to-end checks of the `texgrad` subcommands on built-in meshes (no files needed).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_runner.h"
#include "test_paths.h"
#include "texgrad/io/image_io.h"

namespace texgrad::test {
namespace {

TEST(Cli, SampleWritesMeshAndTexture) {
  const auto dir = tempDir("cli_sample");
  const CliResult r = runCli({"sample", "--out-dir", "s", "--size", "64"}, dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "s/sample.obj"));
  EXPECT_TRUE(std::filesystem::exists(dir / "s/sample.mtl"));
  const Image texture = readImage(dir / "s/sample.png");
  EXPECT_EQ(texture.width, 64);
  EXPECT_EQ(texture.height, 64);
  // The written sample reads back with the same chart structure as the built-in one.
  const CliResult fromFile = runCli({"info", "s/sample.obj", "--json"}, dir);
  const CliResult builtin = runCli({"info", "builtin:sample", "--json"}, dir);
  ASSERT_EQ(fromFile.status, 0) << fromFile.err;
  ASSERT_EQ(builtin.status, 0) << builtin.err;
  const auto a = nlohmann::json::parse(fromFile.out), b = nlohmann::json::parse(builtin.out);
  for (const char* key : {"faces", "vertices", "charts", "seam_edges", "boundary_edges"})
    EXPECT_EQ(a[key], b[key]) << key;
  EXPECT_GE(a["charts"].get<int>(), 4);
}

TEST(Cli, MaskMatchesInfoTexelCounts) {
  const auto dir = tempDir("cli_mask");
  const CliResult info = runCli({"info", "builtin:sphere", "-r", "128x64", "--json"}, dir);
  ASSERT_EQ(info.status, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  for (const char* kind : {"active", "interior", "boundary"}) {
    const std::string out = std::string(kind) + ".png";
    const CliResult r = runCli({"mask", "builtin:sphere", "-r", "128x64", "-k", kind, "-o", out}, dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const Image mask = readImage(dir / out);
    ASSERT_EQ(mask.width, 128);
    ASSERT_EQ(mask.height, 64);
    int64_t lit = 0;
    for (float v : mask.pixels) lit += v > 0.5f ? 1 : 0;
    const int64_t outside = j["texels"]["texels_outside_image"].get<int64_t>();
    EXPECT_LE(lit, j["texels"][kind].get<int64_t>()) << kind;
    EXPECT_GE(lit, j["texels"][kind].get<int64_t>() - outside) << kind;
  }
}

TEST(Cli, UnknownBuiltinIsOneLine) {
  const auto dir = tempDir("cli_unknown_builtin");
  const CliResult r = runCli({"info", "builtin:teapot"}, dir);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(lineCount(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("builtin:teapot"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace texgrad::test
