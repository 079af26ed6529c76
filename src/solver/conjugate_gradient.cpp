// Solver module: multi-channel preconditioned conjugate gradients with a solve report.
#include "texgrad/solver/conjugate_gradient.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <string>
#include <type_traits>
#include <utility>

#include "core/row_sums.h"
#include "texgrad/core/error.h"

namespace texgrad {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Column-wise dot products of two n x k blocks, accumulated in double whatever their precision,
/// on all cores (sumOverRows: the same bits on any number of threads).
template <typename U, typename V>
Eigen::RowVectorXd columnDots(const U& u, const V& v) {
  Eigen::RowVectorXd dots(u.cols());
  for (Eigen::Index c = 0; c < u.cols(); ++c)
    dots(c) = sumOverRows(u.rows(), [&](int64_t begin, int64_t end) {
      double acc = 0.0;
      for (int64_t i = begin; i < end; ++i)
        acc += static_cast<double>(u(i, c)) * static_cast<double>(v(i, c));
      return acc;
    });
  return dots;
}

/// The Frobenius norm of an n x k block, accumulated in double on all cores (sumOverRows).
template <typename M>
double normOf(const M& m) {
  return std::sqrt(columnDots(m, m).sum());
}

/// r -= w step, column c by step(c), on all cores; returns |r|^2 after it, in double.
template <typename R, typename W>
double subtractStep(R& r, const W& w,
                    const Eigen::Matrix<typename R::Scalar, 1, Eigen::Dynamic>& step) {
  using Iterate = typename R::Scalar;
  return sumOverRows(r.rows(), [&](int64_t begin, int64_t end) {
    double acc = 0.0;
    for (Eigen::Index c = 0; c < r.cols(); ++c)
      for (int64_t i = begin; i < end; ++i) {
        r(i, c) -= static_cast<Iterate>(w(i, c)) * step(c);
        acc += static_cast<double>(r(i, c)) * static_cast<double>(r(i, c));
      }
    return acc;
  });
}

/// x += p step, column c by step(c) (alpha(c) rounded), on all cores; returns |p alpha|^2 of the
/// step in double, alpha unrounded.
template <typename X, typename P>
double addStep(X& x, const P& p, const Eigen::Matrix<typename X::Scalar, 1, Eigen::Dynamic>& step,
               const Eigen::RowVectorXd& alpha) {
  using Iterate = typename X::Scalar;
  return sumOverRows(x.rows(), [&](int64_t begin, int64_t end) {
    double acc = 0.0;
    for (Eigen::Index c = 0; c < x.cols(); ++c)
      for (int64_t i = begin; i < end; ++i) {
        x(i, c) += static_cast<Iterate>(p(i, c)) * step(c);
        const double change = static_cast<double>(p(i, c)) * alpha(c);
        acc += change * change;
      }
    return acc;
  });
}

/// p = w + beta p, column c by beta(c), on all cores.
template <typename P>
void newDirection(P& p, const P& w, const Eigen::RowVectorXd& beta) {
  using Scalar = typename P::Scalar;
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, p.rows(), kRowsPerTask),
                    [&](const tbb::blocked_range<int64_t>& rows) {
                      for (Eigen::Index c = 0; c < p.cols(); ++c) {
                        const auto b = static_cast<Scalar>(beta(c));
                        for (int64_t i = rows.begin(); i != rows.end(); ++i)
                          p(i, c) = w(i, c) + b * p(i, c);
                      }
                    });
}

/// Throws NumericalError naming the first NaN or infinity of `m` ("the right-hand side").
template <typename M>
void requireFinite(const M& m, const std::string& what) {
  if (m.allFinite()) return;
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index i = 0; i < m.rows(); ++i)
      if (!std::isfinite(m(i, c)))
        throw NumericalError("conjugateGradient: " + what + " holds " +
                             std::to_string(double(m(i, c))) + " at row " + std::to_string(i) +
                             ", column " + std::to_string(c));
}

/// Throws NumericalError if a curvature p^T A p (or r^T z) of column c at iteration k is NaN, or
/// is not positive although the direction (or residual) is nonzero: a column that has converged
/// exactly has p = 0 and a zero curvature, which is fine.
void requirePositive(double value, bool nonzeroDirection, const char* name, const char* operand,
                     Eigen::Index c, int k) {
  if (std::isfinite(value) && (value > 0.0 || (value == 0.0 && !nonzeroDirection))) return;
  const std::string where = " at iteration " + std::to_string(k + 1) + ", column " +
                            std::to_string(c) + " (" + name + " = " + std::to_string(value) + ")";
  if (!std::isfinite(value))
    throw NumericalError("conjugateGradient: a NaN or infinity arose" + where +
                         "; the matrix or the preconditioner holds non-finite values");
  throw NumericalError(std::string("conjugateGradient: ") + operand + " is not positive definite" +
                       where);
}

}  // namespace

