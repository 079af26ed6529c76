// Solver module: the texel-grid multigrid V-cycle of paper §6.2 (Fig. 8) over per-chart grids,
// with CHOLMOD for boundary blocks and the coarsest level.
#include "texgrad/solver/multigrid_solver.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>

#include "solver/grid_kernels.h"
#include "solver/line_relaxation.h"
#include "texgrad/core/error.h"
#include "texgrad/core/storage_bytes.h"
#include "texgrad/solver/galerkin.h"

namespace texgrad {
namespace detail {

std::vector<BoxRow> boxRowsOf(const GridLevel& level) {
  std::vector<BoxRow> rows;
  for (size_t b = 0; b < level.boxes.size(); ++b)
    for (int r = 0; r < level.boxes[b].height; ++r)
      rows.push_back({static_cast<int>(b), level.boxes[b].y0 + r});
  return rows;
}

}  // namespace detail

namespace {

/// A number as an error message quotes it: %g (0.5, 1e-08), not std::to_string's six decimals.
std::string formatNumber(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

/// Adds 1e-12 * max|diag| to every diagonal entry of a coarse Galerkin operator. P^T A P is
/// singular when prolongation columns are dependent (tiny or thin charts: several coarse nodes
/// whose only child is the same fine texel), and so are its boundary blocks; every null vector v
/// has P v = 0, so the shift changes no coarse correction, while CHOLMOD can factorise.
void shiftDiagonal(Eigen::SparseMatrix<double>& a) {
  double largest = 0.0;
  for (int k = 0; k < a.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, k); it; ++it)
      if (it.row() == k) largest = std::max(largest, std::abs(it.value()));
  const double shift = 1e-12 * largest;
  for (int k = 0; k < a.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, k); it; ++it)
      if (it.row() == k) it.valueRef() += shift;
}

/// Bytes of a compressed sparse matrix's arrays (values, row indices, column starts).
int64_t sparseBytes(const Eigen::SparseMatrix<double>& a) {
  return static_cast<int64_t>(a.nonZeros()) * int64_t(sizeof(double) + sizeof(int)) +
         (a.outerSize() > 0 ? a.outerSize() + 1 : 0) * int64_t(sizeof(int));
}

/// Lets the system drop the pages of the entries of a matrix about to be freed: a block freed
/// inside the heap stays resident until it is reused (reuseFreedMemory), and a coarse A^l, the
/// largest block a set-up frees (A^1: 28 bytes per texel at spot 4096²), would otherwise sit
/// resident through the solves.
void dropEntryPages(Eigen::SparseMatrix<double>& a) {
  const auto entries = static_cast<size_t>(a.nonZeros());
  detail::discardWholePages(a.valuePtr(), entries * sizeof(double));
  detail::discardWholePages(a.innerIndexPtr(), entries * sizeof(int));
}

/// A^0 handed over to a set-up (initAndUpdate or update on an rvalue), as a double matrix or a
/// FloatSystem: the walk owns it, drops its pages as level 0's stencils read it and frees it
/// once level 0 is set up.
struct HandedOver {
  Eigen::SparseMatrix<double>* matrix = nullptr;
  FloatSystem* compact = nullptr;
  explicit operator bool() const { return matrix != nullptr || compact != nullptr; }
  /// Bytes of A^0's arrays.
  int64_t bytes() const {
    return matrix ? sparseBytes(*matrix) : compact ? compact->storageBytes() : 0;
  }
  /// A^0's row sums per unknown if it carries them (a FloatSystem), else empty.
  std::span<const float> rowSums() const {
    return compact ? compact->rowSums() : std::span<const float>();
  }
  /// Frees A^0.
  void free() {
    if (matrix) Eigen::SparseMatrix<double>().swap(*matrix);
    if (compact) *compact = FloatSystem();
  }
};

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Sum of squares of v[0, n), with a split that does not depend on the thread count.
template <typename T>
double sumOfSquares(const T* v, size_t n) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<size_t>(0, n, 1 << 16), 0.0,
      [&](const tbb::blocked_range<size_t>& r, double acc) {
        // Four partial sums: one would chain every addition behind the previous one.
        std::array<double, 4> part{};
        size_t i = r.begin();
        for (; i + 4 <= r.end(); i += 4)
          for (size_t k = 0; k < 4; ++k) part[k] += double(v[i + k]) * double(v[i + k]);
        for (; i != r.end(); ++i) part[0] += double(v[i]) * double(v[i]);
        return acc + ((part[0] + part[1]) + (part[2] + part[3]));
      },
      [](double a, double b) { return a + b; });
}

/// -(A x) on the interior slots of one colour run of one channel plane (0 on masked slots), in
/// difference form with double accumulation: sum_k w_k (x_k - x_s) + rowSum_s x_s. The
/// coefficients' float rounding then perturbs only the differences, never the small row sum (the
/// screening term), and no large terms cancel in float: A x to double-like accuracy for smooth x.
template <typename T>
void negatedProductRun(int64_t n, const detail::RunStencil<T>& w, const T* rowSum, const T* up,
                       const T* mid, const T* down, T* y) {
  auto term = [&](int k, int64_t i, T neighbour, double centre) {
    return double(w.w[k][i]) * (double(neighbour) - centre);
  };
  for (int64_t i = 0; i < n; ++i) {
    const int64_t j = 2 * i;
    const double c = mid[j];
    const double value = ((term(0, i, up[j - 1], c) + term(1, i, up[j], c)) +
                          (term(2, i, up[j + 1], c) + term(3, i, mid[j - 1], c))) +
                         ((term(5, i, mid[j + 1], c) + term(6, i, down[j - 1], c)) +
                          (term(7, i, down[j], c) + term(8, i, down[j + 1], c))) +
                         double(rowSum[j]) * c;
    y[j] = w.inverse[i] == T(0) ? T(0) : static_cast<T>(-value);
  }
}

