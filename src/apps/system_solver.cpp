// SystemSolver: dispatches to MultigridSolver<float|double>, multigrid-preconditioned CG or
// CHOLMOD, moving blocks between double (app side) and the cycle precision.
#include "texgrad/apps/system_solver.h"

#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "core/row_sums.h"
#include "texgrad/core/error.h"
#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/conjugate_gradient.h"

namespace texgrad {
namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double residual(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b,
                const Eigen::MatrixXd& x, Eigen::MatrixXd& r) {
  r.resize(b.rows(), b.cols());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* values = a.valuePtr();
  // Column i of the symmetric A is row i, so each task writes only its own rows.
  return sumOverRows(b.rows(), [&](Eigen::Index begin, Eigen::Index end) {
    double acc = 0.0;
    for (Eigen::Index c = 0; c < b.cols(); ++c) {
      const double* xc = x.col(c).data();
      for (Eigen::Index i = begin; i < end; ++i) {
        double v = b(i, c);
        for (int e = outer[i]; e < outer[i + 1]; ++e) v -= values[e] * xc[inner[e]];
        r(i, c) = v;
        acc += v * v;
      }
    }
    return acc;
  });
}

double shiftResidual(Eigen::MatrixXd& r, const Eigen::MatrixXd& previousB,
                     const Eigen::MatrixXd& b) {
  return sumOverRows(b.rows(), [&](Eigen::Index begin, Eigen::Index end) {
    double acc = 0.0;
    for (Eigen::Index c = 0; c < b.cols(); ++c)
      for (Eigen::Index i = begin; i < end; ++i) {
        const double v = r(i, c) + (b(i, c) - previousB(i, c));
        r(i, c) = v;
        acc += v * v;
      }
    return acc;
  });
}

double addInPlace(Eigen::MatrixXd& x, const Eigen::MatrixXd& z) {
  return sumOverRows(x.rows(), [&](Eigen::Index begin, Eigen::Index end) {
    double acc = 0.0;
    for (Eigen::Index c = 0; c < x.cols(); ++c)
      for (Eigen::Index i = begin; i < end; ++i) {
        x(i, c) += z(i, c);
        acc += z(i, c) * z(i, c);
      }
    return acc;
  });
}

/// The stage update and initAndUpdate report (0 before, 1 after the factorisations).
constexpr std::string_view kSetupStage = "solver setup";

/// A number as an error message quotes it: %g (0.5, 1e-08), not std::to_string's six decimals.
std::string formatNumber(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

bool sameValues(const Eigen::MatrixXd& u, const Eigen::MatrixXd& v) {
  return sumOverRows(u.rows(), [&](Eigen::Index begin, Eigen::Index end) {
           for (Eigen::Index c = 0; c < u.cols(); ++c)
             for (Eigen::Index i = begin; i < end; ++i)
               if (u(i, c) != v(i, c)) return 1.0;
           return 0.0;
         }) == 0.0;
}

}  // namespace

SolverKind parseSolverKind(const std::string& text) {
  if (text == "multigrid") return SolverKind::Multigrid;
  if (text == "cg") return SolverKind::MultigridCg;
  if (text == "direct") return SolverKind::Direct;
  throw InvalidInputError("unknown solver '" + text + "'; use multigrid, cg or direct");
}

std::string toString(SolverKind kind) {
  switch (kind) {
    case SolverKind::Multigrid:
      return "multigrid";
    case SolverKind::MultigridCg:
      return "cg";
    case SolverKind::Direct:
      return "direct";
  }
  return "?";
}

bool parseSinglePrecision(const std::string& text) {
  if (text == "float") return true;
  if (text == "double") return false;
  throw InvalidInputError("unknown precision '" + text + "'; use float or double");
}

bool SolverSettings::cgUsesLevelZeroOperator() const {
  return kind == SolverKind::MultigridCg &&
         (!singlePrecision || effectiveTolerance() >= kFloatOperatorTolerance);
}

double SolverSettings::effectiveTolerance() const {
  if (tolerance == 0.0 && kind == SolverKind::MultigridCg) return kDefaultCgTolerance;
  return tolerance;
}

void SolverSettings::validate() const {
  multigrid.validate();
  if (cycles < 1)
    throw InvalidInputError("solver cycles is " + std::to_string(cycles) + "; expected >= 1");
  if (maxIterations < 1)
    throw InvalidInputError("solver maxIterations is " + std::to_string(maxIterations) +
                            "; expected >= 1");
  if (!(tolerance >= 0.0 && tolerance <= 1.0))
    throw InvalidInputError("solver tolerance is " + formatNumber(tolerance) +
                            "; expected 0 to 1 (a relative residual; 0 = the kind's default)");
}

namespace {

/// A FloatSystem formed in double (formedMatrix) for a solver that keeps A; the system is freed
/// once formed.
Eigen::SparseMatrix<double> formedInDouble(FloatSystem a) {
  return formedMatrix(a);
}

}  // namespace

struct SystemSolver::Impl {
  SolverSettings settings;
  std::unique_ptr<MultigridSolver<float>> multigridFloat;
  std::unique_ptr<MultigridSolver<double>> multigridDouble;
  CholmodSolver direct;
  MatrixCopy copy;
  /// A of the last update while keepsMatrix(); empty otherwise (A is applied through the
  /// multigrid's level-0 stencils, row sums and boundary rows).
  Eigen::SparseMatrix<double> a;
  /// Forms A again for the change to double cycles when a is empty (formAgainWith).
  std::function<Eigen::SparseMatrix<double>()> formAgain;
  Eigen::Index rows = 0;  ///< of A
  double initTime = 0.0, updateTime = 0.0;
  double hierarchyTime = 0.0;  ///< of the build in the constructor, counted by the first init
  int unknowns = 0;            ///< of the grid (summary)
  tbb::task_arena arena;
  /// Refinement state: residual r = b - A x, correction z, and the b and x r belongs to.
  Eigen::MatrixXd r, z, lastX, lastB;
  bool cacheValid = false;

