// Solver module (private): allocation-free kernels of the V-cycle on slot-layout vectors (paper
// §6.2): multi-colour Gauss–Seidel on 9-point stencils, residuals, boundary solves, bilinear
// transfers. Vectors hold k channel planes of one value per slot: value (slot, c) is at
// c * slotCount + slot, so a channel's rows are contiguous whatever the channel count.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <algorithm>
#include <vector>

#include "solver/level_system.h"

namespace texgrad::detail {

/// The hot row kernels are compiled three times, for x86-64-v4 (AVX-512: 16 floats per vector),
/// x86-64-v3 (AVX2 + FMA: 8) and the baseline, and the loader picks the best one the CPU runs
/// (GCC/Clang function multiversioning; ifunc: needs glibc; off under AddressSanitizer, whose
/// build tests the baseline path).
#if defined(__x86_64__) && defined(__GLIBC__) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(__SANITIZE_ADDRESS__)
#define TEXGRAD_SIMD_CLONES \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define TEXGRAD_SIMD_CLONES
#endif

/// Rows per TBB task in grid loops (a row is a few hundred to a few thousand slots).
constexpr size_t kRowGrain = 4;

/// Sum of the 8 off-centre stencil terms w_k x_k at slot 2i of a colour run (fixed association
/// order, so every channel count and thread count rounds alike). up / mid / down point at the
/// run's first slot in the rows y - 1, y, y + 1 of one channel plane; wk[i] is weight k (index
/// (dy + 1) * 3 + (dx + 1)) of run slot i. Always inlined: GCC 12 leaves the calling loop scalar
/// when it inlines this late (measured: relaxation twice as slow).
template <typename T>
[[gnu::always_inline]] inline T offCentreSum(int64_t i, const T* w0, const T* w1, const T* w2,
                                             const T* w3, const T* w5, const T* w6, const T* w7,
                                             const T* w8, const T* up, const T* mid,
                                             const T* down) {
  const int64_t j = 2 * i;
  return ((w0[i] * up[j - 1] + w1[i] * up[j]) + (w2[i] * up[j + 1] + w3[i] * mid[j - 1])) +
         ((w5[i] * mid[j + 1] + w6[i] * down[j - 1]) + (w7[i] * down[j] + w8[i] * down[j + 1]));
}

/// Gauss–Seidel on n slots of a colour run of one channel plane:
/// x_s = (b_s - sum_{k != centre} w_k x_k) / w_centre where the mask (inverse) is non-zero. `mid`
/// and `x` alias the same row but touch disjoint slots (x the colour being relaxed, mid its
/// neighbours of the other colour). Every pointer is a parameter of its own, restrict-qualified,
/// so that the loop vectorises without run-time alias checks.
template <typename T>
[[gnu::always_inline]] inline void relaxSlots(
    int64_t n, const T* __restrict w0, const T* __restrict w1, const T* __restrict w2,
    const T* __restrict w3, const T* __restrict w5, const T* __restrict w6, const T* __restrict w7,
    const T* __restrict w8, const T* __restrict inverse, const T* __restrict b,
    const T* __restrict up, const T* __restrict mid, const T* __restrict down, T* __restrict x) {
  for (int64_t i = 0; i < n; ++i) {
    const int64_t j = 2 * i;
    const T sum = offCentreSum(i, w0, w1, w2, w3, w5, w6, w7, w8, up, mid, down);
    const T value = inverse[i] * (b[j] - sum);
    const T old = x[j];
    x[j] = value + (inverse[i] == T(0) ? old : T(0));  // select by addition: vectorises
  }
}

/// relaxSlots on a run whose weights `w` gives.
template <typename T>
TEXGRAD_SIMD_CLONES void relaxRun(int64_t n, const RunStencil<T>& w, const T* b, const T* up,
                                  const T* mid, const T* down, T* x) {
  relaxSlots(n, w.w[0], w.w[1], w.w[2], w.w[3], w.w[5], w.w[6], w.w[7], w.w[8], w.inverse, b, up,
             mid, down, x);
}

/// r = b - A x on n slots of a colour run of one channel plane, 0 where the mask is 0.
template <typename T>
[[gnu::always_inline]] inline void residualSlots(int64_t n, const T* __restrict w0,
                                                 const T* __restrict w1, const T* __restrict w2,
                                                 const T* __restrict w3, const T* __restrict w4,
                                                 const T* __restrict w5, const T* __restrict w6,
                                                 const T* __restrict w7, const T* __restrict w8,
                                                 const T* __restrict inverse, const T* __restrict b,
                                                 const T* __restrict up, const T* __restrict mid,
                                                 const T* __restrict down, T* __restrict r) {
  for (int64_t i = 0; i < n; ++i) {
    const int64_t j = 2 * i;
    const T sum = offCentreSum(i, w0, w1, w2, w3, w5, w6, w7, w8, up, mid, down);
    const T value = b[j] - (sum + w4[i] * mid[j]);
    r[j] = inverse[i] == T(0) ? T(0) : value;
  }
}

/// residualSlots on a run whose weights `w` gives.
template <typename T>
TEXGRAD_SIMD_CLONES void residualRun(int64_t n, const RunStencil<T>& w, const T* b, const T* up,
                                     const T* mid, const T* down, T* r) {
  residualSlots(n, w.w[0], w.w[1], w.w[2], w.w[3], w.w[4], w.w[5], w.w[6], w.w[7], w.w[8],
                w.inverse, b, up, mid, down, r);
}

/// relaxRun on the slots of colour q of box row i, for each of the k channel planes (channel c
/// of slot s at c * slotCount + s); the run's stencils stay in cache across channels.
template <typename T>
void relaxRowColour(const LevelSystem& sys, int64_t i, int q, const T* stencil, const T* b, T* x,
                    int k) {
  const SlotRow& row = sys.boxRows[static_cast<size_t>(i)];
  const int64_t n = row.runLength(q);
  if (n <= 0) return;
  const RunStencil<T> w = runStencil(stencil, sys.boxRows[static_cast<size_t>(i) - 1], row, q);
  const int64_t width = row.width, plane = sys.slotCount();
  for (int c = 0; c < k; ++c) {
    const int64_t s0 = c * plane + row.begin + q;
    relaxRun<T>(n, w, b + s0, x + s0 - width, x + s0, x + s0 + width, x + s0);
  }
}

/// r = b - A x on both colours of box row i, every channel plane; 0 on masked slots.
template <typename T>
void residualRow(const LevelSystem& sys, int64_t i, const T* stencil, const T* b, const T* x, T* r,
                 int k) {
  const SlotRow& row = sys.boxRows[static_cast<size_t>(i)];
  const int64_t plane = sys.slotCount();
  for (int q = 0; q < 2; ++q) {
    const int64_t n = row.runLength(q);
    if (n <= 0) continue;
    const RunStencil<T> w = runStencil(stencil, sys.boxRows[static_cast<size_t>(i) - 1], row, q);
    for (int c = 0; c < k; ++c) {
      const int64_t s0 = c * plane + row.begin + q;
      residualRun<T>(n, w, b + s0, x + s0 - row.width, x + s0, x + s0 + row.width, r + s0);
    }
  }
}

/// Relaxes box row i at half-sweep h (sweep h / 2, phase h % 2) if the row has that phase's y
/// parity: colours (y, x) parity 00, 01, 10, 11 forward, the reverse backward.
template <typename T>
void relaxNode(const LevelSystem& sys, int64_t i, int h, bool forward, const T* stencil, const T* b,
               T* x, int k) {
  const SlotRow& row = sys.boxRows[static_cast<size_t>(i)];
  if (row.begin == row.end || row.yParity() != (forward ? (h & 1) : 1 - (h & 1))) return;
  for (int p = 0; p < 2; ++p)
    relaxRowColour<T>(sys, i, ((forward ? p : 1 - p) ^ row.xParity) & 1, stencil, b, x, k);
}

/// The half-sweeps [0, halves) of a band that need no row of a neighbouring band: row i at
/// half-sweep h reads rows i +- 1 at h - 1, so a cut side loses one row per half-sweep
/// (a trapezoid). Rows advance as a wavefront, so the band's stencils are read once.
/// With r, also the residual of every row whose neighbours are final within the trapezoid
/// (row i once the wavefront has passed row i + 1), while its stencils are still in cache.
template <typename T>
void relaxBandInterior(const LevelSystem& sys, const RowBand& band, int halves, bool forward,
                       const T* stencil, const T* b, T* x, T* r, int k) {
  const int64_t lo = band.first + (band.cutBelow ? halves : 0);
  const int64_t hi = band.end - (band.cutAbove ? halves : 0);
  for (int64_t step = band.first; step < band.end + halves; ++step) {
    for (int h = 0; h < halves; ++h) {
      const int64_t i = step - h;
      if (i < band.first + (band.cutBelow ? h : 0) || i >= band.end - (band.cutAbove ? h : 0))
        continue;
      relaxNode<T>(sys, i, h, forward, stencil, b, x, k);
    }
    const int64_t ready = step - halves;
    if (r && ready >= lo && ready < hi) residualRow<T>(sys, ready, stencil, b, x, r, k);
  }
}

/// The rest of the half-sweeps around the cut between two bands at box row m: rows
/// [m - h, m + h) at half-sweep h, after both neighbouring trapezoids.
/// With r, also the residual of rows [m - halves, m + halves), which the trapezoids left out.
template <typename T>
void relaxBandSeam(const LevelSystem& sys, int64_t m, int halves, bool forward, const T* stencil,
                   const T* b, T* x, T* r, int k) {
  for (int h = 1; h < halves; ++h)
    for (int64_t i = m - h; i < m + h; ++i) relaxNode<T>(sys, i, h, forward, stencil, b, x, k);
  if (r)
    for (int64_t i = m - halves; i < m + halves; ++i) residualRow<T>(sys, i, stencil, b, x, r, k);
}

/// `sweeps` symmetric-ordered Gauss–Seidel sweeps over all interior slots with boundary values
/// locked (Fig. 8 R.2–R.3 fused), cache-blocked: bands run their trapezoids in parallel, then
/// the seams between bands. Every row update sees the same neighbour values as in plain
/// sweep-by-sweep order, so the result equals it bit for bit for any thread count. With r
/// (not null), r = b - A x on the interior slots of every run afterwards, as interiorResidual.
/// Slot vectors hold k channel planes of sys.slotCount() slots each.
template <typename T>
void relaxInterior(const LevelSystem& sys, const T* stencil, const T* b, T* x, int k, int sweeps,
                   bool forward, T* r = nullptr) {
  constexpr int kMaxSweepsPerPass = static_cast<int>((kBandRows - 2) / 4);
  for (int done = 0; done < sweeps; done += kMaxSweepsPerPass) {
    const int halves = 2 * std::min(kMaxSweepsPerPass, sweeps - done);
    T* residual = done + kMaxSweepsPerPass >= sweeps ? r : nullptr;  // last pass only
    tbb::parallel_for(size_t(0), sys.bands.size(), [&](size_t i) {
      relaxBandInterior<T>(sys, sys.bands[i], halves, forward, stencil, b, x, residual, k);
    });
    tbb::parallel_for(size_t(0), sys.bands.size(), [&](size_t i) {
      if (sys.bands[i].cutBelow)
        relaxBandSeam<T>(sys, sys.bands[i].first, halves, forward, stencil, b, x, residual, k);
    });
  }
}

/// r = b - A x on interior slots and r = 0 on the other slots of interior rows.
template <typename T>
void interiorResidual(const LevelSystem& sys, const T* stencil, const T* b, const T* x, T* r,
                      int k) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, sys.boxRows.size(), kRowGrain),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i)
                        residualRow<T>(sys, static_cast<int64_t>(i), stencil, b, x, r, k);
                    });
}

