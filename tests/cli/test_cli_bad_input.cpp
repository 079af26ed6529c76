// CLI contract on bad input: one line on stderr naming the file, non-zero status, no output.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <fstream>

#include "cli_runner.h"
#include "test_paths.h"

namespace texgrad::test {
namespace {

const char* kGoodObj =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "vt 0.1 0.1\nvt 0.9 0.1\nvt 0.9 0.9\nvt 0.1 0.9\n"
    "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";

void writeFile(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

uint32_t crc32(const std::string& bytes) {
  uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char byte : bytes) {
    crc ^= byte;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

std::string bigEndian32(uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
          static_cast<char>(v)};
}

/// A PNG whose IHDR declares a 0 x 0 image (invalid but well-formed chunks).
std::string zeroSizePng() {
  std::string ihdr = "IHDR" + bigEndian32(0) + bigEndian32(0) + std::string("\x08\x02\x00\x00\x00", 5);
  std::string png = "\x89PNG\r\n\x1a\n";
  png += bigEndian32(13) + ihdr + bigEndian32(crc32(ihdr));
  std::string iend = "IEND";
  png += bigEndian32(0) + iend + bigEndian32(crc32(iend));
  return png;
}

struct BadMeshCase {
  std::string name;
  std::string file;
  std::string content;
};

class BadMeshInput : public ::testing::TestWithParam<BadMeshCase> {};

TEST_P(BadMeshInput, OneLineNonZeroStatusNoOutput) {
  const BadMeshCase& c = GetParam();
  const auto dir = tempDir("bad_mesh_" + c.name);
  writeFile(dir / c.file, c.content);
  const CliResult r = runCli({"mask", c.file, "--resolution", "64", "--out", "out.png"}, dir);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(lineCount(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(c.file), std::string::npos) << "message must name the file: " << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.png"));
}

std::string glbHeaderClaiming(uint32_t length) {
  auto le = [](uint32_t v) {
    return std::string{static_cast<char>(v), static_cast<char>(v >> 8), static_cast<char>(v >> 16),
                       static_cast<char>(v >> 24)};
  };
  return "glTF" + le(2) + le(length) + le(200) + "JSON" + "{\"asset\":";
}

INSTANTIATE_TEST_SUITE_P(
    Cli, BadMeshInput,
    ::testing::Values(
        BadMeshCase{"empty_obj", "empty.obj", ""},
        BadMeshCase{"truncated_obj", "cut.obj", std::string(kGoodObj).substr(0, 60) + "\nf 1/1 2/2 3/3\nf 1/1 3/3 4/"},
        BadMeshCase{"index_out_of_range", "oob.obj",
                    std::string(kGoodObj) + "f 1/1 2/2 9/3\n"},
        BadMeshCase{"nan_coordinate", "nan.obj",
                    "v 0 0 0\nv nan 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\n"},
        BadMeshCase{"inf_coordinate", "inf.obj",
                    "v 0 0 0\nv 1 0 0\nv 1 inf 0\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\n"},
        BadMeshCase{"no_uvs", "nouv.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n"},
        BadMeshCase{"truncated_ply", "cut.ply",
                    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float "
                    "y\nproperty float z\nproperty float u\nproperty float v\nelement face "
                    "1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 "
                    "0\n"},
        BadMeshCase{"truncated_glb", "cut.glb", glbHeaderClaiming(4096)},
        BadMeshCase{"empty_glb", "empty.glb", ""},
        BadMeshCase{"unknown_extension", "mesh.stl", "solid x\nendsolid x\n"}),
    [](const auto& p) { return p.param.name; });

TEST(Cli, MissingMeshFileIsOneLine) {
  const auto dir = tempDir("missing_mesh");
  const CliResult r = runCli({"info", "nothere.obj"}, dir);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(lineCount(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("nothere.obj"), std::string::npos) << r.err;
}

class BadTextureInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = tempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    writeFile(dir_ / "mesh.obj", kGoodObj);
  }
  void expectOneLineError(const std::string& texture) {
    const CliResult r = runCli({"info", "mesh.obj", "--texture", texture}, dir_);
    EXPECT_NE(r.status, 0);
    EXPECT_EQ(lineCount(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(texture), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  }
  std::filesystem::path dir_;
};

TEST_F(BadTextureInput, MissingTexture) { expectOneLineError("missing.png"); }

TEST_F(BadTextureInput, UnreadableTexture) {
  writeFile(dir_ / "garbage.png", "this is not an image at all");
  expectOneLineError("garbage.png");
}

TEST_F(BadTextureInput, PngNamedJpg) {
  ASSERT_EQ(runCli({"mask", "mesh.obj", "-r", "8", "--out", "real.png"}, dir_).status, 0);
  std::filesystem::copy_file(dir_ / "real.png", dir_ / "fake.jpg");
  expectOneLineError("fake.jpg");
}

TEST_F(BadTextureInput, ZeroByZeroImage) {
  writeFile(dir_ / "zero.png", zeroSizePng());
  expectOneLineError("zero.png");
}

TEST(Cli, HelpDescribesEveryOptionWithDefaults) {
  const auto dir = tempDir("help");
  const CliResult top = runCli({"--help"}, dir);
  EXPECT_EQ(top.status, 0);
  for (const char* cmd : {"info", "mask", "sample"}) {
    EXPECT_NE(top.out.find(cmd), std::string::npos) << cmd;
    const CliResult sub = runCli({cmd, "--help"}, dir);
    EXPECT_EQ(sub.status, 0) << cmd;
    EXPECT_NE(sub.out.find("Options:"), std::string::npos) << cmd;
  }
  const CliResult mask = runCli({"mask", "--help"}, dir);
  // CLI11 prints a default as "=value" (or "[value]" in other versions).
  const bool shown = mask.out.find("=active") != std::string::npos ||
                     mask.out.find("[active]") != std::string::npos;
  EXPECT_TRUE(shown) << "defaults are shown: " << mask.out;
  for (const char* cmd : {"filter", "stitch", "seams", "dilate", "geodesic", "lic", "react"}) {
    const CliResult sub = runCli({cmd, "--help"}, dir);
    EXPECT_EQ(sub.status, 0) << cmd;
    EXPECT_NE(sub.out.find("Options:"), std::string::npos) << cmd;
  }
}

}  // namespace
}  // namespace texgrad::test
