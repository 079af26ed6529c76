// Benchmarks for the solver module (paper §6.3, Table 1): multigrid init / update / V-cycle and
// CHOLMOD factor / solve on synthetic square charts, and V-cycles on spot's atlas.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <memory>

#include "../tests/solver/synthetic_problem.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/operators/texel_operators.h"
#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/multigrid_solver.h"

using namespace texgrad;

namespace {

/// Screening weight of the filter application (paper Sec. 7.1).
constexpr double kAlpha = 1e4;

/// alpha M + S for a square chart of n x n Full cells in an (n + 3)^2 grid (Partial ring), built
/// column by column from per-cell bilinear element matrices without triplet lists.
struct Problem {
  TexelGrid grid;
  Eigen::SparseMatrix<double> a;
};

Eigen::SparseMatrix<double> assembleSquare(const TexelGrid& g, double alpha) {
  const int n = g.unknownCount();
  double area = 0.0;
  for (CellCoverage c : g.cellCoverage)
    area += c == CellCoverage::Full ? 1.0 : c == CellCoverage::Partial ? 0.5 : 0.0;
  // Element entry between corners (ix, iy) and (jx, jy) of a unit cell.
  auto element = [&](int ix, int iy, int jx, int jy) {
    const double m = (ix == jx ? 2.0 : 1.0) * (iy == jy ? 2.0 : 1.0) / 36.0 / area;
    const double sx = (ix == jx ? 1.0 : -1.0) * (iy == jy ? 1.0 / 3 : 1.0 / 6);
    const double sy = (iy == jy ? 1.0 : -1.0) * (ix == jx ? 1.0 / 3 : 1.0 / 6);
    return alpha * m + sx + sy;
  };
  Eigen::SparseMatrix<double> a(n, n);
  a.reserve(Eigen::VectorXi::Constant(n, 9));
  for (int u = 0; u < n; ++u) {
    const int t = g.texelOfUnknown[static_cast<size_t>(u)], x = t % g.nx, y = t / g.nx;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (x + dx < 0 || y + dy < 0 || x + dx >= g.nx || y + dy >= g.ny) continue;
        const int v = g.unknownOfTexel[static_cast<size_t>(g.texelIndex(x + dx, y + dy))];
        if (v < 0) continue;
        double sum = 0.0;
        for (int b = y - 1; b <= y; ++b)  // cells in both footprints
          for (int c = x - 1; c <= x; ++c) {
            if (c > x + dx || c + 1 < x + dx || b > y + dy || b + 1 < y + dy) continue;
            const CellCoverage cov = g.cellCoverage[static_cast<size_t>(g.cellIndex(c, b))];
            if (cov == CellCoverage::Empty) continue;
            sum += (cov == CellCoverage::Full ? 1.0 : 0.5) *
                   element(x - c, y - b, x + dx - c, y + dy - b);
          }
        a.insert(v, u) = sum;
      }
  }
  a.makeCompressed();
  return a;
}

const Problem& problem(int size) {
  static std::map<int, std::unique_ptr<Problem>> cache;
  auto& p = cache[size];
  if (!p) {
    const int n = size - 3;
    p = std::make_unique<Problem>();
    p->grid = test::makeGrid(size, size, [n](int a, int b) -> test::CellInfo {
      if (a < 0 || b < 0 || a > n + 1 || b > n + 1) return {};
      if (a == 0 || b == 0 || a == n + 1 || b == n + 1) return {CellCoverage::Partial, 0};
      return {CellCoverage::Full, 0};
    });
    p->a = assembleSquare(p->grid, kAlpha);
  }
  return *p;
}

/// spot's atlas at size^2 with A = alpha M + S (filter system), built once per size.
struct SpotProblem {
  std::unique_ptr<TexelDomain> domain;
  Eigen::SparseMatrix<double> a;
};

const SpotProblem& spot(int size) {
  static std::map<int, SpotProblem> cache;
  SpotProblem& p = cache[size];
  if (!p.domain) {
    const std::filesystem::path obj =
        std::filesystem::path(TEXGRAD_SHARED_DATA) / "spot" / "spot_triangulated.obj";
    p.domain = std::make_unique<TexelDomain>(readMesh(obj), size, size);
    p.a = kAlpha * p.domain->operators().mass() + p.domain->operators().stiffness();
  }
  return p;
}

