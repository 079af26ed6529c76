// CLI contract on bad input: one line on stderr naming the file, non-zero status, no output.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

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
  std::string ihdr =
      "IHDR" + bigEndian32(0) + bigEndian32(0) + std::string("\x08\x02\x00\x00\x00", 5);
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
        BadMeshCase{"truncated_obj", "cut.obj",
                    std::string(kGoodObj).substr(0, 60) + "\nf 1/1 2/2 3/3\nf 1/1 3/3 4/"},
        BadMeshCase{"index_out_of_range", "oob.obj", std::string(kGoodObj) + "f 1/1 2/2 9/3\n"},
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

TEST_F(BadTextureInput, MissingTexture) {
  expectOneLineError("missing.png");
}

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

/// A .vf field file: little-endian int32 `count`, then the values as float64 (vector_field.h).
std::string vectorFieldBytes(int32_t count, const std::vector<double>& values) {
  std::string bytes(reinterpret_cast<const char*>(&count), sizeof count);
  for (double v : values) bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
  return bytes;
}

/// Runs a command that must be refused: non-zero status, exactly one stderr line containing
/// `mention` (and no "internal error"), and none of `outputs` written.
void expectRefused(const std::vector<std::string>& args, const std::filesystem::path& dir,
                   const std::string& mention, const std::vector<std::string>& outputs) {
  const CliResult r = runCli(args, dir);
  std::string command;
  for (const std::string& a : args) command += a + " ";
  EXPECT_NE(r.status, 0) << command;
  EXPECT_EQ(lineCount(r.err), 1) << command << "\n" << r.err;
  EXPECT_NE(r.err.find(mention), std::string::npos)
      << command << ": expected '" << mention << "' in: " << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << command << "\n" << r.err;
  for (const std::string& out : outputs)
    EXPECT_FALSE(std::filesystem::exists(dir / out)) << command << " wrote " << out;
}

/// builtin:square has two faces; these files hold fields for it, good and broken.
class BadAppArguments : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = tempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    const double nan = std::numeric_limits<double>::quiet_NaN();
    writeFile(dir_ / "good.vf", vectorFieldBytes(2, {1, 0, 0, 1, 0, 0}));
    writeFile(dir_ / "short.vf", std::string("\x02\x00", 2));
    writeFile(dir_ / "truncated.vf", vectorFieldBytes(2, {1, 0, 0, 1, 0}));  // count says 6
    writeFile(dir_ / "nan.vf", vectorFieldBytes(2, {1, 0, 0, nan, 0, 0}));
    writeFile(dir_ / "three.vf", vectorFieldBytes(3, {1, 0, 0, 1, 0, 0, 1, 0, 0}));
    writeFile(dir_ / "negative.vf", vectorFieldBytes(-2, {}));
  }
  /// `texgrad lic builtin:square` at 32^2 writing lic.png, plus `extra` arguments.
  std::vector<std::string> lic(std::vector<std::string> extra) const {
    std::vector<std::string> args{"lic", "builtin:square", "-r", "32", "--out", "lic.png"};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  }
  /// `texgrad geodesic builtin:square` at 32^2 writing d.exr and d.png, plus `extra`.
  std::vector<std::string> geodesic(std::vector<std::string> extra) const {
    std::vector<std::string> args{"geodesic", "builtin:square", "-r",    "32",
                                  "--out",    "d.exr",          "--png", "d.png"};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  }
  /// `texgrad react builtin:square` at 32^2 writing rd.png, plus `extra`.
  std::vector<std::string> react(std::vector<std::string> extra) const {
    std::vector<std::string> args{"react", "builtin:square", "-r", "32", "--out", "rd.png"};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  }
  std::filesystem::path dir_;
};

TEST_F(BadAppArguments, ControlsSucceedWithJson) {
  // The same command lines with good arguments run and print a JSON summary, so the refusals
  // below are caused by the bad argument alone.
  const std::vector<std::vector<std::string>> good{
      lic({"--field", "good.vf", "--json"}),
      geodesic({"--source-vertex", "0", "--source-uv", "0.5,0.5", "--json"}),
      react({"--steps", "3", "--preset", "dots", "--json"})};
  for (const auto& args : good) {
    const CliResult r = runCli(args, dir_);
    ASSERT_EQ(r.status, 0) << args[0] << ": " << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["command"], args[0]);
  }
  for (const char* out : {"lic.png", "d.exr", "d.png", "rd.png"})
    EXPECT_TRUE(std::filesystem::exists(dir_ / out)) << out;
}

