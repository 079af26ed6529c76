// One row of the solver benchmark table (issue: texel-grid multigrid, paper §6 and Table 1) for
// one mesh at one resolution: set-up phases, V-cycle times in float and double on 1 and 2
// threads, the full CHOLMOD factorisation, peak memory, and the error to the direct solution
// after each of the first cycles on the paper's Fig. 11 problem (alpha = 1e4, random RGB psi,
// x = 0). scripts/bench-solver.sh runs one process per row so that peak memory is per row.
//
// Usage: solver_table MESH RESOLUTION [--name NAME] [--no-direct] [--line-ratio R]
//        [--weak-row-reach D] | solver_table --header
// (--line-ratio 0 --weak-row-reach 0: the paper's smoother and split, as a baseline.)
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/multigrid_solver.h"

namespace texgrad {
namespace {

constexpr int kErrorCycles = 6;  ///< cycles whose error to the direct solution is reported

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Peak resident memory of this process so far, in GB.
double peakGigabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / (1024.0 * 1024.0);
}

/// Set-up and per-cycle times of one multigrid configuration.
struct MultigridTimes {
  double init = 0.0, update = 0.0, cycle = 0.0;
};

/// Seconds of initAndUpdate (one chain of Galerkin products, as the apps set up a solve).
double timeInitAndUpdate(const TexelGrid& grid, const SparseSum& a, MultigridOptions options,
                         int threads) {
  options.threads = threads;
  MultigridSolver<float> solver(options);
  const auto start = Clock::now();
  solver.initAndUpdate(grid, a);
  return secondsSince(start);
}

/// Times init, update and the mean of `cycles` V-cycles on the RGB right-hand side b.
template <typename Scalar>
MultigridTimes timeMultigrid(const TexelGrid& grid, const SparseSum& a, const Eigen::MatrixXd& b,
                             MultigridOptions options, int threads, int cycles) {
  options.threads = threads;
  MultigridSolver<Scalar> solver(options);
  MultigridTimes t;
  auto start = Clock::now();
  solver.init(grid, a);
  t.init = secondsSince(start);
  start = Clock::now();
  solver.update(a);
  t.update = secondsSince(start);
  using Matrix = typename MultigridSolver<Scalar>::Matrix;
  const Matrix rhs = b.cast<Scalar>();
  Matrix x = Matrix::Zero(b.rows(), b.cols());
  solver.cycle(rhs, x);  // warm-up: first touch of the workspace
  start = Clock::now();
  for (int k = 0; k < cycles; ++k) solver.cycle(rhs, x);
  t.cycle = secondsSince(start) / cycles;
  return t;
}

/// Relative RMS error to `truth` after each of the first kErrorCycles V-cycles from x = 0.
template <typename Scalar>
std::vector<double> errorPerCycle(const TexelGrid& grid, const SparseSum& a,
                                  const Eigen::MatrixXd& b, const Eigen::MatrixXd& truth,
                                  const MultigridOptions& options) {
  MultigridSolver<Scalar> solver(options);
  solver.init(grid, a);
  solver.update(a);
  using Matrix = typename MultigridSolver<Scalar>::Matrix;
  const Matrix rhs = b.cast<Scalar>();
  Matrix x = Matrix::Zero(b.rows(), b.cols());
  std::vector<double> errors;
  for (int k = 0; k < kErrorCycles; ++k) {
    solver.cycle(rhs, x);
    errors.push_back((x.template cast<double>() - truth).norm() / truth.norm());
  }
  return errors;
}

void printHeader() {
  std::cout << "| mesh | res | texels | interior | boundary | levels | read s | operators s | "
               "MG init s (1T/2T) | MG update s (1T/2T) | V-cycle float ms (1T/2T) | "
               "V-cycle double ms (1T/2T) | ready s (read + operators + initAndUpdate 2T) | peak "
               "GB (MG) | CHOLMOD factor s | "
               "CHOLMOD solve s | peak GB (with CHOLMOD) | rel. error after cycles 1..6 (float) |\n"
            << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
}

/// M psi for a random texture psi with `channels` channels (values in [0, 1], fixed seed).
Eigen::MatrixXd randomMassRhs(const TexelDomain& domain, int channels) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> value(0.0, 1.0);
  Eigen::MatrixXd psi(domain.unknowns(), channels);
  for (Eigen::Index k = 0; k < psi.size(); ++k) psi.data()[k] = value(rng);
  return domain.operators().mass() * psi;
}