/// r = -(A x) on the interior slots of every run (0 on their other slots), negatedProductRun
/// on each colour and channel plane.
template <typename T>
void negatedInteriorProduct(const detail::LevelSystem& sys, const T* stencil, const T* rowSums,
                            const T* x, T* r, int k) {
  const int64_t plane = sys.slotCount();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, sys.boxRows.size(), detail::kRowGrain),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i) {
                        const detail::SlotRow& row = sys.boxRows[i];
                        for (int q = 0; q < 2; ++q) {
                          const int64_t n = row.runLength(q);
                          if (n <= 0) continue;
                          const auto w = detail::runStencil(stencil, sys.boxRows[i - 1], row, q);
                          for (int c = 0; c < k; ++c) {
                            const int64_t s0 = c * plane + row.begin + q;
                            negatedProductRun<T>(n, w, rowSums + row.begin + q, x + s0 - row.width,
                                                 x + s0, x + s0 + row.width, r + s0);
                          }
                        }
                      }
                    });
}

}  // namespace

void MultigridOptions::validate() const {
  if (levels < 0 || levels > kMaxLevels)
    throw InvalidInputError("multigrid levels is " + std::to_string(levels) + "; expected 0 to " +
                            std::to_string(kMaxLevels) + " (paper default 4)");
  if (sweeps < 1 || sweeps > kMaxSweeps)
    throw InvalidInputError("multigrid sweeps is " + std::to_string(sweeps) + "; expected 1 to " +
                            std::to_string(kMaxSweeps) + " (paper default 3)");
  if (minCoarseUnknowns < 1)
    throw InvalidInputError("multigrid minCoarseUnknowns is " + std::to_string(minCoarseUnknowns) +
                            "; expected >= 1");
  if (!(lineRatio == 0.0 || lineRatio >= kMinLineRatio) || !std::isfinite(lineRatio))
    throw InvalidInputError("multigrid lineRatio is " + formatNumber(lineRatio) +
                            "; expected 0 (off) or a number >= " + formatNumber(kMinLineRatio));
  if (weakRowReach < 0 || weakRowReach > kMaxWeakRowReach)
    throw InvalidInputError("multigrid weakRowReach is " + std::to_string(weakRowReach) +
                            "; expected 0 (off) to " + std::to_string(kMaxWeakRowReach));
  if (threads < 0 || threads > kMaxThreads)
    throw InvalidInputError("multigrid threads is " + std::to_string(threads) +
                            "; expected 0 (all cores) to " + std::to_string(kMaxThreads));
}

void SolveControl::validate() const {
  if (maxCycles < 0)
    throw InvalidInputError("maxCycles is " + std::to_string(maxCycles) + "; expected >= 0");
  if (!(tolerance >= 0.0)) throw InvalidInputError("tolerance must be >= 0 (0 runs all cycles)");
}

template <typename Scalar>
struct MultigridSolver<Scalar>::Impl {
  using T = Scalar;
  struct Level {
    detail::LevelSystem sys;
    PageArray<T> stencil;  ///< interior stencils (assignStencils)
    std::vector<T> x, b, r;
    detail::LineSet lines;      ///< anisotropic interior slots relaxed by lines
    std::vector<T> lineCoeffs;  ///< their coefficients (detail::kLinePlanes per slot)
    std::vector<detail::BoxRow> boxRows;
    Eigen::MatrixXd work;
  };

  MultigridOptions options;
  GridHierarchy hierarchy;
  std::vector<Level> levels;
  std::vector<int64_t> nonZeros;         // per level, of A^l
  std::vector<int64_t> heldMatrixBytes;  // per level (MultigridLevelInfo::setUpMatrixBytes)
  PageArray<T> rowSums;  // per slot of level 0: sum of A^0's row (applyOperator, A^1's set-up)
  CholmodSolver coarseSolver;
  Eigen::MatrixXd coarseWork;
  MultigridStats stats;
  PhaseTimes times;
  int channels = 0;
  bool initialised = false, updated = false;
  tbb::task_arena arena;