void CgOptions::validate() const {
  if (maxIterations < 0)
    throw InvalidInputError("CG maxIterations is " + std::to_string(maxIterations) +
                            "; expected >= 0");
  if (!(tolerance >= 0.0)) throw InvalidInputError("CG tolerance must be >= 0");
}

namespace {

/// y = A x for the symmetricProduct overloads: each entry a double sum in column order, stored
/// as store(sum).
template <typename X, typename Y, typename Store>
void productInto(const Eigen::Ref<const Eigen::SparseMatrix<double>>& a, const X& x, Y& y,
                 Store store) {
  y.resize(a.rows(), x.cols());
  const Eigen::Index k = x.cols();
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, a.outerSize(), 1024),
                    [&](const tbb::blocked_range<Eigen::Index>& range) {
    for (Eigen::Index j = range.begin(); j != range.end(); ++j) {
      for (Eigen::Index c = 0; c < k; ++c) {
        double acc = 0.0;
        for (Eigen::Ref<const Eigen::SparseMatrix<double>>::InnerIterator it(a, j); it; ++it)
          acc += it.value() * static_cast<double>(x(it.row(), c));
        y(j, c) = store(acc);
      }
    }
  });
}

}  // namespace

void symmetricProduct(const Eigen::Ref<const Eigen::SparseMatrix<double>>& a,
                      const Eigen::MatrixXd& x, Eigen::MatrixXd& y) {
  productInto(a, x, y, [](double sum) { return sum; });
}

void symmetricProduct(const Eigen::Ref<const Eigen::SparseMatrix<double>>& a,
                      const Eigen::VectorXf& x, Eigen::MatrixXd& y) {
  productInto(a, x, y, [](double sum) { return sum; });
}

void symmetricProduct(const Eigen::Ref<const Eigen::SparseMatrix<double>>& a,
                      const Eigen::VectorXf& x, double scale, Eigen::MatrixXf& y) {
  productInto(a, x, y, [scale](double sum) { return static_cast<float>(scale * sum); });
}

namespace {

/// conjugateGradient with `r` holding B on entry: the residual is formed in its storage.
template <typename Scalar, typename Iterate>
SolveReport conjugateGradientFrom(const CgOperator<Scalar, Iterate>& a,
                                  typename CgOperator<Scalar, Iterate>::Vectors r,
                                  typename CgOperator<Scalar, Iterate>::Vectors& x,
                                  const CgOptions& options, const ProgressCallback& progress) {
  using Block = typename CgOperator<Scalar, Iterate>::Block;
  options.validate();
  if (r.rows() != a.rows || x.rows() != r.rows() || x.cols() != r.cols())
    throw InvalidInputError("conjugateGradient: A is " + std::to_string(a.rows) + " x " +
                            std::to_string(a.rows) + ", B has " + std::to_string(r.rows()) +
                            " rows, X is " + std::to_string(x.rows()) + " x " +
                            std::to_string(x.cols()));
  requireFinite(r, "the right-hand side");
  requireFinite(x, "the initial guess");
  SolveReport report;
  const double bNorm = normOf(r);
  const double scale = bNorm > 0.0 ? 1.0 / bNorm : 1.0;
  // w holds A p until x and r have taken their step, then M⁻¹ r until p has taken it: one block
  // for both (the classic four work vectors in three).
  Block p, w;
  auto start = Clock::now();
  if constexpr (std::is_same_v<Scalar, Iterate>) {
    a.product(x, w);
    r -= w;
  } else {
    residualOfDoubleIterate(a.product, r, x, r, p, w);  // p and w are free until then
  }
  report.times.matvec += secondsSince(start);
  auto precondition = [&] {
    const auto t = Clock::now();
    if (a.preconditioner)
      a.preconditioner(r, w);
    else
      w = r.template cast<Scalar>();
    report.times.preconditioner += secondsSince(t);
  };
  precondition();
  p = w;
  Eigen::RowVectorXd rz = columnDots(r, w);
  for (Eigen::Index c = 0; c < x.cols(); ++c)
    requirePositive(rz(c), !r.col(c).isZero(0.0), "r^T z", "the preconditioner", c, -1);
  report.residuals.push_back(normOf(r) * scale);
  requireFinite(r, "the residual of the initial guess (A holds non-finite values)");
  // The iterate with the smallest residual, returned if the residual then diverges. While the
  // residuals fall that is the current iterate, so it is copied (one n x k block) only once
  // they rise: the iterate before the step that made them rise, which x still is then.
  Block best;
  double bestResidual = report.residuals.back();
  while (report.iterations < options.maxIterations && report.residuals.back() > options.tolerance) {
    reportSolveProgress(progress, report, options.maxIterations, options.tolerance);
    start = Clock::now();
    a.product(p, w);
    report.times.matvec += secondsSince(start);
    start = Clock::now();
    const Eigen::RowVectorXd pap = columnDots(p, w);
    Eigen::RowVectorXd alpha(x.cols());
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      requirePositive(pap(c), !p.col(c).isZero(0.0), "p^T A p", "the matrix", c, report.iterations);
      alpha(c) = pap(c) > 0.0 ? rz(c) / pap(c) : 0.0;
    }
    const Eigen::Matrix<Iterate, 1, Eigen::Dynamic> step = alpha.template cast<Iterate>();
    const double residual = std::sqrt(subtractStep(r, w, step)) * scale;  // r -= A p alpha
    if (residual >= bestResidual && best.size() == 0) best = x.template cast<Scalar>();
    const double change = addStep(x, p, step, alpha);  // x += p alpha
    report.rmsChange.push_back(std::sqrt(change) /
                               std::sqrt(std::max<double>(1.0, double(p.size()))));
    report.times.other += secondsSince(start);
    precondition();
    start = Clock::now();
    const Eigen::RowVectorXd rzNew = columnDots(r, w);
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      requirePositive(rzNew(c), !r.col(c).isZero(0.0), "r^T z", "the preconditioner", c,
                      report.iterations);
    }
    Eigen::RowVectorXd beta(x.cols());
    for (Eigen::Index c = 0; c < x.cols(); ++c) beta(c) = rz(c) > 0.0 ? rzNew(c) / rz(c) : 0.0;
    newDirection(p, w, beta);
    rz = rzNew;
    ++report.iterations;
    report.residuals.push_back(residual);
    report.times.other += secondsSince(start);
    if (residual < bestResidual) {
      bestResidual = residual;
      if (best.size() != 0) best = x.template cast<Scalar>();
    } else if (residual > kCgDivergenceGrowth * bestResidual) {
      x = best.template cast<Iterate>();
      report.diverged = true;
      break;
    }
  }
  report.converged = !report.diverged && report.residuals.back() <= options.tolerance;
  reportSolveProgress(progress, report, options.maxIterations, options.tolerance, true);
  return report;
}

}  // namespace