  Impl(const TexelGrid& grid, const SolverSettings& s, MatrixCopy c)
      : settings(s),
        copy(c),
        unknowns(grid.unknownCount()),
        arena(s.multigrid.threads > 0 ? s.multigrid.threads : tbb::task_arena::automatic) {
    settings.validate();
    if (settings.kind == SolverKind::Direct) return;
    if (settings.singlePrecision)  // float V-cycles; CG and refinement residuals stay double
      multigridFloat = std::make_unique<MultigridSolver<float>>(settings.multigrid);
    else
      multigridDouble = std::make_unique<MultigridSolver<double>>(settings.multigrid);
    // The grid is read here only: a one-shot caller may free its per-texel maps once the
    // hierarchy exists (TexelDomain::releaseImageMaps).
    const auto start = std::chrono::steady_clock::now();
    if (multigridFloat) multigridFloat->buildHierarchy(grid);
    if (multigridDouble) multigridDouble->buildHierarchy(grid);
    hierarchyTime = secondsSince(start);
  }

  /// Seconds since `start` plus the hierarchy build not yet counted by an init.
  double initSecondsSince(std::chrono::steady_clock::time_point start) {
    const double seconds = secondsSince(start) + hierarchyTime;
    hierarchyTime = 0.0;
    return seconds;
  }

  /// True while the solves need A itself, or the caller asked for it (MatrixCopy).
  bool keepsMatrix() const { return keepsMatrixFor(settings, copy, multigridFloat != nullptr); }

  /// keepsMatrix() of a solver with these settings and copy, cycling in float or not.
  static bool keepsMatrixFor(const SolverSettings& s, MatrixCopy c, bool floatCycles) {
    if (c == MatrixCopy::Kept) return true;
    if (refinesOnLevelZeroFor(s, c, floatCycles)) return false;
    return !s.cgUsesLevelZeroOperator();
  }

