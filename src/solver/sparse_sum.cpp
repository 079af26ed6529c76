// Solver module: checks of the view's operands, the bits of an added in-pattern matrix, and the
// conversion to a matrix.
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

void SparseSum::addInPattern(const Eigen::SparseMatrix<double>& z) {
  if (z.rows() != rows_ || z.cols() != rows_)
    throw InvalidInputError("SparseSum: the added matrix is " + std::to_string(z.rows()) + " x " +
                            std::to_string(z.cols()) + "; expected " + std::to_string(rows_) +
                            " x " + std::to_string(rows_));
  if (z.nonZeros() == 0) return;  // value() then reads X and Y only
  marks_.assign(static_cast<size_t>((nonZeros() + kWordBits - 1) / kWordBits), 0);
  addend_.reserve(static_cast<size_t>(z.nonZeros()));
  // Column by column and row by row within a column: the entries come in pattern order, which
  // value() relies on (a hand-made uncompressed Z might not keep it: refused).
  int64_t previous = -1;
  for (Eigen::Index j = 0; j < z.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(z, j); it; ++it) {
      const int* first = inner_ + outer_[j];
      const int* last = inner_ + outer_[j + 1];
      const int* found = std::lower_bound(first, last, static_cast<int>(it.row()));
      if (found == last || *found != it.row())
        throw InvalidInputError("SparseSum: the added matrix has entry (" +
                                std::to_string(it.row()) + ", " + std::to_string(j) +
                                "), outside the pattern; form the sum instead");
      const int64_t e = found - inner_;
      if (e <= previous)
        throw InvalidInputError(
            "SparseSum: the added matrix's rows are not in increasing order "
            "in column " +
            std::to_string(j) + "; call makeCompressed()");
      previous = e;
      marks_[static_cast<size_t>(e / kWordBits)] |= uint64_t{1} << (e % kWordBits);
      addend_.push_back(it.value());
    }
  rankBefore_.resize(marks_.size());
  uint32_t marked = 0;
  for (size_t w = 0; w < marks_.size(); ++w) {
    rankBefore_[w] = marked;
    marked += static_cast<uint32_t>(std::popcount(marks_[w]));
  }
}

Eigen::SparseMatrix<double> SparseSum::toMatrix() const {
  Eigen::SparseMatrix<double> m(rows_, rows_);
  m.resizeNonZeros(nonZeros());
  std::copy(outer_, outer_ + rows_ + 1, m.outerIndexPtr());
  std::copy(inner_, inner_ + nonZeros(), m.innerIndexPtr());
  for (Eigen::Index e = 0; e < nonZeros(); ++e) m.valuePtr()[e] = value(e);
  return m;
}

double SparseSum::diagonalFromRowSum(int u, double rowSum) const {
  double others = 0.0;
  for (int e = outer()[u]; e != outer()[u + 1]; ++e)
    if (inner()[e] != u) others += value(e);
  return rowSum - others;
}

Eigen::SparseMatrix<double> formedMatrix(const FloatSystem& a) {
  const SparseSum sum(a);
  Eigen::SparseMatrix<double> m = sum.toMatrix();
  const std::span<const float> rowSums = a.rowSums();
  for (int u = 0; u < m.outerSize(); ++u)
    for (int e = m.outerIndexPtr()[u]; e < m.outerIndexPtr()[u + 1]; ++e)
      if (m.innerIndexPtr()[e] == u && sum.rounded(e))
        m.valuePtr()[e] = sum.diagonalFromRowSum(u, rowSums[static_cast<size_t>(u)]);
  return m;
}

}  // namespace texgrad
