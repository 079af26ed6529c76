// Solver module (private): Galerkin coarse operators by sparse accumulation, one coarse column at
// a time (the classic row-by-row RAP, transposed for column-major storage).
#include "texgrad/solver/galerkin.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

namespace texgrad {
namespace {

using Sparse = Eigen::SparseMatrix<double>;
using RowMajor = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// Coarse columns per task (fixed, so the split does not depend on the thread count).
constexpr Eigen::Index kColumnsPerTask = 2048;

/// Dense accumulator over an index range with the list of touched indices; reset by stamps.
struct Accumulator {
  std::vector<double> value;
  std::vector<Eigen::Index> stamp;
  std::vector<int> touched;
  void resize(Eigen::Index n) {
    if (static_cast<Eigen::Index>(value.size()) == n) return;
    value.assign(static_cast<size_t>(n), 0.0);
    stamp.assign(static_cast<size_t>(n), -1);
  }
  void add(int i, double v, Eigen::Index column) {
    const size_t si = static_cast<size_t>(i);
    if (stamp[si] != column) {
      stamp[si] = column;
      value[si] = 0.0;
      touched.push_back(i);
    }
    value[si] += v;
  }
};

struct Scratch {
  Accumulator fine, coarse;
};

/// One task's columns of the result, in compressed form with a local column pointer.
struct Block {
  std::vector<int> count;
  std::vector<int> inner;
  std::vector<double> values;
};

}  // namespace

Sparse galerkinProduct(const Sparse& a, const Sparse& p) {
  const RowMajor pRows = p;  // row r of P: the coarse columns fine texel r interpolates from
  const Eigen::Index nc = p.cols();
  const Eigen::Index tasks = (nc + kColumnsPerTask - 1) / kColumnsPerTask;
  std::vector<Block> blocks(static_cast<size_t>(tasks));
  tbb::enumerable_thread_specific<Scratch> scratch;
  tbb::parallel_for(Eigen::Index(0), tasks, [&](Eigen::Index t) {
    Scratch& s = scratch.local();
    s.fine.resize(a.rows());
    s.coarse.resize(nc);
    Block& block = blocks[static_cast<size_t>(t)];
    const Eigen::Index first = t * kColumnsPerTask, last = std::min(nc, first + kColumnsPerTask);
    for (Eigen::Index j = first; j < last; ++j) {
      s.fine.touched.clear();
      s.coarse.touched.clear();
      for (Sparse::InnerIterator pi(p, j); pi; ++pi)  // (A P)_{:, j}
        for (Sparse::InnerIterator ai(a, pi.row()); ai; ++ai)
          s.fine.add(static_cast<int>(ai.row()), ai.value() * pi.value(), j);
      for (int r : s.fine.touched)  // (Pᵀ A P)_{:, j}
        for (RowMajor::InnerIterator pr(pRows, r); pr; ++pr)
          s.coarse.add(static_cast<int>(pr.col()),
                       pr.value() * s.fine.value[static_cast<size_t>(r)], j);
      std::sort(s.coarse.touched.begin(), s.coarse.touched.end());
      block.count.push_back(static_cast<int>(s.coarse.touched.size()));
      for (int k : s.coarse.touched) {
        block.inner.push_back(k);
        block.values.push_back(s.coarse.value[static_cast<size_t>(k)]);
      }
    }
  });
  Sparse c(nc, nc);
  Eigen::Index nonZeros = 0;
  for (const Block& block : blocks) nonZeros += static_cast<Eigen::Index>(block.inner.size());
  c.resizeNonZeros(nonZeros);
  int* outer = c.outerIndexPtr();
  outer[0] = 0;
  Eigen::Index column = 0;
  for (const Block& block : blocks)
    for (int count : block.count) {
      outer[column + 1] = outer[column] + count;
      ++column;
    }
  tbb::parallel_for(Eigen::Index(0), tasks, [&](Eigen::Index t) {
    const Block& block = blocks[static_cast<size_t>(t)];
    const int offset = outer[t * kColumnsPerTask];
    std::copy(block.inner.begin(), block.inner.end(), c.innerIndexPtr() + offset);
    std::copy(block.values.begin(), block.values.end(), c.valuePtr() + offset);
  });
  return c;
}

}  // namespace texgrad
