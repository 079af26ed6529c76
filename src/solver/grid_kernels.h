// Solver module (private): allocation-free kernels of the V-cycle on slot-layout vectors (paper §6.2):
// multi-colour Gauss–Seidel on 9-point stencils, residuals, boundary solves, bilinear transfers.
// Vectors hold k interleaved channels per slot: value (slot, c) is at slot * k + c.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <type_traits>
#include <vector>

#include "solver/level_system.h"

namespace texgrad::detail {

template <int N>
using IntC = std::integral_constant<int, N>;

/// Calls fn(chunk, stride, c0) over channel chunks of at most 4; chunk and stride are compile-time
/// constants (stride 0 = the runtime k).
template <typename Fn>
void forChannelChunks(int k, Fn&& fn) {
  switch (k) {
    case 1: fn(IntC<1>{}, IntC<1>{}, 0); return;
    case 2: fn(IntC<2>{}, IntC<2>{}, 0); return;
    case 3: fn(IntC<3>{}, IntC<3>{}, 0); return;
    case 4: fn(IntC<4>{}, IntC<4>{}, 0); return;
    default: break;
  }
  int c0 = 0;
  for (; c0 + 4 <= k; c0 += 4) fn(IntC<4>{}, IntC<0>{}, c0);
  switch (k - c0) {
    case 1: fn(IntC<1>{}, IntC<0>{}, c0); break;
    case 2: fn(IntC<2>{}, IntC<0>{}, c0); break;
    case 3: fn(IntC<3>{}, IntC<0>{}, c0); break;
    default: break;
  }
}

/// Rows per TBB task in grid loops (a row is a few hundred to a few thousand slots).
constexpr size_t kRowGrain = 4;

/// Gauss–Seidel on slots of one x parity in a row: x = (b - sum_{k != centre} w_k x_k) / w_centre.
template <typename T, int KC, int S>
void relaxRowParity(const SlotRow& row, int parity, const T* stencil, const SlotKind* kind,
                    const T* b, T* x, int k, int c0) {
  const int64_t stride = S > 0 ? S : k;
  const int64_t w = row.width;
  const int64_t off[9] = {-w - 1, -w, -w + 1, -1, 0, 1, w - 1, w, w + 1};
  for (int64_t s = row.begin + ((parity ^ row.xParity) & 1); s < row.end; s += 2) {
    if (kind[s] != SlotKind::Interior) continue;
    const T* ws = stencil + s * 9;
    T acc[KC];
    for (int c = 0; c < KC; ++c) acc[c] = b[s * stride + c0 + c];
    for (int j = 0; j < 9; ++j) {
      if (j == 4) continue;
      const T* xn = x + (s + off[j]) * stride + c0;
      for (int c = 0; c < KC; ++c) acc[c] -= ws[j] * xn[c];
    }
    const T inv = T(1) / ws[4];
    for (int c = 0; c < KC; ++c) x[s * stride + c0 + c] = acc[c] * inv;
  }
}

/// One symmetric-ordered Gauss–Seidel sweep over all interior slots with boundary values locked
/// (Fig. 8 R.2–R.3 fused): colours (y, x) parity 00, 01, 10, 11 forward, the reverse backward.
/// Same-colour slots do not couple, so rows run in parallel and the result is thread-independent.
template <typename T>
void relaxInterior(const LevelSystem& sys, const T* stencil, const T* b, T* x, int k,
                   bool forward) {
  const SlotKind* kind = sys.kind.data();
  for (int phase = 0; phase < 2; ++phase) {
    const int yParity = forward ? phase : 1 - phase;
    const std::vector<SlotRow>& rows = sys.rows[yParity];
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rows.size(), kRowGrain),
                      [&](const tbb::blocked_range<size_t>& range) {
      forChannelChunks(k, [&](auto chunk, auto stride, int c0) {
        for (size_t i = range.begin(); i != range.end(); ++i) {
          for (int q = 0; q < 2; ++q) {
            const int parity = forward ? q : 1 - q;
            relaxRowParity<T, decltype(chunk)::value, decltype(stride)::value>(
                rows[i], parity, stencil, kind, b, x, k, c0);
          }
        }
      });
    });
  }
}

/// r = b - A x on interior slots and r = 0 on the other slots of interior rows.
template <typename T>
void interiorResidual(const LevelSystem& sys, const T* stencil, const T* b, const T* x, T* r,
                      int k) {
  const SlotKind* kind = sys.kind.data();
  for (int yParity = 0; yParity < 2; ++yParity) {
    const std::vector<SlotRow>& rows = sys.rows[yParity];
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rows.size(), kRowGrain),
                      [&](const tbb::blocked_range<size_t>& range) {
      for (size_t i = range.begin(); i != range.end(); ++i) {
        const int64_t w = rows[i].width;
        const int64_t off[9] = {-w - 1, -w, -w + 1, -1, 0, 1, w - 1, w, w + 1};
        for (int64_t s = rows[i].begin; s < rows[i].end; ++s) {
          if (kind[s] != SlotKind::Interior) {
            for (int c = 0; c < k; ++c) r[s * k + c] = T(0);
            continue;
          }
          const T* ws = stencil + s * 9;
          for (int c = 0; c < k; ++c) {
            T acc = b[s * k + c];
            for (int j = 0; j < 9; ++j) acc -= ws[j] * x[(s + off[j]) * k + c];
            r[s * k + c] = acc;
          }
        }
      }
    });
  }
}

