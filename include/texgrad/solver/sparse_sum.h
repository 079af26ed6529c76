// Solver module: a read-only view of a x X + y Y for two sparse matrices of one pattern, so that
// the screened systems alpha M + S (paper §5) reach the multigrid set-up without being formed.
#pragma once

#include <Eigen/SparseCore>

namespace texgrad {

/// The square matrix xScale X + yScale Y, where X and Y are compressed column-major matrices with
/// one sparsity pattern (equal index arrays), read entry by entry and never stored. A single
/// matrix converts implicitly (Y absent). Holds pointers: X and Y must outlive the view.
class SparseSum {
 public:
  /// View of one compressed matrix. Throws InvalidInputError if `x` is not compressed.
  SparseSum(const Eigen::SparseMatrix<double>& x)  // NOLINT(google-explicit-constructor)
      : SparseSum(x.isCompressed(), x.rows(), x.cols(), x.outerIndexPtr(), x.innerIndexPtr(),
                  x.valuePtr()) {}
  /// View of xScale X + yScale Y for SparseMatrix<double> or Map<const SparseMatrix<double>>
  /// operands. Throws InvalidInputError unless both are compressed, square, of one size and
  /// have the same pattern.
  template <typename X, typename Y>
  SparseSum(double xScale, const X& x, double yScale, const Y& y)
      : SparseSum(x.isCompressed(), x.rows(), x.cols(), x.outerIndexPtr(), x.innerIndexPtr(),
                  x.valuePtr()) {
    static_assert(!X::IsRowMajor && !Y::IsRowMajor, "SparseSum reads column-major matrices");
    addSecond(xScale, yScale, y.isCompressed(), y.rows(), y.cols(), y.outerIndexPtr(),
              y.innerIndexPtr(), y.valuePtr());
  }

  /// Rows (= columns).
  Eigen::Index rows() const { return rows_; }
  /// Stored entries of the shared pattern.
  Eigen::Index nonZeros() const { return outer_[rows_]; }
  /// Column starts (size rows() + 1), as Eigen's outerIndexPtr().
  const int* outer() const { return outer_; }
  /// Row of each entry, as Eigen's innerIndexPtr().
  const int* inner() const { return inner_; }
  /// Value of entry e of the pattern.
  double value(Eigen::Index e) const { return y_ ? xScale_ * x_[e] + yScale_ * y_[e] : x_[e]; }
  /// The sum as a matrix (for the direct solver of a one-level hierarchy).
  Eigen::SparseMatrix<double> toMatrix() const;

 private:
  SparseSum(bool compressed, Eigen::Index rows, Eigen::Index cols, const int* outer,
            const int* inner, const double* values);
  void addSecond(double xScale, double yScale, bool compressed, Eigen::Index rows,
                 Eigen::Index cols, const int* outer, const int* inner, const double* values);

  Eigen::Index rows_ = 0;
  const int* outer_ = nullptr;
  const int* inner_ = nullptr;
  const double* x_ = nullptr;
  const double* y_ = nullptr;  ///< null for a single matrix
  double xScale_ = 1.0, yScale_ = 0.0;
};

}  // namespace texgrad