  /// True if float refinement cycles take their residuals from the level-0 operator and keep no
  /// refinement state between solves (MatrixCopy::NotForRefinement): not for a tolerance below
  /// kFloatOperatorTolerance, which those residuals' float rounding would not let them reach.
  bool refinesOnLevelZero() const {
    return refinesOnLevelZeroFor(settings, copy, multigridFloat != nullptr);
  }

  /// refinesOnLevelZero() of a solver with these settings and copy, cycling in float or not.
  static bool refinesOnLevelZeroFor(const SolverSettings& s, MatrixCopy c, bool floatCycles) {
    return c == MatrixCopy::NotForRefinement && s.kind == SolverKind::Multigrid && floatCycles &&
           (s.tolerance == 0.0 || s.tolerance >= SolverSettings::kFloatOperatorTolerance);
  }

  /// Takes over `from` as A; hands it to `factorise` (the direct or multigrid set-up), then frees
  /// it unless keepsMatrix() (setUpMultigrid hands it over to be freed inside the set-up).
  template <typename F>
  void adoptMatrix(Eigen::SparseMatrix<double>& from, F&& factorise) {
    a.swap(from);
    Eigen::SparseMatrix<double>().swap(from);
    a.makeCompressed();
    rows = a.rows();
    cacheValid = false;
    factorise(a);
    if (!keepsMatrix()) Eigen::SparseMatrix<double>().swap(a);
  }

  /// Runs `setUp` (a MultigridSolver's update or initAndUpdate) on `view` as the new A, for
  /// a solver that keeps no copy of A (!keepsMatrix()): nothing of A is formed or held.
  template <typename SetUp>
  void adoptView(const SparseSum& view, SetUp&& setUp) {
    Eigen::SparseMatrix<double>().swap(a);
    rows = view.rows();
    cacheValid = false;
    visitMultigrid([&](auto& solver) {
      setUp(solver, view);
      return 0;
    });
  }

  /// Hands `from` (A as a FloatSystem) over to the float multigrid's initAndUpdate (`init`) or
  /// update, for a solver that takes it (takesFloatSystem: float cycles, no copy of A kept),
  /// reporting and timing the set-up as the other set-ups do.
  void setUpFloatSystem(FloatSystem& from, bool init, const ProgressCallback& progress) {
    reportProgress(progress, kSetupStage, 0.0);
    const auto start = std::chrono::steady_clock::now();
    Eigen::SparseMatrix<double>().swap(a);
    rows = from.rows();
    cacheValid = false;
    if (init) {
      multigridFloat->initAndUpdate(std::move(from));
      initTime = initSecondsSince(start);
      updateTime = 0.0;
    } else {
      multigridFloat->update(std::move(from));
      updateTime = secondsSince(start);
    }
    reportProgress(progress, kSetupStage, 1.0);
  }

  /// Runs `setUp` (a MultigridSolver's update or initAndUpdate) on the adopted A: as a view
  /// while keepsMatrix(), else handing A over, so the set-up frees it once level 0 and A^1 are
  /// built instead of holding it while the coarser levels are (docs/memory.md).
  template <typename SetUp>
  void setUpMultigrid(Eigen::SparseMatrix<double>& adopted, SetUp&& setUp) {
    visitMultigrid([&](auto& solver) {
      if (keepsMatrix())
        setUp(solver, std::as_const(adopted));
      else
        setUp(solver, std::move(adopted));
      return 0;
    });
  }

  template <typename F>
  auto visitMultigrid(F&& f) const {
    if (multigridFloat) return f(*multigridFloat);
    if (!multigridDouble) throw Error("internal: multigrid used with the direct solver");
    return f(*multigridDouble);
  }

  template <typename Solver>
  static SolveReport cycles(Solver& solver, const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                            const SolveControl& control, const ProgressCallback& progress) {
    using Scalar = typename Solver::Matrix::Scalar;
    const typename Solver::Matrix bs = b.cast<Scalar>();
    typename Solver::Matrix xs = x.cast<Scalar>();
    SolveReport report = solver.solve(bs, xs, control, progress);
    x = xs.template cast<double>();
    return report;
  }

