// Solver module: CHOLMOD behind a pimpl (cholmod.h stays in this file), phases counted and timed.
#include "texgrad/solver/cholmod_solver.h"

#include <cholmod.h>

#include <chrono>
#include <string>
#include <vector>

#include "texgrad/core/error.h"
#include "texgrad/core/storage_bytes.h"

namespace texgrad {
namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

struct CholmodSolver::Impl {
  mutable cholmod_common common{};
  cholmod_factor* factor = nullptr;
  // Lower triangle of the analysed / factorised matrix in CSC form (CHOLMOD_INT indices). The
  // pattern stays to tell whether the next matrix needs a new analysis; the values are freed once
  // analysed or factorised (every entry point loads them again first).
  std::vector<int> colPtr, rowIdx;
  std::vector<double> values;
  int n = 0;
  bool analysed = false, factorised = false;
  mutable cholmod_dense *x = nullptr, *y = nullptr, *e = nullptr;  // solve2 workspace
  CholmodStats stats;

  Impl() {
    cholmod_start(&common);
    common.print = 0;  // the library never prints; failures come back through status
  }
  ~Impl() {
    freeWorkspace();
    if (factor) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  void freeWorkspace() const {
    if (x) cholmod_free_dense(&x, &common);
    if (y) cholmod_free_dense(&y, &common);
    if (e) cholmod_free_dense(&e, &common);
  }

  // Copies the lower triangle of `a`; returns true when its pattern equals the stored one.
  bool loadLower(const Eigen::SparseMatrix<double>& a) {
    if (a.rows() != a.cols())
      throw InvalidInputError("CholmodSolver: matrix is " + std::to_string(a.rows()) + " x " +
                              std::to_string(a.cols()) + ", expected square");
    std::vector<int> newPtr(static_cast<size_t>(a.cols()) + 1, 0);
    std::vector<int> newIdx;
    newIdx.reserve(static_cast<size_t>(a.nonZeros() / 2 + a.cols()));
    values.clear();
    values.reserve(newIdx.capacity());
    for (Eigen::Index j = 0; j < a.outerSize(); ++j) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(a, j); it; ++it) {
        if (it.row() < j) continue;
        newIdx.push_back(static_cast<int>(it.row()));
        values.push_back(it.value());
      }
      newPtr[static_cast<size_t>(j) + 1] = static_cast<int>(newIdx.size());
    }
    const bool same = newPtr == colPtr && newIdx == rowIdx;
    colPtr.swap(newPtr);
    rowIdx.swap(newIdx);
    n = static_cast<int>(a.rows());
    return same;
  }

  cholmod_sparse view() {
    cholmod_sparse s{};
    s.nrow = s.ncol = static_cast<size_t>(n);
    s.nzmax = rowIdx.size();
    s.p = colPtr.data();
    s.i = rowIdx.data();
    s.x = values.data();
    s.stype = -1;  // symmetric, lower triangle stored
    s.itype = CHOLMOD_INT;
    s.xtype = CHOLMOD_REAL;
    s.dtype = CHOLMOD_DOUBLE;
    s.sorted = 1;
    s.packed = 1;
    return s;
  }

  void analyse() {
    const auto start = std::chrono::steady_clock::now();
    if (factor) cholmod_free_factor(&factor, &common);
    freeWorkspace();
    cholmod_sparse a = view();
    factor = cholmod_analyze(&a, &common);
    if (!factor || common.status < CHOLMOD_OK)
      throw NumericalError("CHOLMOD symbolic analysis failed (status " +
                           std::to_string(common.status) + ") on a " + std::to_string(n) +
                           " x " + std::to_string(n) + " matrix; it may be too large for memory");
    analysed = true;
    factorised = false;
    ++stats.analyses;
    stats.analyzeSeconds += secondsSince(start);
  }

  // A simplicial LDLᵀ factorisation succeeds on indefinite matrices; its pivots D(j, j) tell.
  bool positiveLdlPivots() const {
    if (factor->is_super || factor->is_ll) return true;
    const auto* p = static_cast<const int*>(factor->p);
    const auto* pivots = static_cast<const double*>(factor->x);
    for (size_t j = 0; j < factor->n; ++j)
      if (!(pivots[p[j]] > 0.0)) return false;
    return true;
  }

