// Solver module: a read-only view of a x X + y Y (+ Z) for sparse matrices of one pattern, so
// that the screened systems alpha M + S (paper §5) reach the multigrid set-up without being formed;
// or of a FloatSystem's entries.
#pragma once

#include <Eigen/SparseCore>

#include <bit>
#include <cstdint>
#include <vector>

#include "texgrad/core/float_system.h"

namespace texgrad {

/// The square matrix xScale X + yScale Y (+ Z), where X and Y are compressed column-major matrices
/// with one sparsity pattern (equal index arrays), read entry by entry and never stored, and Z, if
/// given, has its entries within that pattern (a correction on a few texels, such as the geodesic
/// distance system's ghost penalty). A single matrix converts implicitly (Y absent). Holds
/// pointers: X and Y must outlive the view; Z's entries are copied.
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
  /// View of (xScale X + yScale Y) + Z, entry for entry the values of forming the sum and then
  /// adding Z's stored entries to it. Z is held as a bit and a share of a rank per entry of the
  /// pattern (3/16 byte, copied with the view) and its own values, where a formed sum takes 8
  /// bytes per entry. Throws InvalidInputError as the two-matrix view does, or if Z is of another
  /// size, has an entry outside the pattern or its rows out of order in a column.
  template <typename X, typename Y>
  SparseSum(double xScale, const X& x, double yScale, const Y& y,
            const Eigen::SparseMatrix<double>& z)
      : SparseSum(xScale, x, yScale, y) {
    addInPattern(z);
  }

  /// View of a FloatSystem's entries (FloatSystem::value; its row sums are the system's own).
  explicit SparseSum(const FloatSystem& a)
      : rows_(a.rows()), outer_(a.outer()), inner_(a.inner()), floatSystem_(&a) {}

  /// Rows (= columns).
  Eigen::Index rows() const { return rows_; }
  /// Stored entries of the shared pattern.
  Eigen::Index nonZeros() const { return outer_[rows_]; }
  /// Column starts (size rows() + 1), as Eigen's outerIndexPtr().
  const int* outer() const { return outer_; }
  /// Row of each entry, as Eigen's innerIndexPtr().
  const int* inner() const { return inner_; }
  /// Value of entry e of the pattern.
  double value(Eigen::Index e) const {
    if (floatSystem_) return floatSystem_->value(e);  // one matrix, no Z
    const double sum = y_ ? xScale_ * x_[e] + yScale_ * y_[e] : x_[e];
    if (marks_.empty()) return sum;
    const auto word = static_cast<size_t>(e / kWordBits);
    const auto bit = static_cast<int>(e % kWordBits);
    if (!((marks_[word] >> bit) & 1u)) return sum;
    // Z's values are stored in pattern order: this entry's rank among the marked ones.
    const uint64_t below = marks_[word] & ((uint64_t{1} << bit) - 1);
    return sum + addend_[rankBefore_[word] + static_cast<size_t>(std::popcount(below))];
  }
  /// True if entry e is a FloatSystem's entry rounded to float (not one it keeps exact).
  bool rounded(Eigen::Index e) const { return floatSystem_ && !floatSystem_->exact(e); }
  /// The diagonal of column u that makes its entries sum to `rowSum`: rowSum minus its other
  /// entries, summed in column order (a rounded diagonal of a FloatSystem's row).
  double diagonalFromRowSum(int u, double rowSum) const;
  /// The sum as a matrix (for the direct solver of a one-level hierarchy).
  Eigen::SparseMatrix<double> toMatrix() const;

 private:
  SparseSum(bool compressed, Eigen::Index rows, Eigen::Index cols, const int* outer,
            const int* inner, const double* values);
  void addSecond(double xScale, double yScale, bool compressed, Eigen::Index rows,
                 Eigen::Index cols, const int* outer, const int* inner, const double* values);
  /// Marks Z's entries in the pattern and keeps their values (the three-operand constructor).
  void addInPattern(const Eigen::SparseMatrix<double>& z);

  Eigen::Index rows_ = 0;
  const int* outer_ = nullptr;
  const int* inner_ = nullptr;
  const double* x_ = nullptr;
  const double* y_ = nullptr;  ///< null for a single matrix
  const FloatSystem* floatSystem_ = nullptr;  ///< the viewed FloatSystem (x_ and y_ null)
  static constexpr int kWordBits = 64;  ///< entries per word of marks_
  double xScale_ = 1.0, yScale_ = 0.0;
  std::vector<uint64_t> marks_;       ///< bit e: Z has entry e of the pattern (empty: no entry)
  std::vector<uint32_t> rankBefore_;  ///< per word of marks_: marked entries in the words before
  std::vector<double> addend_;        ///< Z's values, in pattern order
};

/// The matrix a FloatSystem holds, in double: its entries (FloatSystem::value), each rounded
/// diagonal set to its row's sum minus the row's other entries (so each such row keeps its sum,
/// as the multigrid's boundary rows do: MultigridSolver::initAndUpdate(FloatSystem&&)).
Eigen::SparseMatrix<double> formedMatrix(const FloatSystem& a);

}  // namespace texgrad