  /// Float V-cycles with the residual in double (mixed-precision iterative refinement): each
  /// cycle corrects x by V(b - A x), so accuracy is not limited by float rounding of A x. A
  /// float cycle that diverges (divergesFrom) is undone, and this solve and every later one
  /// cycle in double instead (useDoubleCycles). Polls `progress` before every cycle; a cancel
  /// leaves x at the last cycle's iterate.
  SolveReport refinedCycles(const Eigen::MatrixXd& b, Eigen::MatrixXd& x, int count,
                            const ProgressCallback& progress) {
    SolveReport report;
    const auto start = std::chrono::steady_clock::now();
    arena.execute([&] {
      try {
        cycleInPlace(b, x, count, progress, report);
      } catch (...) {  // a cancel or a divergence: r and z go all the same
        if (refinesOnLevelZero()) releaseRefinementState();
        throw;
      }
      if (refinesOnLevelZero())
        releaseRefinementState();
      else
        remember(b, x);
    });
    report.times.other = secondsSince(start);
    reportSolveProgress(progress, report, count, settings.tolerance, true);
    return report;
  }

  /// The cycles of refinedCycles, adding to `report`.
  void cycleInPlace(const Eigen::MatrixXd& b, Eigen::MatrixXd& x, int count,
                    const ProgressCallback& progress, SolveReport& report) {
    const double norm = b.norm() > 0 ? b.norm() : 1.0;
    report.residuals.push_back(std::sqrt(startingResidual(b, x)) / norm);
    // r now belongs to this b: a cancelled solve must not leave it to the next (remember).
    cacheValid = false;
    for (int k = 0; k < count; ++k) {
      reportSolveProgress(progress, report, count, settings.tolerance);
      visitMultigrid([&](const auto& solver) {
        solver.precondition(r, z);
        return 0;
      });
      double change = addInPlace(x, z);
      double rr = refinesOnLevelZero() ? subtractOperatorProduct(z, r) : residual(a, b, x, r);
      if (multigridFloat && divergesFrom(report.residuals.back(), std::sqrt(rr) / norm)) {
        x -= z;
        if (!keepsMatrix()) adoptFormedAgain();
        rr = residual(a, b, x, r);
        change = 0.0;
        useDoubleCycles();
      }
      ++report.iterations;
      report.residuals.push_back(std::sqrt(rr) / norm);
      report.rmsChange.push_back(
          std::sqrt(change / static_cast<double>(std::max<Eigen::Index>(1, z.size()))));
      if (settings.tolerance > 0 && report.residuals.back() <= settings.tolerance) {
        report.converged = true;
        break;
      }
    }
  }

  static constexpr const char* kDivergedWithoutMatrix =
      "float V-cycles diverged on this system (nearly singular: float rounding grows each "
      "cycle), and the solver keeps no copy of A to change to double cycles; solve it with double "
      "cycles (SolverSettings::singlePrecision false; CLI: --precision double)";

  /// Makes a the A that formAgain forms, for useDoubleCycles; throws FloatCyclesDiverged if the
  /// caller gave no way to form it.
  void adoptFormedAgain() {
    if (!formAgain) throw FloatCyclesDiverged(kDivergedWithoutMatrix);
    Eigen::SparseMatrix<double> formed = formAgain();
    if (formed.rows() != rows || formed.cols() != rows)
      throw Error("internal: SystemSolver::formAgainWith formed a matrix of another size");
    a.swap(formed);
    a.makeCompressed();
  }

  /// Frees r and z (the residual cache is invalid already).
  void releaseRefinementState() {
    r = Eigen::MatrixXd();
    z = Eigen::MatrixXd();
  }

  /// A float cycle diverges when it takes the relative residual from above kDivergenceFloor to
  /// more than kDivergenceGrowth times it, or to NaN: float rounding amplified by a nearly
  /// singular A (a unit square stretched 3000:1 with screening 1e-7 grows by about 1e4 a
  /// cycle). Below the floor, residuals near double rounding may rise and fall harmlessly.
  static constexpr double kDivergenceGrowth = 2.0;
  static constexpr double kDivergenceFloor = 1e-10;
  static bool divergesFrom(double before, double after) {
    return before > kDivergenceFloor && !(after <= kDivergenceGrowth * before);
  }

