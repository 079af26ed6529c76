// Operator assembly benchmark (fem/ + operators/): TexelOperators on shared meshes at 1024^2 and
// 2048^2, one vs two threads. `bench_operators --table MESH RES` prints one row of the table of
// scripts/bench-operators.sh instead (run it in a fresh process per mesh for peak memory).
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>

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
    ->ArgsProduct({{1024, 2048}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);
BENCHMARK_CAPTURE(assemble, bob, std::string("bob/bob_tri.obj"))
    ->ArgsProduct({{1024, 2048}, {2}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);
BENCHMARK_CAPTURE(reassemble, spot, std::string("spot/spot_triangulated.obj"))
    ->ArgsProduct({{2048}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
namespace {

/// CPU seconds (user + system, all threads) this process has used so far.
double cpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto seconds = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
  };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

/// Wall and CPU seconds to build TexelOperators (clipping, integration, pattern, M and S).
struct Timing {
  double wall = 1e300, cpu = 1e300;
};

/// Best of `repeats` builds with at most `threads` threads.
Timing assemblyTiming(const Input& in, int threads, int repeats) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                            static_cast<size_t>(threads));
  Timing best;
  for (int r = 0; r < repeats; ++r) {
    const double cpu = cpuSeconds();
    const auto start = std::chrono::steady_clock::now();
    texgrad::TexelOperators ops(in.mesh, in.atlas, in.grid);
    benchmark::DoNotOptimize(ops.stiffness().nonZeros());
    best.wall = std::min(
        best.wall, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    best.cpu = std::min(best.cpu, cpuSeconds() - cpu);
  }
  return best;
}

/// Peak resident memory of this process so far, in MB.
double peakMegabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

/// One table row: texels (interior / boundary), boundary cells, assembly wall time with 1 thread,
/// its CPU time (robust to other load), wall time with 2 threads (best of two each), seam pieces,
/// and the peak resident memory of the process after its first assembly (mesh, atlas, grid and one
/// TexelOperators).
int tableRow(const std::string& mesh, int resolution) {
  const Input& in = input(mesh, resolution);
  int interior = 0, boundary = 0, partialCells = 0;
  for (auto c : in.grid.texelClass) {
    interior += c == texgrad::TexelClass::Interior;
    boundary += c == texgrad::TexelClass::Boundary;
  }
  for (auto c : in.grid.cellCoverage) partialCells += c == texgrad::CellCoverage::Partial;
  int seamPieces = 0;
  {
    texgrad::TexelOperators ops(in.mesh, in.atlas, in.grid);
    seamPieces = ops.report().seamPieces;
  }
  const double peak = peakMegabytes();
  const Timing two = assemblyTiming(in, 2, 2), one = assemblyTiming(in, 1, 2);
  std::printf("%d %d %d %d %.3f %.3f %.3f %d %.0f\n", resolution, interior, boundary, partialCells,
              one.wall, one.cpu, two.wall, seamPieces, peak);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--table") == 0)
    return tableRow(argv[2], std::atoi(argv[3]));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