  explicit Impl(const MultigridOptions& o)
      : options(o), arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic) {}

  int coarsest() const { return hierarchy.levelCount() - 1; }

  void refreshCounters() {
    stats.symbolicAnalyses = coarseSolver.stats().analyses;
    stats.numericFactorizations = coarseSolver.stats().factorizations;
    for (const Level& lv : levels) {
      stats.symbolicAnalyses += lv.sys.boundarySolver.stats().analyses;
      stats.numericFactorizations += lv.sys.boundarySolver.stats().factorizations;
    }
  }

  /// Walks the levels once: A^0 = a0, then A^{l+1} = Pᵀ A^l P (diagonal-shifted for l > 0).
  /// `symbolicPhase` builds the split and the CHOLMOD analyses from the patterns (Galerkin
  /// products never drop an entry, so the values do not change any pattern);
  /// `numericPhase` fills stencils and boundary data and factorises. Both at once cost one
  /// chain of Galerkin products instead of two. For l > 0, A^{l+1} is formed before level l's
  /// data are filled in, so the product's temporaries never coexist with them, and A^l is freed
  /// once both exist. Level 0 goes the other way in the numeric phase: its data are filled in
  /// from A^0, its row sums band by band with its stencils; if A^0 was handed over
  /// (`handedOver`: the matrix a0 views, owned by the walk), its pages are dropped meanwhile,
  /// then its boundary block is factorised (from the boundary rows, as every level's) and A^0
  /// freed; then A^1 is formed from level 0's data (galerkinFromLevel), so A^0 coexists with
  /// neither A^1 nor a factorisation (docs/memory.md).
  /// The symbolic phase alone has no level-0 data and forms A^1 from A^0's pattern: the same
  /// pattern (galerkinFromLevel).
  void walkLevels(const SparseSum& a0, bool symbolicPhase, bool numericPhase,
                  HandedOver handedOver = {}) {
    // Only a set-up reads unknownOfSlot: rebuilt for it, freed after (8 B/t at spot 4096²),
    // also when the set-up throws.
    struct ReleasedAfter {
      GridHierarchy& hierarchy;
      ~ReleasedAfter() { hierarchy.releaseUnknownOfSlot(); }
    } released{hierarchy};
    hierarchy.restoreUnknownOfSlot();
    walkLevelsWithUnknownOfSlot(a0, symbolicPhase, numericPhase, handedOver);
  }

  /// walkLevels, with every level's unknownOfSlot there.
  void walkLevelsWithUnknownOfSlot(const SparseSum& a0, bool symbolicPhase, bool numericPhase,
                                   HandedOver handedOver) {
    if (symbolicPhase) {
      levels.clear();
      levels.resize(static_cast<size_t>(hierarchy.levelCount()));
      nonZeros.assign(levels.size(), 0);
      heldMatrixBytes.assign(levels.size(), 0);
      coarseSolver = CholmodSolver();
      rowSums = PageArray<T>();
    }
    Eigen::SparseMatrix<double> coarse;  // A^l for l > 0
    SparseSum a = a0;                    // A^l
    for (int l = 0; l <= coarsest(); ++l) {
      const size_t sl = static_cast<size_t>(l);
      const GridLevel& grid = hierarchy.level(l);
      Level& lv = levels[sl];
      heldMatrixBytes[sl] = 0;
      if (symbolicPhase) {
        lv.boxRows = detail::boxRowsOf(grid);
        nonZeros[sl] = a.nonZeros();
      } else if (a.nonZeros() != nonZeros[sl] || a.rows() != grid.unknownCount()) {
        throw InvalidInputError(
            "MultigridSolver::update: level " + std::to_string(l) + " matrix has " +
            std::to_string(a.nonZeros()) + " non-zeros, the pattern given to init has " +
            std::to_string(nonZeros[sl]) + "; call init again when the sparsity changes");
      }
      if (l > 0 && numericPhase) shiftDiagonal(coarse);
      const bool fromLevelData = l == 0 && numericPhase && l < coarsest();
      // Initialised, never assigned: Eigen 3.4's SparseMatrix has no move assignment, so
      // `x = product` would copy it.
      Eigen::SparseMatrix<double> next = l < coarsest() && !fromLevelData
                                             ? galerkinProduct(a, grid, hierarchy.level(l + 1))
                                             : Eigen::SparseMatrix<double>();
      // Levels split into interior stencils and a boundary block: all but a coarsest level
      // above level 0, which is solved directly.
      const bool split = l < coarsest() || l == 0;
      // A handed-over A^0's pages are released (assignStencils) before level 0's boundary block
      // is factorised, so that CHOLMOD's copy and its factor's work (15-20 bytes per texel)
      // never sit beside it; any other block is factorised before the level's stencils exist.
      const bool factoriseLast = l == 0 && handedOver;
      if (split) {
        // Weak rows pull in their neighbours on the texel grid only: there they come from
        // texels their chart barely covers; coarse Galerkin rows of boundary nodes are often
        // weak without such a cause, and locking their neighbours slowed small atlases (cube
        // sphere at 96 x 64: mass drift of a reaction-diffusion step 1.4e-5 against 3.9e-6).
        if (symbolicPhase)
          detail::classifyLevel(grid, a, l == 0 ? options.weakRowReach : 0, lv.sys);
        if (numericPhase) {
          detail::assignBoundary(grid, a, lv.sys,
                                 l == 0 ? handedOver.rowSums() : std::span<const float>());
          if (!factoriseLast) detail::factoriseBoundary(grid, lv.sys);
          detail::assignLines<T>(grid, a, lv.sys, options.lineRatio, lv.lines, lv.lineCoeffs);
        }
        if (numericPhase) {
          // Level 0's row sums come band by band with its stencils, before the band's columns
          // of a handed-over A^0 are released: on pages of their own then, they become
          // resident as A^0 stops being.
          const bool release = fromLevelData && handedOver;
          std::function<void(int)> consumed;
          if (l == 0)
            consumed =
                rowSummer(grid, a, handedOver.rowSums(), release ? releaser(handedOver) : nullptr);
          detail::assignStencils<T>(grid, a, lv.sys, lv.stencil, release, consumed);
        }
      }
      if (l == coarsest()) {
        // A one-level hierarchy is solved directly: only then is A^0 formed (unless handed over).
        // A FloatSystem's diagonals come from its row sums, as its boundary rows' do.
        const Eigen::SparseMatrix<double> formed =
            l == 0 && !handedOver.matrix
                ? (handedOver.compact ? formedMatrix(*handedOver.compact) : a0.toMatrix())
                : Eigen::SparseMatrix<double>();
        const Eigen::SparseMatrix<double>& direct =
            l > 0 ? coarse : (handedOver.matrix ? *handedOver.matrix : formed);
        if (symbolicPhase) coarseSolver.analyzePattern(direct);
        if (numericPhase) coarseSolver.factorize(direct);
        heldMatrixBytes[sl] = sparseBytes(formed);
      }
      // The matrices held with level l's data: A^l (A^0 only if handed over) and A^{l+1}; at
      // level 0 from its data, a handed-over A^0 and then A^1, never both.
      const int64_t handedBytes = l == 0 ? handedOver.bytes() : 0;
      // Before A^0 is freed, though its pages are gone: CHOLMOD's blocks then do not settle in
      // the hole it leaves, which the next matrix formed (reaction-diffusion's second species)
      // fills whole.
      if (numericPhase && split && factoriseLast) detail::factoriseBoundary(grid, lv.sys);
      if (l == 0) handedOver.free();  // A^0
      if (fromLevelData) {
        Eigen::SparseMatrix<double> formed = detail::galerkinFromLevel(
            grid, lv.sys, std::span<const T>(lv.stencil.data(), lv.stencil.size()),
            std::span<const T>(rowSums.data(), rowSums.size()), hierarchy.level(l + 1));
        next.swap(formed);
      }
      heldMatrixBytes[sl] +=
          sparseBytes(coarse) + (fromLevelData ? std::max(handedBytes, sparseBytes(next))
                                               : handedBytes + sparseBytes(next));
      if (l < coarsest()) {
        coarse.swap(next);  // next now holds A^l, freed at the end of this iteration
        a = SparseSum(coarse);
        dropEntryPages(next);
      }
    }
  }

  /// For assignStencils at level 0: releases the pages of a handed-over A^0's entries in the
  /// columns the stencils have read (its last reader), so that A^0 shrinks as level 0's
  /// stencils grow instead of both being whole at once (docs/memory.md). The matrix is freed
  /// after, never read again: released pages only stop being resident.
  static std::function<void(int)> releaser(HandedOver a) {
    // Each time from the arrays' start: a page across the previous end goes too (pages that
    // are gone already cost the kernel nothing).
    return [a](int u) {
      if (a.compact) {
        a.compact->discardColumnsBefore(u);
        return;
      }
      const auto end = static_cast<size_t>(a.matrix->outerIndexPtr()[u]);
      detail::discardWholePages(a.matrix->valuePtr(), end * sizeof(double));
      detail::discardWholePages(a.matrix->innerIndexPtr(), end * sizeof(int));
    };
  }

  /// For assignStencils at level 0: a callback that, given u, sums the rows before u not summed
  /// yet (sumRows; or takes their sums from `given`, per unknown, if not empty), then passes u
  /// on to `then` if given. rowSums is allocated first (zeros), on pages of its own if `then`
  /// releases A^0. Only interior rows' sums are used (the difference form of the interior
  /// rows), and every interior row lies in a band.
  std::function<void(int)> rowSummer(const GridLevel& grid, const SparseSum& a,
                                     std::span<const float> given, std::function<void(int)> then) {
    if (rowSums.size() != static_cast<size_t>(grid.slotCount))
      rowSums = PageArray<T>::zeros(static_cast<size_t>(grid.slotCount), static_cast<bool>(then));
    return [this, &grid, &a, given, then = std::move(then), done = 0](int end) mutable {
      if (end > done) {
        sumRows(grid, a, given, done, end);
        done = end;
      }
      if (then) then(end);
    };
  }

  /// rowSums at unknowns [begin, end) of level 0 (columns of the symmetric A: its rows), or
  /// their `given` sums if not empty.
  void sumRows(const GridLevel& grid, const SparseSum& a, std::span<const float> given, int begin,
               int end) {
    tbb::parallel_for(
        tbb::blocked_range<int>(begin, end, 4096), [&](const tbb::blocked_range<int>& range) {
          for (int u = range.begin(); u != range.end(); ++u) {
            double sum = 0.0;
            if (!given.empty())
              sum = given[static_cast<size_t>(u)];
            else
              for (int e = a.outer()[u]; e < a.outer()[u + 1]; ++e) sum += a.value(e);
            rowSums.data()[grid.slotOfUnknown[static_cast<size_t>(u)]] = static_cast<T>(sum);
          }
        });
  }

  /// Throws InvalidInputError naming `caller` unless a hierarchy was built or set.
  void requireHierarchy(const char* caller) const {
    if (hierarchy.levelCount() == 0)
      throw InvalidInputError(std::string("MultigridSolver::") + caller +
                              ": no hierarchy; call init(grid, pattern) or buildHierarchy(grid) "
                              "first");
  }

  void buildHierarchy(const TexelGrid& grid) {
    const auto start = Clock::now();
    hierarchy = GridHierarchy::build(grid, options.levels, options.minCoarseUnknowns);
    stats.initSeconds += secondsSince(start);
  }

  void symbolic(const SparseSum& pattern, bool numericToo, HandedOver handedOver = {}) {
    const auto start = Clock::now();
    walkLevels(pattern, true, numericToo, handedOver);
    initialised = true;
    updated = numericToo;
    channels = 0;
    ++stats.inits;
    const double seconds = secondsSince(start);
    if (numericToo) {
      times = {};
      ++stats.updates;
    }
    stats.initSeconds += seconds;
    refreshCounters();
  }

  void numeric(const SparseSum& a0, HandedOver handedOver = {}) {
    if (!initialised) throw InvalidInputError("MultigridSolver::update called before init");
    const auto start = Clock::now();
    walkLevels(a0, false, true, handedOver);
    updated = true;
    times = {};
    ++stats.updates;
    stats.updateSeconds += secondsSince(start);
    refreshCounters();
  }

  void ensureChannels(int k) {
    if (!updated) throw InvalidInputError("MultigridSolver: cycle called before update");
    if (k == channels) return;
    for (int l = 0; l <= coarsest(); ++l) {
      Level& lv = levels[static_cast<size_t>(l)];
      const size_t n = static_cast<size_t>(hierarchy.level(l).slotCount) * static_cast<size_t>(k);
      lv.x.assign(n, T(0));
      lv.b.assign(n, T(0));
      lv.r.assign(n, T(0));
    }
    channels = k;
  }

  template <typename Src>
  void scatter(const Src& m, std::vector<T>& dst) {
    const GridLevel& g = hierarchy.level(0);
    const int64_t plane = g.slotCount;
    const int k = channels;
    tbb::parallel_for(tbb::blocked_range<int>(0, g.unknownCount(), 4096),
                      [&](const tbb::blocked_range<int>& range) {
                        for (int u = range.begin(); u != range.end(); ++u) {
                          T* slot = dst.data() + g.slotOfUnknown[static_cast<size_t>(u)];
                          for (int c = 0; c < k; ++c) slot[c * plane] = static_cast<T>(m(u, c));
                        }
                      });
  }

  template <typename Dst>
  void gather(const std::vector<T>& src, Dst& m) {
    const GridLevel& g = hierarchy.level(0);
    const int64_t plane = g.slotCount;
    const int k = channels;
    tbb::parallel_for(tbb::blocked_range<int>(0, g.unknownCount(), 4096),
                      [&](const tbb::blocked_range<int>& range) {
                        for (int u = range.begin(); u != range.end(); ++u) {
                          const T* slot = src.data() + g.slotOfUnknown[static_cast<size_t>(u)];
                          for (int c = 0; c < k; ++c)
                            m(u, c) = static_cast<typename Dst::Scalar>(slot[c * plane]);
                        }
                      });
  }

  /// Interior relaxation; with `residual`, also r = b - A x on interior slots (fused). Line
  /// relaxation comes before the point sweeps on the way down and after them on the way up, so
  /// the cycle stays symmetric.
  void relax(Level& lv, bool forward, bool residual = false) {
    const auto start = Clock::now();
    const bool lines = !lv.lines.empty();
    if (lines && forward)
      detail::relaxLines(lv.lines, lv.lineCoeffs.data(), lv.b.data(), lv.x.data(), channels,
                         lv.sys.slotCount(), true);
    detail::relaxInterior(lv.sys, lv.stencil.data(), lv.b.data(), lv.x.data(), channels,
                          options.sweeps, forward,
                          residual && (forward || !lines) ? lv.r.data() : nullptr);
    if (lines && !forward) {
      detail::relaxLines(lv.lines, lv.lineCoeffs.data(), lv.b.data(), lv.x.data(), channels,
                         lv.sys.slotCount(), false);
      if (residual)
        detail::interiorResidual(lv.sys, lv.stencil.data(), lv.b.data(), lv.x.data(), lv.r.data(),
                                 channels);
    }
    times.relaxation += secondsSince(start);
  }

  /// Boundary solve; with `residual`, keeps the interior residual of relax(.., true) current.
  void boundary(Level& lv, bool residual = false) {
    const auto start = Clock::now();
    detail::solveBoundary(lv.sys, lv.b.data(), lv.x.data(), channels, lv.work,
                          residual ? lv.r.data() : nullptr);
    times.boundary += secondsSince(start);
  }

  void coarseSolve() {
    const auto start = Clock::now();
    const GridLevel& g = hierarchy.level(coarsest());
    Level& lv = levels.back();
    const int k = channels;
    coarseWork.resize(g.unknownCount(), k);
    for (int c = 0; c < k; ++c)
      for (int u = 0; u < g.unknownCount(); ++u)
        coarseWork(u, c) = double(
            lv.b[static_cast<size_t>(c * g.slotCount + g.slotOfUnknown[static_cast<size_t>(u)])]);
    coarseSolver.solveInPlace(coarseWork);
    for (int c = 0; c < k; ++c)
      for (int u = 0; u < g.unknownCount(); ++u)
        lv.x[static_cast<size_t>(c * g.slotCount + g.slotOfUnknown[static_cast<size_t>(u)])] =
            static_cast<T>(coarseWork(u, c));
    times.coarse += secondsSince(start);
  }

  /// Fig. 8 on the slot vectors; level 0 holds b and the current x. With `withResidual`, level
  /// 0's r ends as b - A x for the new x (fused into the last relaxation).
  void vCycle(bool withResidual = false) {
    const int L = coarsest();
    for (int l = 0; l < L; ++l) {
      Level& lv = levels[static_cast<size_t>(l)];
      if (l > 0) std::fill(lv.x.begin(), lv.x.end(), T(0));
      relax(lv, true, true);  // R.2–R.3, and R.6 on interior slots
      boundary(lv, true);     // R.4–R.5, interior residual kept current
      const auto start = Clock::now();
      detail::clearBoundaryResidual(lv.sys, lv.r.data(), channels);  // R.6 on boundary slots
      detail::restrictResidual(hierarchy.level(l), hierarchy.level(l + 1),
                               levels[static_cast<size_t>(l) + 1].boxRows, lv.r.data(),
                               levels[static_cast<size_t>(l) + 1].b.data(), channels);
      times.transfer += secondsSince(start);
    }
    coarseSolve();  // C.1
    for (int l = L - 1; l >= 0; --l) {
      Level& lv = levels[static_cast<size_t>(l)];
      const auto start = Clock::now();
      detail::prolongCorrection(hierarchy.level(l), hierarchy.level(l + 1), lv.sys.kind.data(),
                                lv.boxRows, levels[static_cast<size_t>(l) + 1].x.data(),
                                lv.x.data(),
                                channels);  // P.2
      times.transfer += secondsSince(start);
      boundary(lv);                              // P.3–P.4
      relax(lv, false, withResidual && l == 0);  // P.5–P.6, mirrored colour order
    }
    if (withResidual) {  // interior rows came with the last sweeps (if level 0 was relaxed)
      Level& lv = levels.front();
      const auto start = Clock::now();
      if (L > 0)
        detail::boundaryResidual(lv.sys, lv.b.data(), lv.x.data(), lv.r.data(), channels, lv.work);
      else
        detail::levelResidual(lv.sys, lv.stencil.data(), lv.b.data(), lv.x.data(), lv.r.data(),
                              channels, lv.work);
      times.other += secondsSince(start);
    }
  }

  /// z = V(r): one V-cycle from zero on level 0's vectors, z in double or Scalar.
  template <typename Src, typename Dst>
  void preconditionTo(const Src& r, Dst& z) {
    z.resize(r.rows(), r.cols());
    arena.execute([&] {
      ensureChannels(static_cast<int>(r.cols()));
      scatter(r, levels.front().b);
      std::fill(levels.front().x.begin(), levels.front().x.end(), T(0));
      vCycle();
      gather(levels.front().x, z);
    });
  }

  /// ||b - A x||_F at level 0 (uses level 0's r as scratch).
  double residualNorm() {
    Level& lv = levels.front();
    detail::levelResidual(lv.sys, lv.stencil.data(), lv.b.data(), lv.x.data(), lv.r.data(),
                          channels, lv.work);
    return std::sqrt(sumOfSquares(lv.r.data(), lv.r.size()));
  }

  SolveReport solveSlots(const SolveControl& control, int unknowns,
                         const ProgressCallback& progress) {
    SolveReport report;
    const auto start = Clock::now();
    Level& lv = levels.front();
    const double bNorm = std::sqrt(sumOfSquares(lv.b.data(), lv.b.size()));
    const double scale = bNorm > 0.0 ? 1.0 / bNorm : 1.0;
    report.residuals.push_back(residualNorm() * scale);
    std::vector<T> previous;
    times.other += secondsSince(start);
    while (report.iterations < control.maxCycles &&
           !(control.tolerance > 0.0 && report.residuals.back() <= control.tolerance)) {
      reportSolveProgress(progress, report, control.maxCycles, control.tolerance);
      previous = lv.x;
      vCycle();
      const auto tail = Clock::now();
      const double change = tbb::parallel_deterministic_reduce(
          tbb::blocked_range<size_t>(0, previous.size(), 1 << 16), 0.0,
          [&](const tbb::blocked_range<size_t>& r, double acc) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
              const double d = double(lv.x[i]) - double(previous[i]);
              acc += d * d;
            }
            return acc;
          },
          [](double a, double b) { return a + b; });
      report.rmsChange.push_back(std::sqrt(change / std::max(1.0, double(unknowns) * channels)));
      report.residuals.push_back(residualNorm() * scale);
      ++report.iterations;
      times.other += secondsSince(tail);
    }
    report.converged = control.tolerance > 0.0 && report.residuals.back() <= control.tolerance;
    reportSolveProgress(progress, report, control.maxCycles, control.tolerance, true);
    return report;
  }
};