template <typename Scalar, typename Iterate>
SolveReport conjugateGradient(const CgOperator<Scalar, Iterate>& a,
                              const typename CgOperator<Scalar, Iterate>::Vectors& b,
                              typename CgOperator<Scalar, Iterate>::Vectors& x,
                              const CgOptions& options, const ProgressCallback& progress) {
  return conjugateGradientFrom(a, typename CgOperator<Scalar, Iterate>::Vectors(b), x, options,
                               progress);
}

template <typename Scalar, typename Iterate>
SolveReport conjugateGradient(const CgOperator<Scalar, Iterate>& a,
                              typename CgOperator<Scalar, Iterate>::Vectors&& b,
                              typename CgOperator<Scalar, Iterate>::Vectors& x,
                              const CgOptions& options, const ProgressCallback& progress) {
  return conjugateGradientFrom(a, std::move(b), x, options, progress);
}

template SolveReport conjugateGradient<float, double>(const CgOperator<float>&,
                                                      const Eigen::MatrixXd&, Eigen::MatrixXd&,
                                                      const CgOptions&, const ProgressCallback&);
template SolveReport conjugateGradient<double, double>(const CgOperator<double>&,
                                                       const Eigen::MatrixXd&, Eigen::MatrixXd&,
                                                       const CgOptions&, const ProgressCallback&);
template SolveReport conjugateGradient<float, float>(const CgOperator<float, float>&,
                                                     const Eigen::MatrixXf&, Eigen::MatrixXf&,
                                                     const CgOptions&, const ProgressCallback&);
template SolveReport conjugateGradient<float, float>(const CgOperator<float, float>&,
                                                     Eigen::MatrixXf&&, Eigen::MatrixXf&,
                                                     const CgOptions&, const ProgressCallback&);
template SolveReport conjugateGradient<float, double>(const CgOperator<float>&, Eigen::MatrixXd&&,
                                                      Eigen::MatrixXd&, const CgOptions&,
                                                      const ProgressCallback&);
template SolveReport conjugateGradient<double, double>(const CgOperator<double>&,
                                                       Eigen::MatrixXd&&, Eigen::MatrixXd&,
                                                       const CgOptions&, const ProgressCallback&);

SolveReport conjugateGradient(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b,
                              Eigen::MatrixXd& x, const Preconditioner& preconditioner,
                              const CgOptions& options, const ProgressCallback& progress) {
  if (a.rows() != a.cols())
    throw InvalidInputError("conjugateGradient: A is " + std::to_string(a.rows()) + " x " +
                            std::to_string(a.cols()) + "; expected a square matrix");
  CgOperator<double> op;
  op.rows = a.rows();
  op.product = [&a](const Eigen::MatrixXd& p, Eigen::MatrixXd& ap) { symmetricProduct(a, p, ap); };
  op.preconditioner = preconditioner;
  return conjugateGradient(op, b, x, options, progress);
}

}  // namespace texgrad
