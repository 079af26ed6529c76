// Core: a FloatSystem's exact entries, checks and page release.
#include "texgrad/core/float_system.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>
#include <utility>

#include "texgrad/core/error.h"
#include "texgrad/core/page_allocator.h"
#include "texgrad/core/storage_bytes.h"

namespace texgrad {

FloatSystem::FloatSystem(int rows, int* outer, int* inner, std::span<const uint8_t> exactUnknown)
    : rows_(rows), outer_(outer), inner_(inner) {
  if (rows < 0 || (rows > 0 && (!outer || !inner)))
    throw InvalidInputError("FloatSystem: no pattern for " + std::to_string(rows) + " rows");
  if (exactUnknown.size() != static_cast<size_t>(rows))
    throw InvalidInputError("FloatSystem: " + std::to_string(exactUnknown.size()) +
                            " exact-unknown flags for " + std::to_string(rows) + " rows");
  // Fewer than 2^31 entries (int column starts), so their ranks fit marks_'s uint32 counts.
  const auto entries = static_cast<size_t>(nonZeros());
  values_.assign(entries, 0.0F);
  rowSums_.assign(static_cast<size_t>(rows), 0.0F);
  marks_.assign((entries + 63) / 64, 0);
  // Word by word on all cores, each word's entries walked from the column of its first one.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, marks_.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& words) {
    const auto first = static_cast<int>(words.begin() * 64);
    const auto end = static_cast<int>(std::min(entries, words.end() * 64));
    int u = static_cast<int>(std::upper_bound(outer, outer + rows + 1, first) - outer) - 1;
    for (int e = first; e < end; ++e) {
      while (e >= outer[u + 1]) ++u;
      if (exactUnknown[static_cast<size_t>(u)] || exactUnknown[static_cast<size_t>(inner[e])])
        marks_[static_cast<size_t>(e) >> 6] |= uint64_t{1} << (e & 63);
    }
  });
  rankBefore_.resize(marks_.size());
  uint32_t marked = 0;
  for (size_t w = 0; w < marks_.size(); ++w) {
    rankBefore_[w] = marked;
    marked += static_cast<uint32_t>(std::popcount(marks_[w]));
  }
  exactValues_.assign(marked, 0.0);
}

FloatSystem& FloatSystem::operator=(FloatSystem&& other) noexcept {
  if (this == &other) return *this;
  rows_ = std::exchange(other.rows_, 0);
  outer_ = std::exchange(other.outer_, nullptr);
  inner_ = std::exchange(other.inner_, nullptr);
  owner_ = std::move(other.owner_);
  values_ = std::move(other.values_);
  rowSums_ = std::move(other.rowSums_);
  marks_ = std::move(other.marks_);
  rankBefore_ = std::move(other.rankBefore_);
  exactValues_ = std::move(other.exactValues_);
  return *this;
}

void FloatSystem::discardColumnsBefore(int column) {
  const auto end = static_cast<size_t>(outer_[column]);
  detail::discardWholePages(values_.data(), end * sizeof(float));
  detail::discardWholePages(inner_, end * sizeof(int));
}

int64_t FloatSystem::storageBytes() const {
  return (rows_ + 1 + nonZeros()) * int64_t(sizeof(int)) +
         capacityBytes(values_, rowSums_, marks_, rankBefore_, exactValues_);
}

}  // namespace texgrad
