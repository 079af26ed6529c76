// `--uv-set N`: the commands that read a mesh read glTF's TEXCOORD_N (issue 30).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_runner.h"
#include "test_paths.h"
#include "two_material_gltf.h"

namespace texgrad::test {
namespace {

/// The chart UV areas `texgrad info --json` reports for `args`.
std::vector<double> chartUvAreas(const std::vector<std::string>& args,
                                 const std::filesystem::path& dir) {
  const CliResult r = runCli(args, dir);
  EXPECT_EQ(r.status, 0) << r.err;
  if (r.status != 0) return {};
  return nlohmann::json::parse(r.out)["chart_uv_areas"].get<std::vector<double>>();
}

TEST(CliUvSet, InfoReadsTheUvSetAsked) {
  const auto dir = tempDir("cli_uv_set");
  TwoMaterialGltf{}.write(dir, "two");
  // TEXCOORD_0 maps each quad onto [0, 1]^2, TEXCOORD_1 onto [0.25, 0.75]^2.
  const std::vector<double> first = chartUvAreas({"info", "two.gltf", "--json"}, dir);
  const std::vector<double> second =
      chartUvAreas({"info", "two.gltf", "--json", "--uv-set", "1"}, dir);
  ASSERT_EQ(first.size(), static_cast<size_t>(TwoMaterialGltf::kPrimitives));
  ASSERT_EQ(second.size(), first.size());
  for (size_t c = 0; c < first.size(); ++c) {
    EXPECT_NEAR(first[c], 1.0, 1e-9) << c;
    EXPECT_NEAR(second[c], 0.25, 1e-9) << c;
  }
}

TEST(CliUvSet, MissingUvSetIsOneLine) {
  const auto dir = tempDir("cli_uv_set_missing");
  TwoMaterialGltf asset;
  asset.secondUvSet = false;
  asset.write(dir, "two");
  const CliResult r = runCli({"info", "two.gltf", "--uv-set", "1"}, dir);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(lineCount(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("mesh 0 ('quads') primitive 2 has no TEXCOORD_1"), std::string::npos)
      << r.err;
  const CliResult builtin = runCli({"info", "builtin:cube", "--uv-set", "1"}, dir);
  EXPECT_NE(builtin.status, 0);
  EXPECT_EQ(lineCount(builtin.err), 1) << builtin.err;
}

}  // namespace
}  // namespace texgrad::test
