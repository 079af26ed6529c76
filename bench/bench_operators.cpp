// Operator assembly benchmark (fem/ + operators/): TexelOperators on shared meshes at 1024^2 and
// 2048^2, one vs two threads.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <string>

#include <map>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/operators/texel_operators.h"

namespace {

struct Input {
  texgrad::TexturedMesh mesh;
  texgrad::Atlas atlas;
  texgrad::TexelGrid grid;
};

const Input& input(const std::string& relative, int resolution) {
  static std::map<std::pair<std::string, int>, Input> cache;
  auto [it, added] = cache.try_emplace({relative, resolution});
  if (added) {
    it->second.mesh = texgrad::readMesh(std::string(TEXGRAD_SHARED_DATA) + "/" + relative);
    it->second.atlas = texgrad::buildAtlas(it->second.mesh);
    it->second.grid =
        texgrad::buildTexelGrid(it->second.mesh, it->second.atlas, resolution, resolution);
  }
  return it->second;
}

void assemble(benchmark::State& state, const std::string& mesh) {
  const int resolution = static_cast<int>(state.range(0));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              static_cast<size_t>(state.range(1)));
  const Input& in = input(mesh, resolution);
  for (auto _ : state) {
    texgrad::TexelOperators ops(in.mesh, in.atlas, in.grid);
    benchmark::DoNotOptimize(ops.stiffness().nonZeros());
    state.counters["texels"] = in.grid.unknownCount();
    state.counters["seamPieces"] = ops.report().seamPieces;
  }
}

void reassemble(benchmark::State& state, const std::string& mesh) {
  const Input& in = input(mesh, static_cast<int>(state.range(0)));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              static_cast<size_t>(state.range(1)));
  texgrad::TexelOperators ops(in.mesh, in.atlas, in.grid);
  std::vector<double> beta(size_t(in.grid.nx + 1) * (in.grid.ny + 1), 2.0);
  for (auto _ : state) benchmark::DoNotOptimize(ops.modulatedStiffness(beta).nonZeros());
}

}  // namespace

BENCHMARK_CAPTURE(assemble, spot, std::string("spot/spot_triangulated.obj"))
    ->ArgsProduct({{1024, 2048}, {1, 2}})->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK_CAPTURE(assemble, bob, std::string("bob/bob_tri.obj"))
    ->ArgsProduct({{1024, 2048}, {2}})->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK_CAPTURE(reassemble, spot, std::string("spot/spot_triangulated.obj"))
    ->ArgsProduct({{2048}, {1, 2}})->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_MAIN();
