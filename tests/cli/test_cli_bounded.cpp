// CLI contract of the bound on barely covered texels: filter, stitch and seams keep their float
// outputs within the input's range (plus the documented margin) by default, and --raw writes the
// exact solution, which on a mesh with 0.01-texel slivers lies thousands of ranges outside.
#include <gtest/gtest.h>

#include <algorithm>

#include "cli_runner.h"
#include "test_paths.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_writer.h"
#include "texgrad/io/procedural.h"

namespace texgrad::test::cli_bounded {
namespace {

/// docs/architecture.md "Bounded results": how far outside the input's range (as a fraction of it)
/// a smoothing result may lie.
constexpr double kRangeMargin = 0.1;

/// Largest distance of `image`'s values outside [lo, hi], in units of hi - lo.
double excess(const Image& image, float lo, float hi) {
  const auto [least, most] = std::minmax_element(image.pixels.begin(), image.pixels.end());
  return std::max({0.0, double(lo - *least), double(*most - hi)}) / double(hi - lo);
}

/// The command line of `command` on the sliver cube writing `out`.
std::vector<std::string> commandLine(const std::string& command, const std::string& out) {
  if (command == "filter") return {"filter", "cube.obj", "tex.png", "--beta", "0", "-o", out};
  if (command == "seams") return {"seams", "cube.obj", "tex.png", "-o", out};
  return {"stitch",
          "cube.obj",
          "--composite",
          "tex.png",
          "--segments",
          "seg.png",
          "--no-gain-compensation",
          "-o",
          out};
}

class BoundedCommand : public ::testing::TestWithParam<std::string> {};

TEST_P(BoundedCommand, KeepsFloatOutputInRangeUnlessRaw) {
  const auto dir = tempDir("cli_bounded_" + GetParam());
  const int size = procedural::kAlignedCubeResolution;
  writeObj(dir / "cube.obj", procedural::alignedCube(4, 0.01));
  const Image texture = procedural::sampleTexture(size, size);
  writeImage(dir / "tex.png", texture);
  // Two sources, left and right half, of the same texture.
  Image segments(size, size, 1, PixelFormat::UInt8);
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) segments.at(i, j, 0) = i < size / 2 ? 0.5f : 1.0f;
  writeImage(dir / "seg.png", segments);
  const Image stored = readImage(dir / "tex.png");
  const auto [lo, hi] = std::minmax_element(stored.pixels.begin(), stored.pixels.end());
  const CliResult bounded = runCli(commandLine(GetParam(), "bounded.exr"), dir);
  ASSERT_EQ(bounded.status, 0) << bounded.err;
  auto raw = commandLine(GetParam(), "raw.exr");
  raw.push_back("--raw");
  const CliResult exact = runCli(raw, dir);
  ASSERT_EQ(exact.status, 0) << exact.err;
  // Stitching the cube's seam-discontinuous texture from two sources leaves fully covered texels
  // 0.2 ranges out: there the bound holds barely covered texels within what those reach
  // (tests/apps/test_barely_covered.cpp); here it must at least remove the thousands.
  const double allowed = GetParam() == "stitch" ? 1.0 : kRangeMargin;
  EXPECT_LE(excess(readImage(dir / "bounded.exr"), *lo, *hi), allowed);
  EXPECT_GT(excess(readImage(dir / "raw.exr"), *lo, *hi), 1.0);
}

INSTANTIATE_TEST_SUITE_P(Cli, BoundedCommand, ::testing::Values("filter", "seams", "stitch"),
                         [](const auto& p) { return p.param; });

}  // namespace
}  // namespace texgrad::test::cli_bounded