  /// Replaces the float cycles by double cycles on the current A, for good.
  void useDoubleCycles() {
    multigridDouble = std::make_unique<MultigridSolver<double>>(settings.multigrid);
    multigridDouble->setHierarchy(multigridFloat->hierarchy());
    multigridDouble->initAndUpdate(a);
    multigridFloat.reset();
    settings.singlePrecision = false;
  }

  /// initialResidual, or with refinesOnLevelZero() r = b - A x for x rounded to float first (in
  /// place: the caller's guess loses its last ~6e-8 relative, far below what a few cycles reach):
  /// one product of the level-0 operator instead of residualOf's two.
  double startingResidual(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
    if (!refinesOnLevelZero()) return initialResidual(b, x);
    x = x.cast<float>().cast<double>();
    r = b;
    return subtractOperatorProduct(x, r);
  }

  /// r = b - A x and ||r||^2; reuses the residual left by the previous solve when x is the
  /// iterate that solve returned (interactive refinement): then r = r_prev + (b - b_prev).
  double initialResidual(const Eigen::MatrixXd& b, const Eigen::MatrixXd& x) {
    if (cacheValid && lastX.rows() == x.rows() && lastX.cols() == x.cols() &&
        lastB.cols() == b.cols() && sameValues(lastX, x))
      return shiftResidual(r, lastB, b);
    return residualOf(b, x, r);
  }

  /// out = b - A x and ||out||^2, with the kept A or else the multigrid's level-0 operator (x
  /// rounded to the cycle precision, split into a high and a low part: residualOfDoubleIterate).
  double residualOf(const Eigen::MatrixXd& b, const Eigen::MatrixXd& x, Eigen::MatrixXd& out) {
    if (keepsMatrix()) return residual(a, b, x, out);
    return visitMultigrid([&](const auto& solver) {
      typename std::decay_t<decltype(solver)>::Matrix p, ap;
      const auto apply = [&](const auto& in, auto& y) { solver.applyOperator(in, y); };
      residualOfDoubleIterate(apply, b, x, out, p, ap);
      return out.squaredNorm();
    });
  }

  /// residualBlock -= A correction and its squared norm, with the multigrid's level-0 operator;
  /// the correction must hold float values (a float cycle's, or a rounded guess), so one product
  /// takes it exactly, where a double iterate needs two (residualOf). The product is rounded to
  /// float (applyOperator), so each update is off by ~6e-8 of |A correction|: summed over a
  /// solve, ~1e-7 of |b|, the accuracy these residuals reach.
  double subtractOperatorProduct(const Eigen::MatrixXd& correction,
                                 Eigen::MatrixXd& residualBlock) const {
    return visitMultigrid([&](const auto& solver) {
      using Matrix = typename std::decay_t<decltype(solver)>::Matrix;
      const Matrix zs = correction.cast<typename Matrix::Scalar>();
      Matrix az;
      solver.applyOperator(zs, az);
      residualBlock -= az.template cast<double>();
      return residualBlock.squaredNorm();
    });
  }

  /// Keeps x, b (r is already b - A x) for initialResidual.
  void remember(const Eigen::MatrixXd& b, const Eigen::MatrixXd& x) {
    lastX = x;
    lastB = b;
    cacheValid = true;
  }

  /// ||b - A x|| / ||b|| (||A x|| if b = 0), on the solver's threads; A x by the multigrid's
  /// level-0 operator when A is not kept.
  double relativeResidual(const Eigen::MatrixXd& b, const Eigen::MatrixXd& x) {
    double rr = 0.0;
    Eigen::MatrixXd scratch;  // not r: that holds the residual step() may reuse
    arena.execute([&] { rr = residualOf(b, x, scratch); });
    const double norm = b.norm();
    return norm > 0 ? std::sqrt(rr) / norm : std::sqrt(rr);
  }

