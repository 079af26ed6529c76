// Core tests: PageAllocator gives large blocks pages of their own and returns them to the
// system when freed, and a PageVector keeps its values as std::vector does.
#include <gtest/gtest.h>

#include <cerrno>
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

#include "texgrad/core/page_allocator.h"

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

using namespace texgrad;

namespace {

/// True if every page of [block, block + bytes) is mapped in this process (mincore succeeds).
bool mapped(const void* block, size_t bytes) {
#if defined(__linux__)
  const auto page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
  const auto begin = reinterpret_cast<uintptr_t>(block) & ~(page - 1);
  std::vector<unsigned char> residency((bytes + 2 * page) / page);
  return mincore(reinterpret_cast<void*>(begin), bytes, residency.data()) == 0 || errno != ENOMEM;
#else
  (void)block, (void)bytes;
  return true;
#endif
}

}  // namespace

TEST(PageAllocator, VectorsKeepTheirValuesAcrossTheThresholdAsStdVectorDoes) {
  const size_t large = kOwnPagesMinBytes / sizeof(int64_t) * 3 + 5;  // 3 mapped blocks and more
  PageVector<int64_t> grown;
  std::vector<int64_t> reference;
  for (size_t k = 0; k < large; ++k) {  // reallocates from the heap into mapped blocks
    grown.push_back(static_cast<int64_t>(k * k));
    reference.push_back(static_cast<int64_t>(k * k));
  }
  EXPECT_TRUE(std::equal(grown.begin(), grown.end(), reference.begin(), reference.end()));
  PageVector<double> filled(large, 0.25);  // value-initialised like std::vector
  EXPECT_EQ(std::accumulate(filled.begin(), filled.end(), 0.0), 0.25 * static_cast<double>(large));
  PageVector<int32_t> zeros(large);
  EXPECT_EQ(std::count(zeros.begin(), zeros.end(), 0), static_cast<std::ptrdiff_t>(large));
}

TEST(PageAllocator, LargeBlocksAreAlignedAndReturnedToTheSystemWhenFreed) {
  if (!ownPagesAvailable()) GTEST_SKIP() << "large blocks come from the heap on this build";
  PageAllocator<double> allocator;
  const size_t count = kOwnPagesMinBytes / sizeof(double) * 5 + 7;  // not a whole huge page
  const size_t bytes = count * sizeof(double);
  double* block = allocator.allocate(count);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(block) % kOwnPagesMinBytes, 0u);
  std::fill_n(block, count, 1.0);
  ASSERT_TRUE(mapped(block, bytes));
  allocator.deallocate(block, count);
  // Gone from the process, pages and address range: nothing of it stays resident.
  EXPECT_FALSE(mapped(block, bytes));
}