template <typename Scalar>
MultigridSolver<Scalar>::MultigridSolver(const MultigridOptions& options) {
  options.validate();
  impl_ = std::make_unique<Impl>(options);
}
template <typename Scalar>
MultigridSolver<Scalar>::~MultigridSolver() = default;
template <typename Scalar>
MultigridSolver<Scalar>::MultigridSolver(MultigridSolver&&) noexcept = default;
template <typename Scalar>
MultigridSolver<Scalar>& MultigridSolver<Scalar>::operator=(MultigridSolver&&) noexcept = default;

template <typename Scalar>
void MultigridSolver<Scalar>::init(const TexelGrid& grid, const SparseSum& pattern) {
  buildHierarchy(grid);
  impl_->arena.execute([&] { impl_->symbolic(pattern, false); });
}

template <typename Scalar>
void MultigridSolver<Scalar>::initAndUpdate(const TexelGrid& grid, const SparseSum& a) {
  buildHierarchy(grid);
  initAndUpdate(a);
}

template <typename Scalar>
void MultigridSolver<Scalar>::initAndUpdate(const TexelGrid& grid,
                                            Eigen::SparseMatrix<double>&& a) {
  buildHierarchy(grid);
  initAndUpdate(std::move(a));
}

template <typename Scalar>
void MultigridSolver<Scalar>::buildHierarchy(const TexelGrid& grid) {
  impl_->arena.execute([&] { impl_->buildHierarchy(grid); });
}