  void factorise() {
    const auto start = std::chrono::steady_clock::now();
    cholmod_sparse a = view();
    const int ok = cholmod_factorize(&a, factor, &common);
    factorised = false;
    if (!ok || common.status == CHOLMOD_NOT_POSDEF || factor->minor < factor->n ||
        !positiveLdlPivots())
      throw NumericalError("CHOLMOD factorisation failed: the " + std::to_string(n) + " x " +
                           std::to_string(n) + " matrix is not positive definite (pivot " +
                           std::to_string(factor->minor) +
                           "); check that the screening weight is positive or use a metric "
                           "without degenerate triangles");
    if (common.status < CHOLMOD_OK)
      throw NumericalError("CHOLMOD factorisation failed (status " +
                           std::to_string(common.status) + ")");
    factorised = true;
    ++stats.factorizations;
    stats.factorizeSeconds += secondsSince(start);
    stats.factorNonZeros = static_cast<long>(common.lnz);
  }
};

CholmodSolver::CholmodSolver() : impl_(std::make_unique<Impl>()) {}
CholmodSolver::CholmodSolver(const Eigen::SparseMatrix<double>& a) : CholmodSolver() {
  compute(a);
}
CholmodSolver::~CholmodSolver() = default;
CholmodSolver::CholmodSolver(CholmodSolver&&) noexcept = default;
CholmodSolver& CholmodSolver::operator=(CholmodSolver&&) noexcept = default;

void CholmodSolver::analyzePattern(const Eigen::SparseMatrix<double>& a) {
  impl_->loadLower(a);
  impl_->analyse();
  std::vector<double>().swap(impl_->values);
}

void CholmodSolver::factorize(const Eigen::SparseMatrix<double>& a) {
  const bool same = impl_->loadLower(a);
  if (!impl_->analysed || !same) impl_->analyse();
  impl_->factorise();
  std::vector<double>().swap(impl_->values);
}

CholmodSolver& CholmodSolver::compute(const Eigen::SparseMatrix<double>& a) {
  factorize(a);
  return *this;
}

Eigen::MatrixXd CholmodSolver::solve(const Eigen::MatrixXd& b) const {
  Eigen::MatrixXd x = b;
  solveInPlace(x);
  return x;
}

void CholmodSolver::solveInPlace(Eigen::Ref<Eigen::MatrixXd> bx) const {
  Impl& m = *impl_;
  if (!m.factorised)
    throw InvalidInputError("CholmodSolver::solve called before a successful factorize");
  if (bx.rows() != m.n)
    throw InvalidInputError("CholmodSolver::solve: right-hand side has " +
                            std::to_string(bx.rows()) + " rows, matrix has " +
                            std::to_string(m.n));
  if (m.n == 0 || bx.cols() == 0) return;
  const auto start = std::chrono::steady_clock::now();
  cholmod_dense b{};
  b.nrow = static_cast<size_t>(bx.rows());
  b.ncol = static_cast<size_t>(bx.cols());
  b.d = static_cast<size_t>(bx.outerStride());
  b.nzmax = b.d * b.ncol;
  b.x = bx.data();
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_solve2(CHOLMOD_A, m.factor, &b, nullptr, &m.x, nullptr, &m.y, &m.e, &m.common))
    throw NumericalError("CHOLMOD solve failed (status " + std::to_string(m.common.status) + ")");
  const auto* xs = static_cast<const double*>(m.x->x);
  for (Eigen::Index c = 0; c < bx.cols(); ++c)
    for (Eigen::Index r = 0; r < bx.rows(); ++r)
      bx(r, c) = xs[static_cast<size_t>(c) * m.x->d + static_cast<size_t>(r)];
  ++m.stats.solves;
  m.stats.solveSeconds += secondsSince(start);
}

Eigen::ComputationInfo CholmodSolver::info() const {
  return impl_->factorised ? Eigen::Success : Eigen::InvalidInput;
}

Eigen::Index CholmodSolver::rows() const { return impl_->n; }

int64_t CholmodSolver::storageBytes() const {
  return capacityBytes(impl_->colPtr, impl_->rowIdx, impl_->values) +
         static_cast<int64_t>(impl_->common.memory_inuse);
}

const CholmodStats& CholmodSolver::stats() const { return impl_->stats; }

Eigen::MatrixXd solveDirect(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b) {
  CholmodSolver solver(a);
  return solver.solve(b);
}

}  // namespace texgrad