/// Which entries of the boundary rows a residual subtracts.
enum class BoundaryColumns { OffBlock, All };

/// Accumulates, per boundary row j and channel c, out(j, c) = b - (A_bi x_i) or b - (A x) for
/// columns OffBlock or All.
template <typename T>
void boundaryRowsResidual(const LevelSystem& sys, BoundaryColumns columns, const T* b, const T* x,
                          int k, Eigen::MatrixXd& out) {
  const int64_t plane = sys.slotCount();
  const SlotCsr& csr = sys.boundaryRows;
  out.resize(sys.boundaryCount(), k);
  tbb::parallel_for(tbb::blocked_range<int>(0, sys.boundaryCount(), 256),
                    [&](const tbb::blocked_range<int>& range) {
                      for (int j = range.begin(); j != range.end(); ++j) {
                        const size_t sj = static_cast<size_t>(j);
                        const int64_t s = sys.boundarySlots[sj];
                        const int64_t e0 = csr.ptr[sj], e1 = columns == BoundaryColumns::All
                                                                 ? csr.ptr[sj + 1]
                                                                 : sys.offBlockEnd[sj];
                        for (int c = 0; c < k; ++c) {
                          const T* xc = x + c * plane;
                          double acc = static_cast<double>(b[c * plane + s]);
                          for (int64_t e = e0; e < e1; ++e)
                            acc -= csr.val[static_cast<size_t>(e)] *
                                   static_cast<double>(xc[csr.col[static_cast<size_t>(e)]]);
                          out(j, c) = acc;
                        }
                      }
                    });
}