template <typename Scalar>
void MultigridSolver<Scalar>::setHierarchy(GridHierarchy hierarchy) {
  impl_->hierarchy = std::move(hierarchy);
}

template <typename Scalar>
void MultigridSolver<Scalar>::initAndUpdate(const SparseSum& a) {
  impl_->requireHierarchy("initAndUpdate");
  impl_->arena.execute([&] { impl_->symbolic(a, true); });
}

template <typename Scalar>
void MultigridSolver<Scalar>::initAndUpdate(Eigen::SparseMatrix<double>&& a) {
  impl_->requireHierarchy("initAndUpdate");
  Eigen::SparseMatrix<double> owned;  // swapped: Eigen 3.4's SparseMatrix cannot be moved
  owned.swap(a);
  const SparseSum view(owned);  // throws (a already empty) if `owned` is not compressed
  impl_->arena.execute([&] { impl_->symbolic(view, true, HandedOver{&owned, nullptr}); });
}

template <typename Scalar>
void MultigridSolver<Scalar>::initAndUpdate(FloatSystem&& a) {
  impl_->requireHierarchy("initAndUpdate");
  FloatSystem owned = std::move(a);
  const SparseSum view(owned);
  impl_->arena.execute([&] { impl_->symbolic(view, true, HandedOver{nullptr, &owned}); });
}

