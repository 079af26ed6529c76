// Benchmarks for the geodesic app (paper Sec. 7.3): interactive heat-method updates (one V-cycle on
// each system plus the normalised-gradient divergence) on spot at 1024^2 with 2 threads.
#include <benchmark/benchmark.h>
#include <time.h>

#include <filesystem>
#include <map>
#include <memory>

#include "texgrad/apps/geodesic.h"
#include "texgrad/io/mesh_reader.h"

using namespace texgrad;

namespace {

constexpr int kResolution = 1024;
constexpr int kThreads = 2;

/// The spot domain at 1024^2, built once (operator construction is not what is measured here).
const TexelDomain& spotDomain() {
  static const std::unique_ptr<TexelDomain> domain = [] {
    const std::filesystem::path obj =
        std::filesystem::path(TEXGRAD_SHARED_DATA) / "spot" / "spot_triangulated.obj";
    return std::make_unique<TexelDomain>(readMesh(obj), kResolution, kResolution);
  }();
  return *domain;
}

/// CPU time of the whole process (all threads, spinning workers included): on 2 cores shared with
/// the browser, the viewer's update rate is bounded by CPU per update rather than wall time.
double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

GeodesicOptions benchOptions() {
  GeodesicOptions options = GeodesicOptions::interactive();
  options.solver.multigrid.threads = kThreads;
  return options;
}

/// The interactive solver with `sweeps` Gauss–Seidel sweeps per level and a source set, built
/// once per sweep count (Google Benchmark calls a benchmark several times while sizing the run,
/// and the set-up is not what is measured here).
GeodesicSolver& interactiveSolver(int sweeps) {
  static std::map<int, std::unique_ptr<GeodesicSolver>> solvers;
  std::unique_ptr<GeodesicSolver>& solver = solvers[sweeps];
  if (!solver) {
    GeodesicOptions options = benchOptions();
    options.solver.multigrid.sweeps = sweeps;
    solver = std::make_unique<GeodesicSolver>(spotDomain(), options);
    solver->setSource(GeodesicSource::atVertex(100));
  }
  return *solver;
}

/// Updates timed per source: about the refinement after a click in the viewer, whose picture
/// settles within about ten updates. The heat settles within 5-11 of them, after which update()
/// refines only the distance (GeodesicSolver::update), so updates on one source for ever would
/// time mostly those cheaper updates.
constexpr int kUpdatesPerSource = 8;

/// kUpdatesPerSource interactive updates after setting a new source (not timed) per iteration;
/// items/s = updates per second, the counters are per update. Argument: sweeps per level,
/// kInteractiveSweeps (what the viewer runs) and the paper's 3 as the baseline.
void BM_GeodesicInteractiveUpdate(benchmark::State& state) {
  GeodesicSolver& solver = interactiveSolver(static_cast<int>(state.range(0)));
  const int vertices = static_cast<int>(spotDomain().mesh().positions.size());
  int vertex = 100;
  double cpu = 0.0, diffusion = 0.0, divergence = 0.0, distance = 0.0;
  int settled = 0;
  for (auto _ : state) {
    state.PauseTiming();
    solver.setSource(GeodesicSource::atVertex(vertex));
    vertex = (vertex + 97) % vertices;
    state.ResumeTiming();
    const double cpuStart = processCpuSeconds();
    for (int k = 0; k < kUpdatesPerSource; ++k) {
      solver.update();
      diffusion += solver.timings().diffusion;
      divergence += solver.timings().divergence;
      distance += solver.timings().distance;
      settled += solver.heatSettled();
    }
    cpu += processCpuSeconds() - cpuStart;
    benchmark::DoNotOptimize(solver.distances().data());
  }
  const double updates = static_cast<double>(state.iterations()) * kUpdatesPerSource;
  state.SetItemsProcessed(static_cast<int64_t>(updates));
  state.counters["process_cpu_ms"] = 1e3 * cpu / updates;
  state.counters["unknowns"] = spotDomain().unknowns();
  state.counters["diffusion_ms"] = 1e3 * diffusion / updates;
  state.counters["divergence_ms"] = 1e3 * divergence / updates;
  state.counters["distance_ms"] = 1e3 * distance / updates;
  state.counters["heat_settled"] = settled / updates;  // fraction of updates after settling
}
BENCHMARK(BM_GeodesicInteractiveUpdate)
    ->Arg(kInteractiveSweeps)
    ->Arg(3)
    ->ArgName("sweeps")
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0)
    ->UseRealTime();  // updates per wall-clock second: the main thread's CPU time leaves out waits

/// Picking a new source (resolve + reset) followed by one update, as after a click.
void BM_GeodesicNewSource(benchmark::State& state) {
  const TexelDomain& domain = spotDomain();
  GeodesicSolver solver(domain, benchOptions());
  int vertex = 0;
  for (auto _ : state) {
    solver.setSource(GeodesicSource::atVertex(vertex));
    vertex = (vertex + 97) % static_cast<int>(domain.mesh().positions.size());
    solver.update();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_GeodesicNewSource)->Unit(benchmark::kMillisecond)->MinTime(2.0)->UseRealTime();

/// Per-mesh set-up: gradient samples and both solvers' init + update.
void BM_GeodesicSetup(benchmark::State& state) {
  const TexelDomain& domain = spotDomain();
  for (auto _ : state) {
    GeodesicSolver solver(domain, benchOptions());
    benchmark::DoNotOptimize(&solver);
  }
}
BENCHMARK(BM_GeodesicSetup)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