/// Accumulates, per boundary row j and channel c, out(j, c) = b - sum over csr row j of A x.
template <typename T>
void boundaryRowsResidual(const LevelSystem& sys, const SlotCsr& csr, const T* b, const T* x,
                          int k, Eigen::MatrixXd& out) {
  out.resize(sys.boundaryCount(), k);
  tbb::parallel_for(tbb::blocked_range<int>(0, sys.boundaryCount(), 256),
                    [&](const tbb::blocked_range<int>& range) {
    for (int j = range.begin(); j != range.end(); ++j) {
      const int64_t s = sys.boundarySlots[static_cast<size_t>(j)];
      for (int c = 0; c < k; ++c) {
        double acc = static_cast<double>(b[s * k + c]);
        for (int64_t e = csr.ptr[static_cast<size_t>(j)]; e < csr.ptr[static_cast<size_t>(j) + 1]; ++e)
          acc -= csr.val[static_cast<size_t>(e)] * static_cast<double>(x[csr.col[static_cast<size_t>(e)] * k + c]);
        out(j, c) = acc;
      }
    }
  });
}

/// Boundary direct solve with interior locked (Fig. 8 R.4–R.5 / P.3–P.4), in double precision.
template <typename T>
void solveBoundary(const LevelSystem& sys, const T* b, T* x, int k, Eigen::MatrixXd& work) {
  if (sys.boundaryCount() == 0) return;
  boundaryRowsResidual(sys, sys.offBlock, b, x, k, work);
  sys.boundarySolver.solveInPlace(work);
  for (int j = 0; j < sys.boundaryCount(); ++j)
    for (int c = 0; c < k; ++c)
      x[sys.boundarySlots[static_cast<size_t>(j)] * k + c] = static_cast<T>(work(j, c));
}

/// Complete residual r = b - A x on every slot (empty slots hold 0) (Fig. 8 R.6, before R^l).
template <typename T>
void levelResidual(const LevelSystem& sys, const T* stencil, const T* b, const T* x, T* r, int k,
                   Eigen::MatrixXd& work) {
  interiorResidual(sys, stencil, b, x, r, k);
  if (sys.boundaryCount() == 0) return;
  boundaryRowsResidual(sys, sys.fullRows, b, x, k, work);
  for (int j = 0; j < sys.boundaryCount(); ++j)
    for (int c = 0; c < k; ++c)
      r[sys.boundarySlots[static_cast<size_t>(j)] * k + c] = static_cast<T>(work(j, c));
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

/// b^{l+1} = Pᵀ r^l on every non-empty coarse slot (Fig. 8 R.6).
template <typename T>
void restrictResidual(const GridLevel& fine, const GridLevel& coarse,
                      const std::vector<BoxRow>& coarseRows, const T* r, T* bc, int k) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, coarseRows.size(), kRowGrain),
                    [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i != range.end(); ++i) {
      const GridBox& cb = coarse.boxes[static_cast<size_t>(coarseRows[i].box)];
      const GridBox& fb = fine.boxes[static_cast<size_t>(fine.boxOfChart[static_cast<size_t>(cb.chart)])];
      const int y = coarseRows[i].y;
      for (int x = cb.x0; x < cb.x0 + cb.width; ++x) {
        const int64_t s = cb.slot(x, y);
        if (coarse.unknownOfSlot[static_cast<size_t>(s)] < 0) continue;
        for (int c = 0; c < k; ++c) bc[s * k + c] = T(0);
        for (int fy = 2 * y - 1; fy <= 2 * y + 1; ++fy) {
          for (int fx = 2 * x - 1; fx <= 2 * x + 1; ++fx) {
            if (!fb.contains(fx, fy)) continue;
            const T wgt = transferWeight<T>(fx, x) * transferWeight<T>(fy, y);
            const T* rf = r + fb.slot(fx, fy) * k;
            for (int c = 0; c < k; ++c) bc[s * k + c] += wgt * rf[c];
          }
        }
      }
    }
  });
}

/// x^l += P x^{l+1} on every non-empty fine slot (Fig. 8 P.2).
template <typename T>
void prolongCorrection(const GridLevel& fine, const GridLevel& coarse,
                       const std::vector<BoxRow>& fineRows, const T* xc, T* xf, int k) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, fineRows.size(), kRowGrain),
                    [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i != range.end(); ++i) {
      const GridBox& fb = fine.boxes[static_cast<size_t>(fineRows[i].box)];
      const GridBox& cb = coarse.boxes[static_cast<size_t>(coarse.boxOfChart[static_cast<size_t>(fb.chart)])];
      const int y = fineRows[i].y;
      const int cy0 = y >> 1, cy1 = (y + 1) >> 1;
      const T wy = (y & 1) ? T(0.5) : T(1);
      for (int x = fb.x0; x < fb.x0 + fb.width; ++x) {
        const int64_t s = fb.slot(x, y);
        if (fine.unknownOfSlot[static_cast<size_t>(s)] < 0) continue;
        const int cx0 = x >> 1, cx1 = (x + 1) >> 1;
        const T wx = (x & 1) ? T(0.5) : T(1);
        const T* p00 = xc + cb.slot(cx0, cy0) * k;
        const T* p01 = xc + cb.slot(cx1, cy0) * k;
        const T* p10 = xc + cb.slot(cx0, cy1) * k;
        const T* p11 = xc + cb.slot(cx1, cy1) * k;
        const bool oddX = x & 1, oddY = y & 1;
        for (int c = 0; c < k; ++c) {
          T v = p00[c];
          if (oddX) v += p01[c];
          if (oddY) v += p10[c] + (oddX ? p11[c] : T(0));
          xf[s * k + c] += wx * wy * v;
        }
      }
    }
  });
}

}  // namespace texgrad::detail