/// Boundary direct solve with interior locked (Fig. 8 R.4–R.5 / P.3–P.4), in double precision.
/// With r (not null) holding b - A x on interior slots, r is kept equal to it for the new
/// boundary values: r_s -= A_sj (x_j new - x_j old) on interior slots next to boundary slots.
template <typename T>
void solveBoundary(const LevelSystem& sys, const T* b, T* x, int k, Eigen::MatrixXd& work,
                   T* r = nullptr) {
  if (sys.boundaryCount() == 0) return;
  const int64_t plane = sys.slotCount();
  boundaryRowsResidual(sys, BoundaryColumns::OffBlock, b, x, k, work);
  sys.boundarySolver.solveInPlace(work);
  tbb::parallel_for(tbb::blocked_range<int>(0, sys.boundaryCount(), 4096),
                    [&](const tbb::blocked_range<int>& range) {
                      for (int c = 0; c < k; ++c)
                        for (int j = range.begin(); j != range.end(); ++j) {
                          T& xj = x[c * plane + sys.boundarySlots[static_cast<size_t>(j)]];
                          const T updated = static_cast<T>(work(j, c));
                          work(j, c) = static_cast<double>(updated) - static_cast<double>(xj);
                          xj = updated;
                        }
                    });
  if (!r) return;
  const SlotCsr& fix = sys.interiorNextToBoundary;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, sys.fixupSlots.size(), 1024),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i)
                        for (int c = 0; c < k; ++c) {
                          double acc = 0.0;
                          for (int64_t e = fix.ptr[i]; e < fix.ptr[i + 1]; ++e)
                            acc += fix.val[static_cast<size_t>(e)] *
                                   work(fix.col[static_cast<size_t>(e)], c);
                          r[c * plane + sys.fixupSlots[i]] -= static_cast<T>(acc);
                        }
                    });
}

