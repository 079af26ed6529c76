// CLI contract on what a command writes: nothing (and a non-zero status) when no texel of the
// image would change, bad output paths refused before any input is read, and one summary line.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <chrono>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "test_paths.h"
#include "texgrad/io/image_io.h"

namespace texgrad::test::cli_outputs {
namespace {

/// A counted progress line, "texgrad: STAGE P% (K/N)", split into its parts.
struct CountedLine {
  std::string stage;
  int percent = 0, step = 0, steps = 0;
};

/// The parts of a counted progress line; nothing for any other line. (Parsed by hand: GCC 12's
/// std::regex trips -Wmaybe-uninitialized in the -O1 sanitizer build.)
std::optional<CountedLine> parseCountedLine(const std::string& line) {
  const std::string prefix = "texgrad: ";
  const size_t open = line.rfind(" (");
  if (line.rfind(prefix, 0) != 0 || open == std::string::npos || line.back() != ')')
    return std::nullopt;
  const size_t space = line.rfind(' ', open - 1);
  if (space == std::string::npos || space < prefix.size()) return std::nullopt;
  CountedLine parsed;
  parsed.stage = line.substr(prefix.size(), space - prefix.size());
  char percentSign = 0, close = 0;
  std::istringstream percent(line.substr(space + 1, open - space - 1));
  std::istringstream counts(line.substr(open + 2));
  char slash = 0;
  if (!(percent >> parsed.percent >> percentSign) || percentSign != '%' ||
      !(counts >> parsed.step >> slash >> parsed.steps >> close) || slash != '/' || close != ')')
    return std::nullopt;
  return parsed;
}

/// A unit square (two faces) whose UVs are the unit square moved by (du, dv).
std::string shiftedSquareObj(double du, double dv) {
  std::string obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
  for (const auto& [u, v] : std::vector<std::pair<double, double>>{{0, 0}, {1, 0}, {1, 1}, {0, 1}})
    obj += "vt " + std::to_string(u + du) + " " + std::to_string(v + dv) + "\n";
  return obj + "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
}

void writeText(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

/// A .vf file with one extrinsic vector per face of the square (vector_field.h).
std::string squareFieldBytes() {
  const int32_t count = 2;
  std::string bytes(reinterpret_cast<const char*>(&count), sizeof count);
  for (double v : {1.0, 0.0, 0.0, 1.0, 0.0, 0.0})
    bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
  return bytes;
}

/// Writes the inputs every command line below uses into `dir`: meshes inside.obj (UVs in
/// [0, 1]^2), right.obj (u in [1, 2]), up.obj (v in [1, 2]), half.obj (u in [0.5, 1.5]);
/// a 32x32 texture and segment mask; a vector field.
void writeInputs(const std::filesystem::path& dir) {
  writeText(dir / "inside.obj", shiftedSquareObj(0, 0));
  writeText(dir / "right.obj", shiftedSquareObj(1, 0));
  writeText(dir / "up.obj", shiftedSquareObj(0, 1));
  writeText(dir / "half.obj", shiftedSquareObj(0.5, 0));
  writeImage(dir / "tex.png", Image(32, 32, 3, PixelFormat::UInt8));
  writeImage(dir / "seg.png", Image(32, 32, 1, PixelFormat::UInt8));
  writeText(dir / "field.vf", squareFieldBytes());
}

/// A command line of `command` on `mesh` writing `out` at 32x32 (its texture's size or -r).
std::vector<std::string> commandLine(const std::string& command, const std::string& mesh,
                                     const std::string& out) {
  if (command == "filter" || command == "seams" || command == "dilate")
    return {command, mesh, "tex.png", "-o", out};
  if (command == "stitch")
    return {command, mesh, "--composite", "tex.png", "--segments", "seg.png", "-o", out};
  if (command == "geodesic") return {command, mesh, "-r", "32", "--source-vertex", "0", "-o", out};
  if (command == "lic") return {command, mesh, "-r", "32", "--field", "field.vf", "-o", out};
  if (command == "react") return {command, mesh, "-r", "32", "--steps", "3", "-o", out};
  return {command, mesh, "-r", "32", "-o", out};  // mask
}

std::string joined(const std::vector<std::string>& args) {
  std::string text;
  for (const std::string& a : args) text += a + " ";
  return text;
}

class EveryWritingCommand : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    dir_ = tempDir("outputs_" + GetParam());
    writeInputs(dir_);
  }
  /// The command's output file name (geodesic writes float distances).
  std::string out(const std::string& stem = "out") const {
    return stem + (GetParam() == "geodesic" ? ".exr" : ".png");
  }
  std::filesystem::path dir_;
};

TEST_P(EveryWritingCommand, RefusesUvsOutsideTheImageNamingTheirRange) {
  // Control: the same command line on the square inside the image, and on one half outside it
  // (the grid extends past the image), writes its output.
  for (const char* mesh : {"inside.obj", "half.obj"}) {
    const auto args = commandLine(GetParam(), mesh, out());
    const CliResult r = runCli(args, dir_);
    ASSERT_EQ(r.status, 0) << joined(args) << "\n" << r.err;
    EXPECT_TRUE(std::filesystem::exists(dir_ / out())) << joined(args);
    std::filesystem::remove(dir_ / out());
  }
  const std::vector<std::pair<std::string, std::string>> outside{
      {"right.obj", "UVs span u [1, 2] x v [0, 1], outside the image [0, 1]^2"},
      {"up.obj", "UVs span u [0, 1] x v [1, 2], outside the image [0, 1]^2"}};
  for (const auto& [mesh, range] : outside) {
    auto args = commandLine(GetParam(), mesh, out());
    args.insert(args.end(), {"--wrap", "clamp"});  // the default (OBJ: repeat) wraps them
    const CliResult r = runCli(args, dir_);
    EXPECT_NE(r.status, 0) << joined(args);
    EXPECT_EQ(lineCount(r.err), 1) << joined(args) << "\n" << r.err;
    EXPECT_NE(r.err.find(range), std::string::npos) << joined(args) << "\n" << r.err;
    EXPECT_NE(r.err.find("move the UVs into [0, 1]^2"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir_ / out())) << joined(args);
  }
}

TEST_P(EveryWritingCommand, WrapsUvsInAnotherTileLikeTheirCopyInTheImage) {
  // An OBJ names no sampler: its texture repeats, so the square moved by a whole tile writes
  // the same texels as the square inside the image.
  ASSERT_EQ(runCli(commandLine(GetParam(), "inside.obj", out("inside")), dir_).status, 0);
  const Image inside = readImage(dir_ / out("inside"));
  for (const char* mesh : {"right.obj", "up.obj"}) {
    const auto args = commandLine(GetParam(), mesh, out());
    const CliResult r = runCli(args, dir_);
    ASSERT_EQ(r.status, 0) << joined(args) << "\n" << r.err;
    EXPECT_EQ(readImage(dir_ / out()).pixels, inside.pixels) << joined(args);
  }
}

TEST(Cli, GeodesicUvSourceIsInTheImageTheChartsWereMovedInto) {
  // --source-uv names a point of the image: on the square moved to v in [1, 2] (and wrapped
  // back into the image) the same UV is the same surface point, so the distances are the same.
  const std::filesystem::path dir = tempDir("outputs_geodesic_uv_tile");
  writeInputs(dir);
  const auto run = [&](const char* mesh, const char* uv, const char* out) {
    const CliResult r =
        runCli({"geodesic", mesh, "-r", "32", "--source-uv", uv, "-o", out, "--quiet"}, dir);
    EXPECT_EQ(r.status, 0) << r.err;
    return readImage(dir / out);
  };
  EXPECT_EQ(run("up.obj", "0.3,0.6", "up.exr").pixels,
            run("inside.obj", "0.3,0.6", "inside.exr").pixels);
}

TEST_P(EveryWritingCommand, RefusesABadOutputBeforeReadingAnyInput) {
  // The mesh does not exist: a refusal that names the output, not the mesh, was made before
  // anything was read (let alone computed).
  const std::vector<std::pair<std::string, std::string>> bad{
      {"out.bmp", "unknown image extension '.bmp'"},
      {"nodir/" + out(), "folder nodir does not exist"},
      {"dir.exr", "it is a folder"}};
  std::filesystem::create_directory(dir_ / "dir.exr");
  for (const auto& [path, mention] : bad) {
    const auto args = commandLine(GetParam(), "missing.obj", path);
    const CliResult r = runCli(args, dir_);
    EXPECT_NE(r.status, 0) << joined(args);
    EXPECT_EQ(lineCount(r.err), 1) << joined(args) << "\n" << r.err;
    EXPECT_NE(r.err.find(mention), std::string::npos) << joined(args) << "\n" << r.err;
    EXPECT_EQ(r.err.find("missing.obj"), std::string::npos) << joined(args) << "\n" << r.err;
  }
}

/// The writing commands with a --bit-depth flag (geodesic writes float distances: it has none).
class EveryBitDepthCommand : public EveryWritingCommand {};

TEST_P(EveryBitDepthCommand, RefusesABitDepthTheFormatCannotHold) {
  const std::vector<std::pair<std::string, std::string>> bad{
      {"16", "out.jpg"}, {"float", "out.png"}, {"8", "out.exr"}};
  for (const auto& [depth, path] : bad) {
    auto args = commandLine(GetParam(), "missing.obj", path);
    args.insert(args.end(), {"--bit-depth", depth});
    const CliResult r = runCli(args, dir_);
    EXPECT_NE(r.status, 0) << joined(args);
    EXPECT_EQ(lineCount(r.err), 1) << joined(args) << "\n" << r.err;
    EXPECT_NE(r.err.find("cannot write " + path + " as"), std::string::npos) << joined(args) << "\n"
                                                                             << r.err;
    EXPECT_EQ(r.err.find("missing.obj"), std::string::npos) << joined(args) << "\n" << r.err;
  }
}

INSTANTIATE_TEST_SUITE_P(Cli, EveryWritingCommand,
                         ::testing::Values("filter", "stitch", "seams", "dilate", "geodesic", "lic",
                                           "react", "mask"),
                         [](const auto& p) { return p.param; });
INSTANTIATE_TEST_SUITE_P(Cli, EveryBitDepthCommand,
                         ::testing::Values("filter", "stitch", "seams", "dilate", "lic", "react",
                                           "mask"),
                         [](const auto& p) { return p.param; });

/// CPU seconds used by the test's finished child processes so far.
double childCpuSeconds() {
  rusage usage{};
  ::getrusage(RUSAGE_CHILDREN, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

/// CPU time a refusal may take: the program's start-up is 0.3 s (`texgrad --version`); processing
/// the inputs below takes tens of CPU seconds.
constexpr double kRefusalCpuSeconds = 1.0;

TEST(Cli, RefusesABadOutputInUnderASecondBeforeAnyComputation) {
  // Real inputs that take seconds to process (1024x1024 operators and solves): the refusal does
  // not wait for them. CPU time, not wall time: on a loaded machine (load 9 on 2 cores) the
  // wall time of `texgrad --version` alone reaches 1 s.
  const auto dir = tempDir("outputs_bad_fast");
  const std::vector<std::vector<std::string>> commands{
      {"filter", "builtin:sphere", "-o"},
      {"geodesic", "builtin:sphere", "-r", "1024", "--source-vertex", "0", "-o"},
      {"react", "builtin:sphere", "-r", "1024", "-o"}};
  for (const std::string out : {"out.bmp", "nodir/out.png"})
    for (std::vector<std::string> args : commands) {
      args.push_back(args.front() == "geodesic" && out != "out.bmp" ? "nodir/out.exr" : out);
      const double before = childCpuSeconds();
      const CliResult r = runCli(args, dir);
      EXPECT_NE(r.status, 0) << joined(args);
      EXPECT_EQ(lineCount(r.err), 1) << joined(args) << "\n" << r.err;
      EXPECT_LT(childCpuSeconds() - before, kRefusalCpuSeconds) << joined(args);
    }
}

/// The commands that solve, which all take --progress.
class EverySolvingCommand : public EveryWritingCommand {};

TEST_P(EverySolvingCommand, ProgressLinesCoverEveryStageToTheWriteWithStepCounts) {
  // Forced on although stderr is a file: every stage from read to write, a solve (or time
  // step) stage that counts its steps, the summary last.
  auto args = commandLine(GetParam(), "inside.obj", out());
  args.insert(args.end(), {"--progress", "lines"});
  const CliResult r = runCli(args, dir_);
  ASSERT_EQ(r.status, 0) << joined(args) << "\n" << r.err;
  std::vector<std::string> lines;
  std::istringstream in(r.err);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_GE(lines.size(), 4u) << r.err;
  EXPECT_EQ(lines.front(), "texgrad: read 0%") << r.err;
  EXPECT_EQ(lines[lines.size() - 2], "texgrad: write 100%") << r.err;
  EXPECT_EQ(lines.back().rfind("wrote " + out(), 0), 0u) << r.err;
  int countedLines = 0;
  for (const std::string& line : lines) {
    const auto counted = parseCountedLine(line);
    countedLines += counted && (counted->stage.ends_with("solve") || counted->stage == "react");
  }
  EXPECT_GE(countedLines, 1) << r.err;
}

TEST_P(EverySolvingCommand, ReportsItsPeakResidentMemory) {
  // Any process that has loaded the library and solved holds more than this resident.
  constexpr int64_t kLeastPlausiblePeak = int64_t(1) << 20;
  auto args = commandLine(GetParam(), "inside.obj", out());
  args.push_back("--json");
  const CliResult json = runCli(args, dir_);
  ASSERT_EQ(json.status, 0) << joined(args) << json.err;
  const auto peak = nlohmann::json::parse(json.out).at("peak_rss_bytes");
  ASSERT_TRUE(peak.is_number_integer()) << peak;
  EXPECT_GT(peak.get<int64_t>(), kLeastPlausiblePeak);
  args.back() = "--timings";
  const CliResult timings = runCli(args, dir_);
  ASSERT_EQ(timings.status, 0) << joined(args) << timings.err;
  EXPECT_NE(timings.err.find("peak memory"), std::string::npos) << timings.err;
}

INSTANTIATE_TEST_SUITE_P(Cli, EverySolvingCommand,
                         ::testing::Values("filter", "stitch", "seams", "geodesic", "lic", "react"),
                         [](const auto& p) { return p.param; });

TEST(Cli, ProgressLinesShowTheSolveAdvancingOnANonTerminal) {
  const auto dir = tempDir("outputs_progress_lines");
  const std::vector<std::string> args{"filter",      "builtin:aligned-cube",
                                      "-o",          "f.png",
                                      "--beta",      "0.3",
                                      "--solver",    "multigrid",
                                      "--cycles",    "5",
                                      "--tolerance", "0",
                                      "--progress",  "lines"};
  const CliResult r = runCli(args, dir);
  ASSERT_EQ(r.status, 0) << r.err;
  // "texgrad: solve P% (k/15)" for k = 0 .. 15 (the RGB texture's channels are solved in turn,
  // 5 cycles each), percentages and counts rising, then the write.
  constexpr int kCycles = 3 * 5;
  std::istringstream in(r.err);
  std::vector<int> steps, percents;
  bool wroteAfterSolve = false;
  for (std::string line; std::getline(in, line);) {
    const auto counted = parseCountedLine(line);
    if (counted && counted->stage == "solve" && counted->steps == kCycles) {
      percents.push_back(counted->percent);
      steps.push_back(counted->step);
    } else if (line == "texgrad: write 100%") {
      wroteAfterSolve = !steps.empty();
    }
  }
  std::vector<int> expected(kCycles + 1);
  std::iota(expected.begin(), expected.end(), 0);
  EXPECT_EQ(steps, expected) << r.err;
  for (size_t i = 1; i < percents.size(); ++i) EXPECT_GT(percents[i], percents[i - 1]) << r.err;
  ASSERT_FALSE(percents.empty());
  EXPECT_EQ(percents.back(), 100);
  EXPECT_TRUE(wroteAfterSolve) << r.err;
  // Without --progress a non-terminal gets no progress, only the summary.
  const std::vector<std::string> plain(args.begin(), args.end() - 2);
  const CliResult p = runCli(plain, dir);
  ASSERT_EQ(p.status, 0) << p.err;
  EXPECT_EQ(lineCount(p.err), 1) << p.err;
}

TEST(Cli, PeakResidentMemoryExceedsTheInputImage) {
  // The process holds the decoded texture, so its peak is above the image's byte size.
  constexpr int kSize = 512;
  const auto dir = tempDir("outputs_peak_rss");
  writeInputs(dir);
  const Image texture(kSize, kSize, 3, PixelFormat::UInt8);
  writeImage(dir / "big.png", texture);
  const CliResult r =
      runCli({"filter", "inside.obj", "big.png", "-o", "f.png", "--beta", "0", "--json"}, dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const int64_t imageBytes = int64_t(kSize) * kSize * texture.channels;
  EXPECT_GT(nlohmann::json::parse(r.out).at("peak_rss_bytes").get<int64_t>(), imageBytes);
}

/// Two squares far apart in 3-D: vertices 0-3 with UVs inside the image, 4-7 with UVs outside.
const char* kTwoIslandsObj =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "v 0 0 5\nv 1 0 5\nv 1 1 5\nv 0 1 5\n"
    "vt 0.1 0.1\nvt 0.4 0.1\nvt 0.4 0.4\nvt 0.1 0.4\n"
    "vt 1.1 0.1\nvt 1.4 0.1\nvt 1.4 0.4\nvt 1.1 0.4\n"
    "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\nf 5/5 6/6 7/7\nf 5/5 7/7 8/8\n";

TEST(Cli, GeodesicRefusesASourceThatReachesNoTexelOfTheImage) {
  const auto dir = tempDir("outputs_geodesic_island");
  writeText(dir / "islands.obj", kTwoIslandsObj);
  // With --wrap clamp: a texture that repeats would read the outer island inside the image.
  const std::vector<std::string> base{"geodesic", "islands.obj", "-r",     "32",
                                      "-o",       "d.exr",       "--wrap", "clamp"};
  auto inside = base, outside = base;
  inside.insert(inside.end(), {"--source-vertex", "0"});
  outside.insert(outside.end(), {"--source-vertex", "4"});
  const CliResult good = runCli(inside, dir);
  ASSERT_EQ(good.status, 0) << good.err;
  std::filesystem::remove(dir / "d.exr");
  const CliResult r = runCli(outside, dir);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(lineCount(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("no texel inside the image is reached"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("UV (1.1"), std::string::npos) << "names the source: " << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "d.exr"));
}

TEST(Cli, SummaryLineSaysWhatWasWritten) {
  const auto dir = tempDir("outputs_summary");
  writeInputs(dir);
  const std::vector<std::string> filter{"filter",      "inside.obj", "tex.png", "-o", "f.png",
                                        "--bit-depth", "16",         "--beta",  "0.5"};
  const CliResult r = runCli(filter, dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(lineCount(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("wrote f.png: 32x32 RGB 16-bit, ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(" texels solved in "), std::string::npos) << r.err;
  const Image written = readImage(dir / "f.png");
  EXPECT_EQ(written.format, PixelFormat::UInt16);
  EXPECT_EQ(written.width, 32);
  EXPECT_EQ(written.channels, 3);
  // --quiet: nothing on stderr; --json: the JSON document alone on stdout.
  auto quiet = filter, json = filter;
  quiet.push_back("--quiet");
  json.push_back("--json");
  const CliResult q = runCli(quiet, dir);
  ASSERT_EQ(q.status, 0) << q.err;
  EXPECT_EQ(lineCount(q.err), 0) << q.err;
  const CliResult j = runCli(json, dir);
  ASSERT_EQ(j.status, 0) << j.err;
  EXPECT_EQ(nlohmann::json::parse(j.out)["command"], "filter");
  EXPECT_EQ(j.err.rfind("wrote f.png", 0), 0u) << j.err;
}

}  // namespace
}  // namespace texgrad::test::cli_outputs
