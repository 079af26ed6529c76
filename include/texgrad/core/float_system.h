// Core: a symmetric sparse system held as float V-cycles read it, about 8 bytes per entry where a
// double matrix takes 12, so that a one-shot caller's A never exists in double (docs/memory.md).
#pragma once

#include <bit>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace texgrad {

/// A symmetric sparse matrix A as float multigrid cycles read it (docs/memory.md): its
/// compressed-column pattern; each entry rounded once to float, but those in the row or column
/// of an exact unknown (a caller's choice: the texels without a regular interior stencil) kept in
/// double as well; and each row's sum formed in double from the unrounded entries, then rounded.
/// The interior stencils a multigrid builds are float anyway, and their diagonals come from the
/// row sums, which keep the small screening part (alpha M 1, S 1 = 0) a nearly singular A hinges
/// on; the rows of texels without a regular stencil, solved directly, need their entries exact
/// (a sliver's block is only just positive definite), while a rounded row solved directly (one
/// near a weak row) takes its diagonal from its row sum.
class FloatSystem {
 public:
  FloatSystem() = default;
  /// A system of `rows` unknowns on a pattern (outer: rows + 1 column starts; inner: the row of
  /// each entry, ascending in each column) whose arrays become the system's (keepPatternAlive
  /// hands over what holds them: a set-up that takes the system drops their pages), all entries
  /// and row sums zero; exactUnknown (one per row) marks the exact unknowns. Throws
  /// InvalidInputError if the sizes disagree.
  FloatSystem(int rows, int* outer, int* inner, std::span<const uint8_t> exactUnknown);
  /// Takes `other` over, leaving it empty.
  FloatSystem(FloatSystem&& other) noexcept { *this = std::move(other); }
  /// Takes `other` over, leaving it empty.
  FloatSystem& operator=(FloatSystem&& other) noexcept;
  FloatSystem(const FloatSystem&) = delete;
  FloatSystem& operator=(const FloatSystem&) = delete;
  ~FloatSystem() = default;

  /// Makes this system own whatever holds its pattern's arrays.
  void keepPatternAlive(std::shared_ptr<void> owner) { owner_ = std::move(owner); }
  /// Sets entry e (in the pattern's order) to `value`: rounded, and exact too if exact(e).
  /// Different entries may be set concurrently.
  void set(int64_t e, double value) {
    values_[static_cast<size_t>(e)] = static_cast<float>(value);
    if (exact(e)) exactValues_[rankOf(e)] = value;
  }
  /// Sets row u's sum (of the unrounded entries), rounded to float.
  void setRowSum(int u, double sum) { rowSums_[static_cast<size_t>(u)] = static_cast<float>(sum); }
  /// Sets column u's entries to `values` (its length; set) and its row sum (the symmetric A's
  /// row u) to their sum in column order, as the multigrid sums a row. Different columns may be
  /// set concurrently.
  void setColumn(int u, std::span<const double> values) {
    double sum = 0.0;
    for (size_t k = 0; k < values.size(); ++k) {
      set(outer_[u] + static_cast<int64_t>(k), values[k]);
      sum += values[k];
    }
    setRowSum(u, sum);
  }

  /// Rows (= columns).
  int rows() const { return rows_; }
  /// Stored entries.
  int64_t nonZeros() const { return rows_ == 0 ? 0 : outer_[rows_]; }
  /// Column starts (rows() + 1), as Eigen's outerIndexPtr() (a single 0 for an empty system).
  const int* outer() const { return outer_ ? outer_ : &kNoEntries; }
  /// Row of each entry, as Eigen's innerIndexPtr().
  const int* inner() const { return inner_; }
  /// True if entry e is held in double (its row or its column is an exact unknown's).
  bool exact(int64_t e) const {
    return (marks_[static_cast<size_t>(e >> 6)] >> (e & 63)) & 1u;
  }
  /// Entry e: exact if exact(e), else rounded to float.
  double value(int64_t e) const {
    if (exact(e)) return exactValues_[rankOf(e)];
    return static_cast<double>(values_[static_cast<size_t>(e)]);
  }
  /// Each row's sum of the unrounded entries, rounded to float.
  std::span<const float> rowSums() const { return rowSums_; }
  /// Entries held in double.
  int64_t exactCount() const { return static_cast<int64_t>(exactValues_.size()); }
  /// Lets the system drop the pages of the row indices and rounded values of the columns before
  /// `column`, for a last reader done with them (detail::discardWholePages): they stop being
  /// resident and read as zero. The exact entries stay.
  void discardColumnsBefore(int column);
  /// Bytes held: the pattern's two index arrays, the values, the exact entries with their marks,
  /// and the row sums.
  int64_t storageBytes() const;

 private:
  /// Index of exact entry e among the exact entries.
  size_t rankOf(int64_t e) const {
    const auto word = static_cast<size_t>(e >> 6);
    const uint64_t below = marks_[word] & ((uint64_t{1} << (e & 63)) - 1);
    return rankBefore_[word] + static_cast<size_t>(std::popcount(below));
  }

  static constexpr int kNoEntries = 0;  ///< the column starts of an empty system
  int rows_ = 0;
  int* outer_ = nullptr;
  int* inner_ = nullptr;
  std::shared_ptr<void> owner_;  ///< keeps outer_ and inner_ alive
  std::vector<float> values_;
  std::vector<float> rowSums_;
  std::vector<uint64_t> marks_;       ///< bit e: entry e is exact
  std::vector<uint32_t> rankBefore_;  ///< per word of marks_: exact entries in the words before
  std::vector<double> exactValues_;   ///< the exact entries, in the pattern's order
};

}  // namespace texgrad