/// r = 0 on boundary slots: right after the boundary solve (Fig. 8 R.5) the boundary rows
/// A_bi x_i + A_bb x_b = b_b hold up to rounding, so R.6 needs no pass over them.
template <typename T>
void clearBoundaryResidual(const LevelSystem& sys, T* r, int k) {
  for (int c = 0; c < k; ++c)
    for (const int64_t s : sys.boundarySlots) r[c * sys.slotCount() + s] = T(0);
}

/// r = b - A x on boundary slots (Fig. 8 R.6, before R^l).
template <typename T>
void boundaryResidual(const LevelSystem& sys, const T* b, const T* x, T* r, int k,
                      Eigen::MatrixXd& work) {
  if (sys.boundaryCount() == 0) return;
  boundaryRowsResidual(sys, BoundaryColumns::All, b, x, k, work);
  for (int c = 0; c < k; ++c)
    for (int j = 0; j < sys.boundaryCount(); ++j)
      r[c * sys.slotCount() + sys.boundarySlots[static_cast<size_t>(j)]] =
          static_cast<T>(work(j, c));
}

/// Complete residual r = b - A x on every slot (empty slots hold 0) (Fig. 8 R.6, before R^l).
template <typename T>
void levelResidual(const LevelSystem& sys, const T* stencil, const T* b, const T* x, T* r, int k,
                   Eigen::MatrixXd& work) {
  interiorResidual(sys, stencil, b, x, r, k);
  boundaryResidual(sys, b, x, r, k, work);
}