int run(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "--header") == 0) {
    printHeader();
    return 0;
  }
  if (argc < 3) {
    std::cerr << "usage: solver_table MESH RESOLUTION [--name NAME] [--no-direct] "
                 "[--line-ratio R] [--weak-row-reach D] | solver_table --header\n";
    return 2;
  }
  const std::string path = argv[1];
  const int res = std::stoi(argv[2]);
  std::string name = std::filesystem::path(path).stem().string();
  bool direct = true;
  MultigridOptions options;
  for (int k = 3; k < argc; ++k) {
    if (std::strcmp(argv[k], "--no-direct") == 0) direct = false;
    if (std::strcmp(argv[k], "--name") == 0 && k + 1 < argc) name = argv[++k];
    if (std::strcmp(argv[k], "--line-ratio") == 0 && k + 1 < argc)
      options.lineRatio = std::stod(argv[++k]);
    if (std::strcmp(argv[k], "--weak-row-reach") == 0 && k + 1 < argc)
      options.weakRowReach = std::stoi(argv[++k]);
  }
  options.validate();

  auto start = Clock::now();
  TexturedMesh mesh = readMesh(path);
  const double read = secondsSince(start);
  start = Clock::now();
  // The benchmark's system (alpha M + S) x = M psi never re-assembles: no piece integrals.
  const TexelDomain domain(std::move(mesh), res, res, OperatorOptions::assembledOnce());
  const double operators = secondsSince(start);
  const TexelGrid& grid = domain.grid();
  int interior = 0, boundary = 0;
  for (int32_t t : grid.texelOfUnknown)
    (grid.texelClass[t] == TexelClass::Interior ? interior : boundary) += 1;

  // The paper's Fig. 11 system alpha M + S: the multigrid set-up reads it from M and S (one
  // pattern), so A itself is only formed for the direct solve below.
  constexpr double kAlpha = 1e4;
  const SparseSum a(kAlpha, domain.operators().mass(), 1.0, domain.operators().stiffness());
  const Eigen::MatrixXd b = randomMassRhs(domain, 3);

  const int cycles = 5;
  const double fused = timeInitAndUpdate(grid, a, options, 2);  // first: pays the process's page faults
  // Peak of a process that reads, builds operators and sets up one solver, as the CLI does (the
  // timing runs below reuse the heap but fragment it).
  const double peakMultigrid = peakGigabytes();
  const MultigridTimes f2 = timeMultigrid<float>(grid, a, b, options, 2, cycles);
  const MultigridTimes f1 = timeMultigrid<float>(grid, a, b, options, 1, cycles);
  const MultigridTimes d2 = timeMultigrid<double>(grid, a, b, options, 2, cycles);
  const MultigridTimes d1 = timeMultigrid<double>(grid, a, b, options, 1, cycles);
  int levels = 0;
  {
    MultigridSolver<float> probe(options);
    probe.init(grid, a);
    levels = probe.hierarchy().levelCount();
  }
  const double ready = read + operators + fused;

  std::string factor = "-", solve = "-", peakDirect = "-", errors = "-";
  char buffer[64];
  if (direct) {
    start = Clock::now();
    CholmodSolver cholmod(domain.operators().screenedSystem(kAlpha));
    std::snprintf(buffer, sizeof buffer, "%.2f", secondsSince(start));
    factor = buffer;
    start = Clock::now();
    const Eigen::MatrixXd truth = cholmod.solve(b);
    std::snprintf(buffer, sizeof buffer, "%.3f", secondsSince(start));
    solve = buffer;
    std::snprintf(buffer, sizeof buffer, "%.2f", peakGigabytes());
    peakDirect = buffer;
    errors.clear();
    for (double e : errorPerCycle<float>(grid, a, b, truth, options)) {
      std::snprintf(buffer, sizeof buffer, "%s%.1e", errors.empty() ? "" : " ", e);
      errors += buffer;
    }
  }
  std::printf(
      "| %s | %d | %d | %d | %d | %d | %.2f | %.2f | %.2f / %.2f | %.2f / %.2f | %.0f / %.0f | "
      "%.0f / %.0f | %.2f | %.2f | %s | %s | %s | %s |\n",
      name.c_str(), res, domain.unknowns(), interior, boundary, levels, read, operators, f1.init,
      f2.init, f1.update, f2.update, 1e3 * f1.cycle, 1e3 * f2.cycle, 1e3 * d1.cycle, 1e3 * d2.cycle,
      ready, peakMultigrid, factor.c_str(), solve.c_str(), peakDirect.c_str(), errors.c_str());
  return 0;
}

}  // namespace
}  // namespace texgrad

int main(int argc, char** argv) {
  try {
    return texgrad::run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "solver_table: " << e.what() << "\n";
    return 1;
  }
}