  SolveReport directSolve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                          const ProgressCallback& progress) {
    const auto start = std::chrono::steady_clock::now();
    SolveReport report;
    report.residuals.push_back(relativeResidual(b, x));
    reportSolveProgress(progress, report, 1, 0.0);
    const Eigen::MatrixXd previous = x;
    x = direct.solve(b);
    report.iterations = 1;
    report.converged = true;
    report.residuals.push_back(relativeResidual(b, x));
    report.rmsChange.push_back((x - previous).norm() /
                               std::sqrt(static_cast<double>(std::max<Eigen::Index>(1, x.size()))));
    report.times.other = secondsSince(start);
    reportSolveProgress(progress, report, 1, 0.0, true);
    return report;
  }

  SolveReport run(const Eigen::MatrixXd& b, Eigen::MatrixXd& x, int count,
                  const ProgressCallback& progress) {
    if (x.rows() != b.rows() || x.cols() != b.cols()) x = Eigen::MatrixXd::Zero(b.rows(), b.cols());
    switch (settings.kind) {
      case SolverKind::Direct:
        return directSolve(b, x, progress);
      case SolverKind::Multigrid: {
        if (multigridFloat) return refinedCycles(b, x, count, progress);
        SolveControl control;
        control.maxCycles = count;
        control.tolerance = settings.tolerance;
        return cycles(*multigridDouble, b, x, control, progress);
      }
      case SolverKind::MultigridCg: {
        CgOptions options;
        options.maxIterations = count;
        options.tolerance = settings.effectiveTolerance();
        return visitMultigrid([&](auto& solver) {
          if (settings.cgUsesLevelZeroOperator())
            return conjugateGradient(multigridOperator(solver), b, x, options, progress);
          return conjugateGradient(a, b, x, multigridPreconditioner(solver), options, progress);
        });
      }
    }
    return {};
  }
};

SystemSolver::SystemSolver(const TexelGrid& grid, const SolverSettings& settings, MatrixCopy copy)
    : impl_(std::make_unique<Impl>(grid, settings, copy)) {}
SystemSolver::~SystemSolver() = default;
SystemSolver::SystemSolver(SystemSolver&&) noexcept = default;
SystemSolver& SystemSolver::operator=(SystemSolver&&) noexcept = default;

void SystemSolver::init(const Eigen::SparseMatrix<double>& pattern) {
  const auto start = std::chrono::steady_clock::now();
  if (impl_->settings.kind == SolverKind::Direct)
    impl_->direct.analyzePattern(pattern);
  else
    impl_->visitMultigrid([&](auto& solver) {
      // The multigrid set-up reads compressed matrices only (SparseSum); update() compresses too.
      if (pattern.isCompressed()) {
        solver.analyzePattern(pattern);
      } else {
        Eigen::SparseMatrix<double> compressed = pattern;
        compressed.makeCompressed();
        solver.analyzePattern(compressed);
      }
      return 0;
    });
  impl_->initTime = impl_->initSecondsSince(start);
}

void SystemSolver::update(const Eigen::SparseMatrix<double>& a, const ProgressCallback& progress) {
  Eigen::SparseMatrix<double> copy = a;
  update(std::move(copy), progress);
}

void SystemSolver::initAndUpdate(const Eigen::SparseMatrix<double>& a,
                                 const ProgressCallback& progress) {
  Eigen::SparseMatrix<double> copy = a;
  initAndUpdate(std::move(copy), progress);
}

void SystemSolver::update(Eigen::SparseMatrix<double>&& a, const ProgressCallback& progress) {
  reportProgress(progress, kSetupStage, 0.0);
  const auto start = std::chrono::steady_clock::now();
  // Swaps, as Eigen 3.4's SparseMatrix assignment would copy even from std::move.
  impl_->adoptMatrix(a, [&](Eigen::SparseMatrix<double>& adopted) {
    if (impl_->settings.kind == SolverKind::Direct)
      impl_->direct.factorize(adopted);
    else
      impl_->setUpMultigrid(adopted, [](auto& solver, auto&& matrix) {
        solver.update(std::forward<decltype(matrix)>(matrix));
      });
  });
  impl_->updateTime = secondsSince(start);
  reportProgress(progress, kSetupStage, 1.0);
}