/// One row of one box, for loops over every slot of a level.
struct BoxRow {
  int box = 0;  ///< index into GridLevel::boxes
  int y = 0;    ///< lattice y
};

/// Every row of every box of `level`.
std::vector<BoxRow> boxRowsOf(const GridLevel& level);

/// Bilinear weight of fine coordinate f relative to coarse coordinate c (|f - 2c| <= 1).
template <typename T>
inline T transferWeight(int f, int c) {
  const int d = f - 2 * c;
  return d == 0 ? T(1) : (d == 1 || d == -1) ? T(0.5) : T(0);
}

/// floor(v / 2) for any sign of v.
inline int floorHalf(int v) {
  return v >> 1;
}

/// Row pointer of lattice row y of box `box` in channel plane v (nullptr if the row lies outside
/// the box), at the slot of lattice x = box.x0.
template <typename T>
inline T* boxRow(const GridBox& box, int y, T* v) {
  if (y < box.y0 || y >= box.y0 + box.height) return nullptr;
  return v + box.slot(box.x0, y);
}

/// Restricts one coarse row of one channel plane: bc(x, y) = sum over fine (2x + i, 2y + j),
/// |i|, |j| <= 1 inside the fine box, of w_i w_j r (bilinear weights 1, 1/2). Slots without an
/// unknown get values that are never read.
template <typename T>
TEXGRAD_SIMD_CLONES void restrictRow(const GridBox& fb, const GridBox& cb, int y, const T* r,
                                     T* bc) {
  const T* rows[3] = {boxRow(fb, 2 * y - 1, r), boxRow(fb, 2 * y, r), boxRow(fb, 2 * y + 1, r)};
  const T wy[3] = {T(0.5), T(1), T(0.5)};
  T* out = bc + cb.slot(cb.x0, y);
  // Coarse columns whose three fine columns all lie in the fine box.
  const int lo = std::max(cb.x0, floorHalf(fb.x0 + 1) + ((fb.x0 + 1) & 1));
  const int hi = std::min(cb.x0 + cb.width - 1, floorHalf(fb.x0 + fb.width - 2));
  for (int x = cb.x0; x < cb.x0 + cb.width; ++x) {
    const bool inside = x >= lo && x <= hi;
    if (inside && x == lo) {
      const int64_t n = hi - lo + 1;
      T* o = out + (lo - cb.x0);
      for (int64_t i = 0; i < n; ++i) o[i] = T(0);
      for (int j = 0; j < 3; ++j) {
        if (!rows[j]) continue;
        const T* f = rows[j] + (2 * lo - fb.x0);
        const T wj = wy[j];
        for (int64_t i = 0; i < n; ++i)
          o[i] += wj * ((T(0.5) * f[2 * i - 1] + f[2 * i]) + T(0.5) * f[2 * i + 1]);
      }
      x = hi;
      continue;
    }
    out[x - cb.x0] = T(0);
    for (int j = 0; j < 3; ++j) {
      if (!rows[j]) continue;
      for (int fx = 2 * x - 1; fx <= 2 * x + 1; ++fx) {
        if (fx < fb.x0 || fx >= fb.x0 + fb.width) continue;
        out[x - cb.x0] += wy[j] * transferWeight<T>(fx, x) * rows[j][fx - fb.x0];
      }
    }
  }
}