template <typename Scalar>
void MultigridSolver<Scalar>::update(const SparseSum& a) {
  impl_->arena.execute([&] { impl_->numeric(a); });
}

template <typename Scalar>
void MultigridSolver<Scalar>::update(Eigen::SparseMatrix<double>&& a) {
  Eigen::SparseMatrix<double> owned;
  owned.swap(a);
  const SparseSum view(owned);
  impl_->arena.execute([&] { impl_->numeric(view, HandedOver{&owned, nullptr}); });
}

template <typename Scalar>
void MultigridSolver<Scalar>::update(FloatSystem&& a) {
  FloatSystem owned = std::move(a);
  const SparseSum view(owned);
  impl_->arena.execute([&] { impl_->numeric(view, HandedOver{nullptr, &owned}); });
}

template <typename Scalar>
void MultigridSolver<Scalar>::cycle(const Matrix& b, Matrix& x) {
  const int n = impl_->hierarchy.levelCount() > 0 ? impl_->hierarchy.level(0).unknownCount() : 0;
  if (b.rows() != n || x.rows() != n || x.cols() != b.cols())
    throw InvalidInputError("MultigridSolver::cycle: b and x must both be " + std::to_string(n) +
                            " x k");
  impl_->arena.execute([&] {
    impl_->ensureChannels(static_cast<int>(b.cols()));
    const double before = impl_->times.total();
    const auto start = Clock::now();
    impl_->scatter(b, impl_->levels.front().b);
    impl_->scatter(x, impl_->levels.front().x);
    impl_->vCycle();
    impl_->gather(impl_->levels.front().x, x);
    impl_->times.other += secondsSince(start) - (impl_->times.total() - before);
  });
}

