// Core (private): sums over the rows of long vectors on all cores, in an order fixed by the row
// count alone, so that a solve gives the same bits on any number of threads.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <array>
#include <cstddef>
#include <cstdint>

namespace texgrad {

/// Rows per task of sumsOverRows (fixed: the sums do not depend on the thread count).
inline constexpr int64_t kRowsPerTask = int64_t{1} << 14;

/// The K sums f(begin, end) returns (std::array<double, K>) over row blocks of [0, n), the
/// blocks' sums added in an order that depends on n only.
template <std::size_t K, typename F>
std::array<double, K> sumsOverRows(int64_t n, F&& f) {
  using Sums = std::array<double, K>;
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<int64_t>(0, n, kRowsPerTask), Sums{},
      [&](const tbb::blocked_range<int64_t>& range, Sums acc) {
        const Sums part = f(range.begin(), range.end());
        for (std::size_t k = 0; k < K; ++k) acc[k] += part[k];
        return acc;
      },
      [](Sums u, const Sums& v) {
        for (std::size_t k = 0; k < K; ++k) u[k] += v[k];
        return u;
      });
}

/// The sum f(begin, end) returns (a double) over row blocks of [0, n), as sumsOverRows adds.
template <typename F>
double sumOverRows(int64_t n, F&& f) {
  return sumsOverRows<1>(
      n, [&](int64_t begin, int64_t end) { return std::array<double, 1>{f(begin, end)}; })[0];
}

}  // namespace texgrad