/// b^{l+1} = Pᵀ r^l on every coarse slot of each of the k channel planes (Fig. 8 R.6); values at
/// slots without an unknown are never read.
template <typename T>
void restrictResidual(const GridLevel& fine, const GridLevel& coarse,
                      const std::vector<BoxRow>& coarseRows, const T* r, T* bc, int k) {
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, coarseRows.size(), kRowGrain),
      [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i != range.end(); ++i) {
          const GridBox& cb = coarse.boxes[static_cast<size_t>(coarseRows[i].box)];
          const GridBox& fb =
              fine.boxes[static_cast<size_t>(fine.boxOfChart[static_cast<size_t>(cb.chart)])];
          for (int c = 0; c < k; ++c)
            restrictRow<T>(fb, cb, coarseRows[i].y, r + c * fine.slotCount,
                           bc + c * coarse.slotCount);
        }
      });
}

/// Adds the bilinear interpolation of one or two coarse rows to one fine row of one channel plane
/// on slots whose kind is not Empty: xf(x) += wy (c(x / 2)) for even x,
/// wy (c(x / 2) + c(x / 2 + 1)) / 2 for odd x.
template <typename T>
TEXGRAD_SIMD_CLONES void prolongRow(const GridBox& fb, const GridBox& cb, int y,
                                    const SlotKind* kind, const T* xc, T* xf) {
  const T* c0 = xc + cb.slot(cb.x0, y >> 1);
  const T* c1 = xc + cb.slot(cb.x0, (y + 1) >> 1);
  const bool odd = y & 1;
  const int64_t s0 = fb.slot(fb.x0, y);
  const SlotKind* kd = kind + s0;
  T* out = xf + s0;
  // Fine x = 2 m + parity with coarse index m - cb.x0 (and m + 1 - cb.x0 for odd x).
  for (int parity = 0; parity < 2; ++parity) {
    int x = fb.x0 + ((fb.x0 & 1) != parity ? 1 : 0);
    const int64_t n = (fb.x0 + fb.width - x + 1) / 2;
    const int64_t m0 = (x >> 1) - cb.x0, f0 = x - fb.x0;
    for (int64_t i = 0; i < n; ++i) {
      const int64_t m = m0 + i;
      const T h0 = parity ? T(0.5) * (c0[m] + c0[m + 1]) : c0[m];
      const T h1 = parity ? T(0.5) * (c1[m] + c1[m + 1]) : c1[m];
      const T v = odd ? T(0.5) * (h0 + h1) : h0;
      const int64_t f = f0 + 2 * i;
      out[f] += kd[f] != SlotKind::Empty ? v : T(0);
    }
  }
}

/// x^l += P x^{l+1} on every non-empty fine slot of each of the k channel planes (Fig. 8 P.2).
template <typename T>
void prolongCorrection(const GridLevel& fine, const GridLevel& coarse, const SlotKind* fineKind,
                       const std::vector<BoxRow>& fineRows, const T* xc, T* xf, int k) {
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, fineRows.size(), kRowGrain),
      [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i != range.end(); ++i) {
          const GridBox& fb = fine.boxes[static_cast<size_t>(fineRows[i].box)];
          const GridBox& cb =
              coarse.boxes[static_cast<size_t>(coarse.boxOfChart[static_cast<size_t>(fb.chart)])];
          for (int c = 0; c < k; ++c)
            prolongRow<T>(fb, cb, fineRows[i].y, fineKind, xc + c * coarse.slotCount,
                          xf + c * fine.slotCount);
        }
      });
}

}  // namespace texgrad::detail