/// Runs V-cycles on `channels` channels (RGB by default) and reports the time per phase.
template <typename T>
void runCycles(benchmark::State& state, const TexelGrid& grid, const Eigen::SparseMatrix<double>& a,
               int threads, int channels = 3, int sweeps = MultigridOptions().sweeps) {
  MultigridOptions o;
  o.threads = threads;
  o.sweeps = sweeps;
  MultigridSolver<T> mg(o);
  mg.init(grid, a);
  mg.update(a);
  const Eigen::Index n = a.rows();
  const typename MultigridSolver<T>::Matrix b = test::randomBlock(n, channels).cast<T>();
  typename MultigridSolver<T>::Matrix x = MultigridSolver<T>::Matrix::Zero(n, channels);
  const PhaseTimes before = mg.cycleTimes();
  for (auto _ : state) mg.cycle(b, x);
  PhaseTimes total = mg.cycleTimes();
  total.relaxation -= before.relaxation;
  total.boundary -= before.boundary;
  total.coarse -= before.coarse;
  total.transfer -= before.transfer;
  total.other -= before.other;
  const double it = static_cast<double>(state.iterations());
  state.counters["texels"] = static_cast<double>(n);
  state.counters["relax_ms"] = 1e3 * total.relaxation / it;
  state.counters["boundary_ms"] = 1e3 * total.boundary / it;
  state.counters["coarse_ms"] = 1e3 * total.coarse / it;
  state.counters["transfer_ms"] = 1e3 * total.transfer / it;
  state.counters["other_ms"] = 1e3 * total.other / it;
}

/// One RGB V-cycle on a synthetic square chart; args: size, threads.
template <typename T>
void BM_VCycle(benchmark::State& state) {
  const Problem& p = problem(static_cast<int>(state.range(0)));
  runCycles<T>(state, p.grid, p.a, static_cast<int>(state.range(1)));
}

/// One RGB V-cycle on spot's atlas (13 charts, seams); args: size, threads.
template <typename T>
void BM_VCycleSpot(benchmark::State& state) {
  const SpotProblem& p = spot(static_cast<int>(state.range(0)));
  runCycles<T>(state, p.domain->grid(), p.a, static_cast<int>(state.range(1)));
}

/// One single-channel V-cycle with 2 sweeps on spot's atlas, as each system of an interactive
/// geodesic update (kInteractiveSweeps); arg: size; 2 threads.
template <typename T>
void BM_VCycleSpotScalar(benchmark::State& state) {
  const SpotProblem& p = spot(static_cast<int>(state.range(0)));
  runCycles<T>(state, p.domain->grid(), p.a, 2, 1, 2);
}

/// Read spot -> texel domain with operators -> multigrid init + update: ready to cycle.
void BM_SpotInitToReady(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  const std::filesystem::path obj =
      std::filesystem::path(TEXGRAD_SHARED_DATA) / "spot" / "spot_triangulated.obj";
  for (auto _ : state) {
    TexelDomain domain(readMesh(obj), size, size);
    const Eigen::SparseMatrix<double> a =
        kAlpha * domain.operators().mass() + domain.operators().stiffness();
    MultigridOptions o;
    o.threads = 2;
    MultigridSolver<float> mg(o);
    mg.initAndUpdate(domain.grid(), a);  // as the apps set up a one-shot solve
    benchmark::DoNotOptimize(&mg);
  }
}

void BM_MultigridInit(benchmark::State& state) {
  const Problem& p = problem(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    MultigridSolver<float> mg;
    mg.init(p.grid, p.a);
    benchmark::DoNotOptimize(mg.hierarchy().levelCount());
  }
}

void BM_MultigridUpdate(benchmark::State& state) {
  const Problem& p = problem(static_cast<int>(state.range(0)));
  MultigridSolver<float> mg;
  mg.init(p.grid, p.a);
  for (auto _ : state) mg.update(p.a);
}

void BM_CholmodFactor(benchmark::State& state) {
  const Problem& p = problem(static_cast<int>(state.range(0)));
  CholmodSolver solver;
  solver.analyzePattern(p.a);
  for (auto _ : state) solver.factorize(p.a);
  state.counters["analyze_s"] = solver.stats().analyzeSeconds;
  state.counters["nnzL"] = static_cast<double>(solver.stats().factorNonZeros);
}

void BM_CholmodSolveRgb(benchmark::State& state) {
  const Problem& p = problem(static_cast<int>(state.range(0)));
  CholmodSolver solver(p.a);
  Eigen::MatrixXd x = test::randomBlock(p.a.rows(), 3);
  for (auto _ : state) solver.solveInPlace(x);
}

}  // namespace

BENCHMARK(BM_VCycle<float>)->ArgsProduct({{1024, 2048}, {1, 2}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VCycle<double>)->ArgsProduct({{1024, 2048}, {1, 2}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VCycleSpot<float>)->ArgsProduct({{1024, 2048}, {2}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VCycleSpot<double>)->ArgsProduct({{1024, 2048}, {2}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VCycleSpotScalar<float>)->Arg(1024)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SpotInitToReady)->Arg(2048)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_MultigridInit)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_MultigridUpdate)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(BM_CholmodFactor)->Arg(1024)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_CholmodSolveRgb)->Arg(1024)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_MAIN();
