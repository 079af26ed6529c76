// Solver module (private): line Gauss–Seidel on strongly anisotropic interior texels.
#include "solver/line_relaxation.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <type_traits>
#include <utility>

#include "solver/level_system.h"

namespace texgrad::detail {
namespace {

/// Stencil indices off a line along x (axis 0) or y (axis 1), then the previous and next slot.
constexpr std::array<std::array<int, 8>, 2> kStencilOfPlane = {{
    {0, 1, 2, 6, 7, 8, 3, 5},  // x: rows above and below; west, east
    {0, 3, 6, 2, 5, 8, 1, 7},  // y: columns left and right; south, north
}};

/// Slot offsets of the 6 off-line neighbours, in the order of kStencilOfPlane.
std::array<int64_t, 6> offLineOffsets(const SlotLine& line) {
  const int64_t w = line.width;
  if (line.stride == 1) return {-w - 1, -w, -w + 1, w - 1, w, w + 1};
  return {-w - 1, -1, w - 1, -w + 1, 1, w + 1};
}

/// Per-slot roles for collecting lines.
enum SlotRole : uint8_t {
  kOff = 0,      ///< not on a line
  kAlongX = 1,   ///< interior, strongly coupled along x
  kAlongY = 2,   ///< interior, strongly coupled along y
  kLineEnd = 3,  ///< boundary slot whose row is a 3 x 3 stencil: may join a line
};

/// A line needs its strong coupling to carry at least this fraction of the diagonal (0.75 for
/// an isotropic stiffness stencil, up to 1.5 for a stretched one): where the mass term
/// dominates (heat steps, large screening) point Gauss–Seidel already smooths well.
constexpr double kStrongShare = 0.5;

/// Axis along which the stencil w couples more than `ratio` times as strongly as across it:
/// kAlongX, kAlongY or kOff (neither). The coupling along an axis is the stencil's second moment
/// -sum_k w_k d_k^2 over the neighbour offsets d_k on that axis, twice the diffusion coefficient
/// the stencil discretises (for bilinear elements the axis neighbours alone mislead: their
/// weight turns positive across a stretch of more than 2).
uint8_t strongAxis(const std::array<double, 9>& w, double ratio) {
  const double corners = w[0] + w[2] + w[6] + w[8];
  const double alongX = -(w[3] + w[5] + corners), alongY = -(w[1] + w[7] + corners);
  if (alongX > kStrongShare * w[4] && alongX > ratio * std::max(alongY, 0.0)) return kAlongX;
  if (alongY > kStrongShare * w[4] && alongY > ratio * std::max(alongX, 0.0)) return kAlongY;
  return kOff;
}

/// Appends the lines along one lattice line of `count` slots from `first` with step `stride`:
/// maximal runs of slots with role `role` or kLineEnd that hold a `role` slot and at least two
/// slots. A line that reaches the chart boundary thus takes in the boundary texels it couples to
/// strongly; solving those apart (boundary solve, line locked) would leave the error that is
/// smooth along the whole row.
void collectRuns(const std::vector<uint8_t>& roles, uint8_t role, int64_t first, int count,
                 int32_t stride, int32_t width, std::vector<SlotLine>& out) {
  int start = -1;
  bool hasRole = false;
  for (int i = 0; i <= count; ++i) {
    const uint8_t r =
        i < count ? roles[static_cast<size_t>(first + i * int64_t{stride})] : uint8_t{kOff};
    if (r == role || r == kLineEnd) {
      if (start < 0) start = i;
      hasRole = hasRole || r == role;
      continue;
    }
    if (start >= 0 && hasRole && i - start >= 2)
      out.push_back({first + start * int64_t{stride}, i - start, stride, width, 0});
    start = -1;
    hasRole = false;
  }
}

/// A Thomas pivot below this fraction of its diagonal entry ends a line of T: the block is then
/// nearly singular (coarse rows of dependent prolongation columns, positive definite only
/// through shiftDiagonal), and solving it in T would blow rounding up (pivot / diagonal times
/// T's epsilon is the relative error of the line's solve). Double lines keep blocks float ones
/// cut: a square stretched ~30000:1 with screening 1e-9 cuts the last texel of every line at
/// 2.5e-7, and double cycles with that cut stalled at a residual of 6e-9 instead of 1e-12.
template <typename T>
constexpr double kSmallPivot = std::is_same_v<T, float> ? 1e-6 : 1e-12;

/// One step of the Thomas recurrence along a line of `axis`: the pivot of the row with stencil
/// w, given c'_{i-1} of the row before it on the line (`first`: w starts the line). The
/// returned pair is (pivot, c'_i = w_next / pivot).
std::pair<double, double> thomasStep(const std::array<double, 9>& w, int axis,
                                     double previousFactor, bool first) {
  const auto& planes = kStencilOfPlane[static_cast<size_t>(axis)];
  const double pivot = w[4] - (first ? 0.0 : w[static_cast<size_t>(planes[6])] * previousFactor);
  return {pivot, w[static_cast<size_t>(planes[7])] / pivot};
}

/// Appends `run` to `out`, cut before every slot whose Thomas pivot would be small, keeping the
/// pieces of at least two slots.
void appendSplitAtSmallPivots(const GridLevel& level, const SparseSum& a, int axis,
                              double smallPivot, const SlotLine& run, std::vector<SlotLine>& out) {
  int begin = 0;
  auto emit = [&](int end) {
    if (end - begin >= 2)
      out.push_back(
          {run.first + begin * int64_t{run.stride}, end - begin, run.stride, run.width, 0});
  };
  double previousFactor = 0.0;
  for (int i = 0; i < run.count; ++i) {
    const int64_t s = run.first + i * int64_t{run.stride};
    const std::array<double, 9> w =
        stencilRow(level, a, level.unknownOfSlot[static_cast<size_t>(s)]);
    auto [pivot, factor] = thomasStep(w, axis, previousFactor, i == begin);
    if (i > begin && pivot < smallPivot * w[4]) {
      emit(i);
      begin = i;
      factor = thomasStep(w, axis, 0.0, true).second;
    }
    previousFactor = factor;
  }
  emit(run.count);
}

/// Thomas factorisation of one line's tridiagonal block and its off-line weights (double).
template <typename T>
void fillLine(const GridLevel& level, const SparseSum& a, int axis, const SlotLine& line,
              T* coeffs) {
  const auto& planes = kStencilOfPlane[static_cast<size_t>(axis)];
  double previousFactor = 0.0;  // c'_{i-1}
  for (int i = 0; i < line.count; ++i) {
    const int64_t s = line.first + i * int64_t{line.stride};
    const std::array<double, 9> w =
        stencilRow(level, a, level.unknownOfSlot[static_cast<size_t>(s)]);
    T* c = coeffs + static_cast<int64_t>(i) * kLinePlanes;
    for (int p = 0; p < 8; ++p) c[p] = static_cast<T>(w[static_cast<size_t>(planes[p])]);
    const auto [pivot, factor] = thomasStep(w, axis, previousFactor, i == 0);
    previousFactor = factor;
    c[8] = static_cast<T>(factor);
    c[9] = static_cast<T>(1.0 / pivot);
  }
}

/// Solves one line's block with its neighbours locked, on one channel plane, in place: the
/// forward elimination leaves d_i in x, the back substitution x_i = d_i - c'_i x_{i+1}.
template <typename T>
void solveLine(const SlotLine& line, const T* c, const T* b, T* x) {
  const std::array<int64_t, 6> o = offLineOffsets(line);
  const int64_t st = line.stride;
  const int n = line.count;
  for (int i = 0; i < n; ++i) {
    const int64_t s = line.first + i * st;
    const T* ci = c + static_cast<int64_t>(i) * kLinePlanes;
    T r = b[s] - (((ci[0] * x[s + o[0]] + ci[1] * x[s + o[1]]) +
                   (ci[2] * x[s + o[2]] + ci[3] * x[s + o[3]])) +
                  (ci[4] * x[s + o[4]] + ci[5] * x[s + o[5]]));
    r -= ci[6] * x[s - st];                  // the locked slot before the line, then d_{i-1}
    if (i == n - 1) r -= ci[7] * x[s + st];  // the locked slot after the line
    x[s] = r * ci[9];
  }
  for (int i = n - 2; i >= 0; --i) {
    const int64_t s = line.first + i * st;
    x[s] -= c[static_cast<int64_t>(i) * kLinePlanes + 8] * x[s + st];
  }
}

}  // namespace

template <typename T>
void assignLines(const GridLevel& level, const SparseSum& a, const LevelSystem& system,
                 double ratio, LineSet& set, std::vector<T>& coeffs) {
  set = LineSet{};
  coeffs.clear();
  if (ratio <= 0.0 || system.interiorCount() == 0) return;
  std::vector<uint8_t> roles(static_cast<size_t>(level.slotCount), kOff);
  tbb::parallel_for(0, level.unknownCount(), [&](int u) {
    if (system.boundaryIndex.contains(u)) return;
    roles[static_cast<size_t>(level.slotOfUnknown[static_cast<size_t>(u)])] =
        strongAxis(stencilRow(level, a, u), ratio);
  });
  tbb::parallel_for(size_t(0), system.boundarySlots.size(), [&](size_t j) {
    const int64_t s = system.boundarySlots[j];
    if (rowIsStencil(level, a, level.unknownOfSlot[static_cast<size_t>(s)]))
      roles[static_cast<size_t>(s)] = kLineEnd;
  });
  std::array<std::array<std::vector<SlotLine>, 2>, 2> runs;  // by axis and parity, as lines
  for (const GridBox& box : level.boxes) {
    for (int r = 0; r < box.height; ++r)
      collectRuns(roles, kAlongX, box.offset + static_cast<int64_t>(r) * box.width, box.width, 1,
                  box.width, runs[0][static_cast<size_t>((box.y0 + r) & 1)]);
    for (int col = 0; col < box.width; ++col)
      collectRuns(roles, kAlongY, box.offset + col, box.height, box.width, box.width,
                  runs[1][static_cast<size_t>((box.x0 + col) & 1)]);
  }
  for (size_t ax = 0; ax < 2; ++ax)
    for (size_t parity = 0; parity < 2; ++parity)
      for (const SlotLine& run : runs[ax][parity])
        appendSplitAtSmallPivots(level, a, static_cast<int>(ax), kSmallPivot<T>, run,
                                 set.lines[ax][parity]);
  for (auto& byParity : set.lines)
    for (std::vector<SlotLine>& group : byParity)
      for (SlotLine& line : group) {
        line.coeffs = set.slotCount * kLinePlanes;
        set.slotCount += line.count;
      }
  coeffs.resize(static_cast<size_t>(set.slotCount * kLinePlanes));
  for (int ax = 0; ax < 2; ++ax)
    for (const std::vector<SlotLine>& group : set.lines[static_cast<size_t>(ax)])
      tbb::parallel_for(size_t(0), group.size(), [&](size_t i) {
        fillLine<T>(level, a, ax, group[i], coeffs.data() + group[i].coeffs);
      });
}

template <typename T>
void relaxLines(const LineSet& set, const T* coeffs, const T* b, T* x, int k, int64_t plane,
                bool forward) {
  for (int step = 0; step < 4; ++step) {
    const int g = forward ? step : 3 - step;  // axis g / 2, parity g % 2
    const std::vector<SlotLine>& group =
        set.lines[static_cast<size_t>(g / 2)][static_cast<size_t>(g % 2)];
    tbb::parallel_for(tbb::blocked_range<size_t>(0, group.size(), 16),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t i = range.begin(); i != range.end(); ++i)
                          for (int c = 0; c < k; ++c)
                            solveLine<T>(group[i], coeffs + group[i].coeffs, b + c * plane,
                                         x + c * plane);
                      });
  }
}

template void assignLines<float>(const GridLevel&, const SparseSum&, const LevelSystem&, double,
                                 LineSet&, std::vector<float>&);
template void assignLines<double>(const GridLevel&, const SparseSum&, const LevelSystem&, double,
                                  LineSet&, std::vector<double>&);
template void relaxLines<float>(const LineSet&, const float*, const float*, float*, int, int64_t,
                                bool);
template void relaxLines<double>(const LineSet&, const double*, const double*, double*, int,
                                 int64_t, bool);

}  // namespace texgrad::detail