template <typename Scalar>
SolveReport MultigridSolver<Scalar>::solve(const Matrix& b, Matrix& x, const SolveControl& control,
                                           const ProgressCallback& progress) {
  control.validate();
  const int n = impl_->hierarchy.levelCount() > 0 ? impl_->hierarchy.level(0).unknownCount() : 0;
  if (b.rows() != n || x.rows() != n || x.cols() != b.cols())
    throw InvalidInputError("MultigridSolver::solve: b is " + std::to_string(b.rows()) + " x " +
                            std::to_string(b.cols()) + " and x is " + std::to_string(x.rows()) +
                            " x " + std::to_string(x.cols()) + "; expected " + std::to_string(n) +
                            " rows each and equal channel counts");
  SolveReport report;
  impl_->arena.execute([&] {
    impl_->ensureChannels(static_cast<int>(b.cols()));
    const PhaseTimes before = impl_->times;
    const auto start = Clock::now();
    impl_->scatter(b, impl_->levels.front().b);
    impl_->scatter(x, impl_->levels.front().x);
    impl_->times.other += secondsSince(start);
    report = impl_->solveSlots(control, n, progress);
    const auto tail = Clock::now();
    impl_->gather(impl_->levels.front().x, x);
    impl_->times.other += secondsSince(tail);
    const PhaseTimes& after = impl_->times;
    report.times.relaxation = after.relaxation - before.relaxation;
    report.times.boundary = after.boundary - before.boundary;
    report.times.coarse = after.coarse - before.coarse;
    report.times.transfer = after.transfer - before.transfer;
    report.times.other = after.other - before.other;
  });
  return report;
}

template <typename Scalar>
double MultigridSolver<Scalar>::refine(const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
                                       bool measureResidual) {
  const int n = impl_->hierarchy.levelCount() > 0 ? impl_->hierarchy.level(0).unknownCount() : 0;
  if (b.rows() != n || x.rows() != n || x.cols() != b.cols())
    throw InvalidInputError("MultigridSolver::refine: b and x must both be " + std::to_string(n) +
                            " x k");
  double relative = std::numeric_limits<double>::quiet_NaN();
  impl_->arena.execute([&] {
    Impl& m = *impl_;
    m.ensureChannels(static_cast<int>(b.cols()));
    const double before = m.times.total();
    const auto start = Clock::now();
    auto& level0 = m.levels.front();
    m.scatter(b, level0.b);
    m.scatter(x, level0.x);
    m.vCycle(measureResidual);
    m.gather(level0.x, x);
    if (measureResidual) {
      const double bNorm = std::sqrt(sumOfSquares(level0.b.data(), level0.b.size()));
      const double rNorm = std::sqrt(sumOfSquares(level0.r.data(), level0.r.size()));
      relative = bNorm > 0.0 ? rNorm / bNorm : 0.0;
    }
    m.times.other += secondsSince(start) - (m.times.total() - before);
  });
  return relative;
}

template <typename Scalar>
void MultigridSolver<Scalar>::precondition(const Eigen::MatrixXd& r, Eigen::MatrixXd& z) const {
  impl_->preconditionTo(r, z);
}

template <typename Scalar>
void MultigridSolver<Scalar>::preconditionInto(const Eigen::MatrixXd& r, Matrix& z) const {
  impl_->preconditionTo(r, z);
}

template <typename Scalar>
void MultigridSolver<Scalar>::preconditionInto(const Eigen::MatrixXf& r, Matrix& z) const {
  impl_->preconditionTo(r, z);
}

template <typename Scalar>
void MultigridSolver<Scalar>::applyOperator(const Matrix& x, Matrix& y) const {
  Impl& m = *impl_;
  const int n = m.hierarchy.levelCount() > 0 ? m.hierarchy.level(0).unknownCount() : 0;
  if (x.rows() != n)
    throw InvalidInputError("MultigridSolver::applyOperator: x has " + std::to_string(x.rows()) +
                            " rows; expected " + std::to_string(n));
  y.resize(x.rows(), x.cols());
  m.arena.execute([&] {
    m.ensureChannels(static_cast<int>(x.cols()));
    auto& lv = m.levels.front();
    const int64_t plane = lv.sys.slotCount();
    m.scatter(x, lv.x);
    negatedInteriorProduct(lv.sys, lv.stencil.data(), m.rowSums.data(), lv.x.data(), lv.r.data(),
                           m.channels);
    // Boundary rows in double: r = b - A x with b = 0 there.
    for (int c = 0; c < m.channels; ++c)
      for (const int64_t s : lv.sys.boundarySlots) lv.b[static_cast<size_t>(c * plane + s)] = 0;
    detail::boundaryResidual(lv.sys, lv.b.data(), lv.x.data(), lv.r.data(), m.channels, lv.work);
    m.gather(lv.r, y);
    y = -y;
  });
}

