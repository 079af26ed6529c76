// Solver module: multi-channel preconditioned conjugate gradients with a solve report.
#include "texgrad/solver/conjugate_gradient.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <string>
#include <type_traits>
#include <utility>

#include "texgrad/core/error.h"

namespace texgrad {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Column-wise dot products of two n x k blocks, accumulated in double whatever their precision.
template <typename U, typename V>
Eigen::RowVectorXd columnDots(const U& u, const V& v) {
  return u.template cast<double>().cwiseProduct(v.template cast<double>()).colwise().sum();
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
  const double bNorm = r.norm();
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
  report.residuals.push_back(r.norm() * scale);
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
    r.noalias() -= w.template cast<Iterate>() * step.asDiagonal();
    const double residual = r.norm() * scale;
    if (residual >= bestResidual && best.size() == 0) best = x.template cast<Scalar>();
    x.noalias() += p.template cast<Iterate>() * step.asDiagonal();
    report.rmsChange.push_back((p.template cast<double>() * alpha.asDiagonal()).norm() /
                               std::sqrt(std::max<double>(1.0, double(p.size()))));
    report.times.other += secondsSince(start);
    precondition();
    start = Clock::now();
    const Eigen::RowVectorXd rzNew = columnDots(r, w);
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      requirePositive(rzNew(c), !r.col(c).isZero(0.0), "r^T z", "the preconditioner", c,
                      report.iterations);
      const double beta = rz(c) > 0.0 ? rzNew(c) / rz(c) : 0.0;
      p.col(c) = w.col(c) + static_cast<Scalar>(beta) * p.col(c);
    }
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
