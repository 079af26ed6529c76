// Solver module: checks of the two-matrix view and its conversion to a matrix.
#include "texgrad/solver/sparse_sum.h"

#include <algorithm>
#include <string>

#include "texgrad/core/error.h"

namespace texgrad {

SparseSum::SparseSum(bool compressed, Eigen::Index rows, Eigen::Index cols, const int* outer,
                     const int* inner, const double* values)
    : rows_(rows), outer_(outer), inner_(inner), x_(values) {
  if (!compressed)
    throw InvalidInputError("SparseSum: the matrix is not compressed; call makeCompressed()");
  if (rows != cols)
    throw InvalidInputError("SparseSum: the matrix is " + std::to_string(rows) + " x " +
                            std::to_string(cols) + "; expected a square matrix");
}

void SparseSum::addSecond(double xScale, double yScale, bool compressed, Eigen::Index rows,
                          Eigen::Index cols, const int* outer, const int* inner,
                          const double* values) {
  if (!compressed)
    throw InvalidInputError(
        "SparseSum: the second matrix is not compressed; call makeCompressed()");
  if (rows != rows_ || cols != rows_)
    throw InvalidInputError("SparseSum: the matrices are " + std::to_string(rows_) + " x " +
                            std::to_string(rows_) + " and " + std::to_string(rows) + " x " +
                            std::to_string(cols) + "; expected one square size");
  const bool samePattern = (outer == outer_ || std::equal(outer_, outer_ + rows_ + 1, outer)) &&
                           (inner == inner_ || std::equal(inner_, inner_ + outer_[rows_], inner));
  if (!samePattern)
    throw InvalidInputError(
        "SparseSum: the matrices have different sparsity patterns; form the sum instead");
  xScale_ = xScale;
  yScale_ = yScale;
  y_ = values;
}

Eigen::SparseMatrix<double> SparseSum::toMatrix() const {
  Eigen::SparseMatrix<double> m(rows_, rows_);
  m.resizeNonZeros(nonZeros());
  std::copy(outer_, outer_ + rows_ + 1, m.outerIndexPtr());
  std::copy(inner_, inner_ + nonZeros(), m.innerIndexPtr());
  for (Eigen::Index e = 0; e < nonZeros(); ++e) m.valuePtr()[e] = value(e);
  return m;
}

}  // namespace texgrad