void SystemSolver::initAndUpdate(Eigen::SparseMatrix<double>&& a,
                                 const ProgressCallback& progress) {
  if (impl_->settings.kind == SolverKind::Direct) {
    reportProgress(progress, kSetupStage, 0.0);
    init(a);
    update(std::move(a), progress);
    return;
  }
  reportProgress(progress, kSetupStage, 0.0);
  const auto start = std::chrono::steady_clock::now();
  impl_->adoptMatrix(a, [&](Eigen::SparseMatrix<double>& adopted) {
    impl_->setUpMultigrid(adopted, [&](auto& solver, auto&& matrix) {
      solver.initAndUpdate(std::forward<decltype(matrix)>(matrix));
    });
  });
  impl_->initTime = impl_->initSecondsSince(start);
  impl_->updateTime = 0.0;
  reportProgress(progress, kSetupStage, 1.0);
}

bool SystemSolver::takesFloatSystem() const {
  return impl_->multigridFloat != nullptr && !impl_->keepsMatrix();
}

bool SystemSolver::takesFloatSystem(const SolverSettings& settings, MatrixCopy copy) {
  const bool floatCycles = settings.kind != SolverKind::Direct && settings.singlePrecision;
  return floatCycles && !Impl::keepsMatrixFor(settings, copy, floatCycles);
}

void SystemSolver::initAndUpdate(FloatSystem&& a, const ProgressCallback& progress) {
  if (!takesFloatSystem()) {
    initAndUpdate(formedInDouble(std::move(a)), progress);
    return;
  }
  impl_->setUpFloatSystem(a, true, progress);
}

void SystemSolver::update(FloatSystem&& a, const ProgressCallback& progress) {
  if (!takesFloatSystem()) {
    update(formedInDouble(std::move(a)), progress);
    return;
  }
  impl_->setUpFloatSystem(a, false, progress);
}

void SystemSolver::initAndUpdate(const SparseSum& a, const ProgressCallback& progress) {
  if (impl_->keepsMatrix()) {  // every Direct solver does
    initAndUpdate(a.toMatrix(), progress);
    return;
  }
  reportProgress(progress, kSetupStage, 0.0);
  const auto start = std::chrono::steady_clock::now();
  impl_->adoptView(a, [](auto& solver, const SparseSum& view) { solver.initAndUpdate(view); });
  impl_->initTime = impl_->initSecondsSince(start);
  impl_->updateTime = 0.0;
  reportProgress(progress, kSetupStage, 1.0);
}

void SystemSolver::update(const SparseSum& a, const ProgressCallback& progress) {
  if (impl_->keepsMatrix()) {
    update(a.toMatrix(), progress);
    return;
  }
  reportProgress(progress, kSetupStage, 0.0);
  const auto start = std::chrono::steady_clock::now();
  impl_->adoptView(a, [](auto& solver, const SparseSum& view) { solver.update(view); });
  impl_->updateTime = secondsSince(start);
  reportProgress(progress, kSetupStage, 1.0);
}

SolveReport SystemSolver::solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                                const ProgressCallback& progress) {
  const SolverSettings& s = impl_->settings;
  const int count = s.kind == SolverKind::MultigridCg ? s.maxIterations : s.cycles;
  return impl_->run(b, x, count, progress);
}

SolveReport SystemSolver::solve(Eigen::MatrixXf b, Eigen::MatrixXf& x,
                                const ProgressCallback& progress) {
  if (!floatIterates()) {
    const Eigen::MatrixXd bd = b.cast<double>();
    b.resize(0, 0);
    Eigen::MatrixXd xd = x.cast<double>();
    try {
      const SolveReport report = solve(bd, xd, progress);
      x = xd.cast<float>();
      return report;
    } catch (...) {  // a cancel: x holds the iterate, as the double solve's does
      x = xd.cast<float>();
      throw;
    }
  }
  if (x.rows() != b.rows() || x.cols() != b.cols()) x = Eigen::MatrixXf::Zero(b.rows(), b.cols());
  CgOptions options;
  options.maxIterations = impl_->settings.maxIterations;
  options.tolerance = impl_->settings.effectiveTolerance();
  return conjugateGradient(multigridOperator<float, float>(*impl_->multigridFloat), std::move(b),
                           x, options, progress);
}

