// Benchmarks for LIC (paper Sec. 7.4): MG-preconditioned CG against the CHOLMOD direct solve on
// bob at 1024^2 with its principal-curvature field, in one run so the two times compare.
#include <benchmark/benchmark.h>

#include <chrono>
#include <filesystem>
#include <memory>

#include "texgrad/apps/lic.h"
#include "texgrad/apps/vector_field.h"
#include "texgrad/io/mesh_reader.h"

using namespace texgrad;

namespace {

constexpr int kResolution = 1024;
constexpr int kThreads = 2;

/// The bob domain at 1024^2, built once (operator construction is not what is measured here).
TexelDomain& bobDomain() {
  static const std::unique_ptr<TexelDomain> domain = [] {
    const std::filesystem::path obj =
        std::filesystem::path(TEXGRAD_SHARED_DATA) / "bob" / "bob_tri.obj";
    return std::make_unique<TexelDomain>(readMesh(obj), kResolution, kResolution);
  }();
  return *domain;
}

/// `texgrad lic`'s default field: the major principal direction scaled by |k1 - k2|.
const std::vector<Eigen::Vector2d>& bobField() {
  static const std::vector<Eigen::Vector2d> field = [] {
    TexelDomain& domain = bobDomain();
    return fieldInTexelCoordinates(domain.mesh(), domain.grid(),
                                   curvatureField(domain.mesh(), CurvatureDirection::Major));
  }();
  return field;
}

/// One full LIC per iteration (metric, assembly, solver set-up, diffusion and sharpening solves)
/// with the solver given by the benchmark argument (0 = MG-PCG, 1 = direct). Counters split the
/// time (solve_s: both solves): solver_setup_s + solve_s is what the solver choice changes.
void BM_LicBob1024(benchmark::State& state) {
  TexelDomain& domain = bobDomain();
  const std::vector<Eigen::Vector2d>& field = bobField();
  LicOptions options;
  options.solver.kind = state.range(0) == 0 ? SolverKind::MultigridCg : SolverKind::Direct;
  options.solver.multigrid.threads = kThreads;
  const Eigen::MatrixXd noise = licNoise(domain.grid(), options.channels, options.seed);
  LicReport report;
  double solve = 0.0;
  for (auto _ : state) {
    LineIntegralConvolution lic(domain, field, options);
    const auto start = std::chrono::steady_clock::now();
    const Eigen::MatrixXd values = lic.convolve(noise, &report);
    solve = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    benchmark::DoNotOptimize(values.data());
  }
  state.SetLabel(toString(options.solver.kind));
  state.counters["unknowns"] = domain.unknowns();
  state.counters["setup_s"] = report.setupSeconds;
  state.counters["solver_setup_s"] = report.solverSetupSeconds;
  state.counters["solve_s"] = solve;
  state.counters["solver_total_s"] = report.solverSetupSeconds + solve;
  state.counters["diffusion_iters"] = report.diffusion.iterations;
  state.counters["sharpen_iters"] = report.sharpening.iterations;
  state.counters["converged"] = report.diffusion.converged && report.sharpening.converged;
}
BENCHMARK(BM_LicBob1024)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
