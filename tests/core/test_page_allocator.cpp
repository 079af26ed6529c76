// Core tests: PageAllocator gives large blocks pages of their own and returns them to the
// system when freed, and a PageVector keeps its values as std::vector does.
#include <gtest/gtest.h>

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

#if defined(__linux__)

namespace {

/// Bytes of a base page.
size_t pageBytes() {
  return static_cast<size_t>(sysconf(_SC_PAGESIZE));
}

/// Number of the base pages of [block, block + bytes) that are mapped in this process (mincore
/// succeeds on a page exactly when it is mapped).
size_t mappedPages(const void* block, size_t bytes) {
  const size_t page = pageBytes();
  const auto begin = reinterpret_cast<uintptr_t>(block) / page * page;
  const auto end = reinterpret_cast<uintptr_t>(block) + bytes;
  size_t mapped = 0;
  unsigned char resident = 0;
  for (uintptr_t p = begin; p < end; p += page)
    mapped += mincore(reinterpret_cast<void*>(p), page, &resident) == 0;
  return mapped;
}

}  // namespace

#endif

TEST(PageAllocator, VectorsKeepTheirValuesAcrossTheThresholdAsStdVectorDoes) {
  const size_t large = kOwnPagesMinBytes / sizeof(int64_t) * 3 + 5;  // 3 mapped blocks and more
  PageVector<int64_t> grown;
  std::vector<int64_t> reference;
  for (size_t k = 0; k < large; ++k) {  // reallocates from the heap into mapped blocks
    grown.push_back(static_cast<int64_t>(k * k));
    reference.push_back(static_cast<int64_t>(k * k));
  }
  EXPECT_TRUE(std::equal(grown.begin(), grown.end(), reference.begin(), reference.end()));
  if (detail::ownPagesAvailable()) {  // the last reallocation took the mapped path
    EXPECT_EQ(reinterpret_cast<uintptr_t>(grown.data()) % kOwnPagesMinBytes, 0u);
  }
  const PageVector<double> filled(large, 0.25);
  EXPECT_EQ(std::accumulate(filled.begin(), filled.end(), 0.0), 0.25 * static_cast<double>(large));
  const PageVector<int32_t> zeros(large);  // value-initialised, as std::vector's
  EXPECT_EQ(std::count(zeros.begin(), zeros.end(), 0), static_cast<std::ptrdiff_t>(large));
}

#if defined(__linux__)

TEST(PageAllocator, LargeBlocksAreAlignedAndReturnedToTheSystemWhenFreed) {
  if (!detail::ownPagesAvailable()) GTEST_SKIP() << "every block comes from the heap here";
  PageAllocator<double> allocator;
  const size_t count = kOwnPagesMinBytes / sizeof(double) * 5 + 7;  // not a whole huge page
  const size_t bytes = count * sizeof(double);
  const size_t pages = (bytes + pageBytes() - 1) / pageBytes();
  double* block = allocator.allocate(count);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(block) % kOwnPagesMinBytes, 0u);
  std::fill_n(block, count, 1.0);
  ASSERT_EQ(mappedPages(block, bytes), pages);
  allocator.deallocate(block, count);
  // Gone from the process, every page of it: nothing stays resident.
  EXPECT_EQ(mappedPages(block, bytes), 0u);
}

#endif