TEST_F(BadAppArguments, LicRefusesMalformedFieldFiles) {
  const std::vector<std::string> out{"lic.png"};
  expectRefused(lic({"--field", "short.vf"}), dir_, "short.vf is 2 bytes long, too short", out);
  expectRefused(lic({"--field", "truncated.vf"}), dir_, "truncated.vf is 44 bytes long", out);
  expectRefused(lic({"--field", "nan.vf"}), dir_, "nan.vf: the vector of face 1 holds a non-finite",
                out);
  expectRefused(lic({"--field", "negative.vf"}), dir_, "negative vector count", out);
  expectRefused(lic({"--field", "missing.vf"}), dir_, "missing.vf", out);
  // Extrinsic-sized file read as intrinsic: the message says which flag fits.
  expectRefused(lic({"--field", "good.vf", "--intrinsic"}), dir_, "drop --intrinsic", out);
}

TEST_F(BadAppArguments, LicRefusesAFieldWhoseCountIsNotTheFaceCount) {
  expectRefused(lic({"--field", "three.vf"}), dir_, "mesh has 2 faces", {"lic.png"});
}

TEST_F(BadAppArguments, LicRefusesBadOptions) {
  const std::vector<std::string> out{"lic.png"};
  expectRefused(lic({"--curvature", "mean"}), dir_, "--curvature", out);
  expectRefused(lic({"--epsilon", "0"}), dir_, "--epsilon: must be a number > 0, got 0", out);
  expectRefused(lic({"--sharpen", "-1"}), dir_, "--sharpen", out);
  expectRefused(lic({"--solver", "magic"}), dir_, "magic", out);
  // A flat square has no curvature: the default field is zero everywhere.
  expectRefused(lic({}), dir_, "zero on every face", out);
}

TEST_F(BadAppArguments, GeodesicRefusesBadSources) {
  const std::vector<std::string> out{"d.exr", "d.png"};
  expectRefused(geodesic({"--source-vertex", "4"}), dir_, "--source-vertex 4", out);
  expectRefused(geodesic({"--source-vertex=-1"}), dir_, "--source-vertex -1", out);
  expectRefused(geodesic({"--source-uv", "3,3"}), dir_, "outside every chart", out);
  expectRefused(geodesic({"--source-uv", "0.5,-0.2"}), dir_, "outside every chart", out);
  expectRefused(geodesic({"--source-uv", "0.5"}), dir_, "--source-uv", out);
  expectRefused(geodesic({"--source-uv", "0.5,nan"}), dir_, "--source-uv", out);
  expectRefused(geodesic({"--source-point", "1,2"}), dir_, "--source-point", out);
  expectRefused(geodesic({}), dir_, "no source", out);
  expectRefused(geodesic({"--source-vertex", "0", "--alpha", "-3"}), dir_, "--alpha", out);
}

TEST_F(BadAppArguments, GeodesicSnapsAUvJustOutsideAChart) {
  // Half a texel outside the square's chart (UV [0, 1]^2 at 32^2) is still on the surface.
  const CliResult r = runCli(geodesic({"--source-uv", "1.01,0.5", "--json"}), dir_);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto summary = nlohmann::json::parse(r.out);
  EXPECT_NEAR(summary["sources"][0]["uv"][0].get<double>(), 1.0, 1e-9);
}

TEST_F(BadAppArguments, ReactRefusesBadPresetAndSteps) {
  const std::vector<std::string> out{"rd.png"};
  expectRefused(react({"--preset", "spirals"}), dir_, "--preset", out);
  expectRefused(react({"--steps", "-5"}), dir_, "--steps", out);
  expectRefused(react({"--steps", "many"}), dir_, "--steps", out);
  expectRefused(react({"--steps", "2.5"}), dir_, "--steps", out);
  expectRefused(react({"--time-step", "0"}), dir_, "--time-step", out);
  expectRefused(react({"--scale", "-1"}), dir_, "--scale", out);
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