bool SystemSolver::floatIterates() const {
  // Then CG runs on the level-0 operator too (cgUsesLevelZeroOperator), whose float products
  // reach kFloatOperatorTolerance.
  static_assert(kFloatIterateTolerance >= SolverSettings::kFloatOperatorTolerance);
  const SolverSettings& s = impl_->settings;
  return s.kind == SolverKind::MultigridCg && impl_->multigridFloat &&
         s.effectiveTolerance() >= kFloatIterateTolerance;
}

SolveReport SystemSolver::step(const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                               const ProgressCallback& progress) {
  return impl_->run(b, x, 1, progress);
}

SolveReport SystemSolver::refine(const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                                 bool measureResidual) {
  Impl& m = *impl_;
  if (!m.multigridFloat || m.settings.kind != SolverKind::Multigrid) return step(b, x);
  if (x.rows() != b.rows() || x.cols() != b.cols()) x = Eigen::MatrixXd::Zero(b.rows(), b.cols());
  const auto start = std::chrono::steady_clock::now();
  SolveReport report;
  m.arena.execute([&] {
    const double residual = m.multigridFloat->refine(b, x, measureResidual);
    if (measureResidual) report.residuals.push_back(residual);
  });
  report.iterations = 1;
  report.converged = m.settings.tolerance > 0 && !report.residuals.empty() &&
                     report.residuals.back() <= m.settings.tolerance;
  report.times.other = secondsSince(start);
  return report;
}

double SystemSolver::relativeResidual(const Eigen::MatrixXd& b, const Eigen::MatrixXd& x) const {
  if (b.rows() != impl_->rows || x.rows() != b.rows() || x.cols() != b.cols())
    throw InvalidInputError("SystemSolver::relativeResidual: b and x must both be " +
                            std::to_string(impl_->rows) + " x k");
  return impl_->relativeResidual(b, x);
}

void SystemSolver::formAgainWith(std::function<Eigen::SparseMatrix<double>()> form) {
  impl_->formAgain = std::move(form);
}

const Eigen::SparseMatrix<double>& SystemSolver::matrix() const {
  if (!impl_->keepsMatrix())
    throw Error(
        "SystemSolver::matrix: this solver keeps no copy of A (CG or the refinement applies the "
        "multigrid's level-0 operator); construct it with MatrixCopy::Kept");
  return impl_->a;
}

int64_t SystemSolver::storageBytes() const {
  const Impl& m = *impl_;
  const auto denseBytes = [](const Eigen::MatrixXd& v) {
    return static_cast<int64_t>(v.size()) * int64_t(sizeof(double));
  };
  int64_t bytes = static_cast<int64_t>(m.a.nonZeros()) * int64_t(sizeof(double) + sizeof(int)) +
                  (m.a.outerSize() > 0 ? m.a.outerSize() + 1 : 0) * int64_t(sizeof(int)) +
                  denseBytes(m.r) + denseBytes(m.z) + denseBytes(m.lastX) + denseBytes(m.lastB);
  if (m.settings.kind == SolverKind::Direct) return bytes + m.direct.storageBytes();
  return bytes + m.visitMultigrid([](const auto& solver) { return solver.storageBytes(); });
}

std::string SystemSolver::summary() const {
  if (impl_->settings.kind == SolverKind::Direct)
    return "direct solver (CHOLMOD), " + std::to_string(impl_->unknowns) + " unknowns";
  return impl_->visitMultigrid([](auto& solver) { return solver.summary(); });
}

double SystemSolver::initSeconds() const {
  return impl_->initTime;
}
double SystemSolver::updateSeconds() const {
  return impl_->updateTime;
}
const SolverSettings& SystemSolver::settings() const {
  return impl_->settings;
}

}  // namespace texgrad