template <typename Scalar>
MultigridSolver<Scalar>& MultigridSolver<Scalar>::analyzePattern(
    const Eigen::SparseMatrix<double>& a) {
  impl_->requireHierarchy("analyzePattern");
  impl_->arena.execute([&] { impl_->symbolic(a, false); });
  return *this;
}

template <typename Scalar>
MultigridSolver<Scalar>& MultigridSolver<Scalar>::factorize(const Eigen::SparseMatrix<double>& a) {
  update(a);
  return *this;
}

template <typename Scalar>
MultigridSolver<Scalar>& MultigridSolver<Scalar>::compute(const Eigen::SparseMatrix<double>& a) {
  update(a);
  return *this;
}

template <typename Scalar>
Eigen::VectorXd MultigridSolver<Scalar>::solve(const Eigen::VectorXd& r) const {
  Eigen::MatrixXd z;
  precondition(r, z);
  return z.col(0);
}

template <typename Scalar>
Eigen::ComputationInfo MultigridSolver<Scalar>::info() const {
  return impl_->updated ? Eigen::Success : Eigen::InvalidInput;
}

template <typename Scalar>
const GridHierarchy& MultigridSolver<Scalar>::hierarchy() const {
  return impl_->hierarchy;
}
template <typename Scalar>
const MultigridStats& MultigridSolver<Scalar>::stats() const {
  return impl_->stats;
}
template <typename Scalar>
const PhaseTimes& MultigridSolver<Scalar>::cycleTimes() const {
  return impl_->times;
}
template <typename Scalar>
const MultigridOptions& MultigridSolver<Scalar>::options() const {
  return impl_->options;
}

template <typename Scalar>
std::vector<MultigridLevelInfo> MultigridSolver<Scalar>::levelInfo() const {
  const Impl& m = *impl_;
  std::vector<MultigridLevelInfo> info;
  for (int l = 0; l < static_cast<int>(m.levels.size()); ++l) {
    const auto& lv = m.levels[static_cast<size_t>(l)];
    MultigridLevelInfo i;
    i.unknowns = m.hierarchy.level(l).unknownCount();
    i.direct = l == m.coarsest();
    const bool directOnly = i.direct && l > 0;  // level 0 keeps its split even when alone
    i.interior = directOnly ? 0 : lv.sys.interiorCount();
    i.boundary = directOnly ? i.unknowns : lv.sys.boundaryCount();
    i.lineTexels = lv.lines.slotCount;
    i.nonZeros = m.nonZeros[static_cast<size_t>(l)];
    i.boundaryNonZeros = directOnly ? i.nonZeros : lv.sys.boundaryNonZeros;
    i.factorNonZeros = i.direct ? m.coarseSolver.stats().factorNonZeros
                                : lv.sys.boundarySolver.stats().factorNonZeros;
    i.slots = m.hierarchy.level(l).slotCount;
    i.setUpMatrixBytes = m.heldMatrixBytes[static_cast<size_t>(l)];
    info.push_back(i);
  }
  return info;
}

template <typename Scalar>
int64_t MultigridSolver<Scalar>::storageBytes() const {
  const Impl& m = *impl_;
  int64_t bytes = m.hierarchy.storageBytes() + m.coarseSolver.storageBytes() +
                  static_cast<int64_t>(m.rowSums.bytes()) +
                  static_cast<int64_t>(m.coarseWork.size()) * int64_t(sizeof(double));
  for (const auto& lv : m.levels) {
    bytes += lv.sys.storageBytes() + static_cast<int64_t>(lv.stencil.bytes()) +
             capacityBytes(lv.x, lv.b, lv.r, lv.lineCoeffs) + capacityBytes(lv.boxRows) +
             static_cast<int64_t>(lv.work.size()) * int64_t(sizeof(double));
    for (const auto& byParity : lv.lines.lines)
      for (const auto& lines : byParity) bytes += capacityBytes(lines);
  }
  return bytes;
}

template <typename Scalar>
std::string MultigridSolver<Scalar>::summary() const {
  const Impl& m = *impl_;
  std::ostringstream os;
  os << "multigrid (" << (sizeof(Scalar) == 4 ? "float" : "double")
     << "): " << m.hierarchy.levelCount() << " levels, " << m.options.sweeps << " sweeps, "
     << m.hierarchy.chartCount() << " charts\n";
  os << "level  unknowns  interior  boundary     lines   nnz(A)  nnz(A_bb)  nnz(L_bb)   slots\n";
  const std::vector<MultigridLevelInfo> info = levelInfo();
  for (size_t l = 0; l < info.size(); ++l) {
    const MultigridLevelInfo& i = info[l];
    os << std::setw(5) << l << std::setw(10) << i.unknowns;
    if (i.direct && l > 0)
      os << std::setw(10) << "-" << std::setw(10) << "direct" << std::setw(10) << "-";
    else
      os << std::setw(10) << i.interior << std::setw(10) << i.boundary << std::setw(10)
         << i.lineTexels;
    os << std::setw(9) << i.nonZeros << std::setw(11) << i.boundaryNonZeros << std::setw(11)
       << i.factorNonZeros << std::setw(8) << i.slots << "\n";
  }
  return os.str();
}

template <typename Scalar>
std::ostream& operator<<(std::ostream& os, const MultigridSolver<Scalar>& solver) {
  return os << solver.summary();
}

template class MultigridSolver<float>;
template class MultigridSolver<double>;
template std::ostream& operator<<(std::ostream&, const MultigridSolver<float>&);
template std::ostream& operator<<(std::ostream&, const MultigridSolver<double>&);

}  // namespace texgrad
