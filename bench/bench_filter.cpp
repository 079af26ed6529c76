// End-to-end filtering as `texgrad filter` runs it (read mesh and texture, operators, solve,
// write), spot at 2048², multigrid (default) against the direct solver measured in the same run.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "texgrad/apps/filter.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"

namespace {

const std::filesystem::path kData = TEXGRAD_SHARED_DATA;

/// spot's texture upsampled (nearest) to 2048², written once to a temporary PNG.
const std::filesystem::path& texture2048() {
  static const std::filesystem::path path = [] {
    const texgrad::Image small = texgrad::readImage(kData / "spot" / "spot_texture.png");
    texgrad::Image big(2048, 2048, small.channels, small.format);
    for (int j = 0; j < 2048; ++j)
      for (int i = 0; i < 2048; ++i)
        for (int c = 0; c < small.channels; ++c) big.at(i, j, c) = small.at(i / 2, j / 2, c);
    const auto p = std::filesystem::temp_directory_path() / "texgrad_bench_spot_2048.png";
    texgrad::writeImage(p, big);
    return p;
  }();
  return path;
}

void filterEndToEnd(benchmark::State& state, texgrad::SolverKind kind) {
  const auto input = texture2048();
  const auto output = std::filesystem::temp_directory_path() / "texgrad_bench_filtered.png";
  for (auto _ : state) {
    texgrad::TexturedMesh mesh = texgrad::readMesh(kData / "spot" / "spot_triangulated.obj");
    const texgrad::Image texture = texgrad::readImage(input);
    const texgrad::TexelDomain domain(std::move(mesh), texture.width, texture.height);
    texgrad::FilterOptions options;  // default solver (CG + V-cycle) unless the direct baseline
    options.beta = 0.5;
    if (kind == texgrad::SolverKind::Direct) options.solver.kind = kind;
    const texgrad::FilterResult result = texgrad::filterTexture(domain, texture, options);
    texgrad::writeImage(output, result.image);
    state.counters["texels"] = domain.unknowns();
  }
}

BENCHMARK_CAPTURE(filterEndToEnd, default_cg, texgrad::SolverKind::MultigridCg)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK_CAPTURE(filterEndToEnd, direct_baseline, texgrad::SolverKind::Direct)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
