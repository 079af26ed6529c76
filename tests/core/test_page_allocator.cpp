// Core tests: PageAllocator gives large blocks pages of their own and returns them to the
// system when freed, and a PageVector keeps its values as std::vector does; a PageArray's pages
// become resident as they are written; discarded pages stop being resident.
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

/// Number of the base pages of [block, block + bytes) that are resident (mincore).
size_t residentPages(const void* block, size_t bytes) {
  const size_t page = pageBytes();
  const auto begin = reinterpret_cast<uintptr_t>(block) / page * page;
  const auto end = reinterpret_cast<uintptr_t>(block) + bytes;
  std::vector<unsigned char> resident((end - begin + page - 1) / page);
  if (mincore(reinterpret_cast<void*>(begin), end - begin, resident.data()) != 0) return 0;
  return static_cast<size_t>(std::count_if(resident.begin(), resident.end(),
                                           [](unsigned char r) { return (r & 1) != 0; }));
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

TEST(PageAllocator, ArraysBecomeResidentAsTheyAreWritten) {
  if (!detail::ownPagesAvailable()) GTEST_SKIP() << "every block comes from the heap here";
  const size_t count = kOwnPagesMinBytes / sizeof(float) * 16;  // 32 MB
  PageArray<float> array(count);
  ASSERT_EQ(array.size(), count);
  EXPECT_EQ(residentPages(array.data(), array.bytes()), 0u) << "nothing written yet";
  std::fill_n(array.data(), count / 4, 1.0f);
  // The written quarter, rounded up to a huge page, and no more.
  const size_t quarter = array.bytes() / 4 / pageBytes();
  EXPECT_GE(residentPages(array.data(), array.bytes()), quarter);
  EXPECT_LE(residentPages(array.data(), array.bytes()), quarter + kHugePageBytes / pageBytes());
  const PageArray<float> moved = std::move(array);
  EXPECT_EQ(moved.data()[count / 4 - 1], 1.0f);
  PageArray<float> heap(count, false);  // from the heap: written at once, freed as heap
  std::fill_n(heap.data(), count, 2.0f);
  heap = PageArray<float>();
  EXPECT_EQ(heap.size(), 0u);
}

TEST(PageAllocator, ZeroArraysReadZeroOnTheirOwnPagesAndOnTheHeap) {
  // A mapped block is zero already and stays unresident until written; a heap block is written.
  for (const size_t count : {size_t(3), kOwnPagesMinBytes / sizeof(float) * 2})
    for (const bool ownPages : {true, false}) {
      {  // leave a freed heap block of the size behind, with nonzero values
        PageArray<float> dirty(count, false);
        std::fill_n(dirty.data(), count, 7.0f);
      }
      const PageArray<float> zeros = PageArray<float>::zeros(count, ownPages);
      ASSERT_EQ(zeros.size(), count);
      const auto isZero = [](float v) { return v == 0.0f; };
      EXPECT_TRUE(std::all_of(zeros.data(), zeros.data() + count, isZero))
          << count << " values, own pages " << ownPages;
    }
}

TEST(PageAllocator, DiscardedPagesOfAHeapBlockStopBeingResidentAndReadZero) {
  if (!detail::ownPagesAvailable()) GTEST_SKIP() << "discarding does nothing here";
  // 64 KB: below glibc's mmap threshold (128 KB at least), so a block of the heap proper.
  std::vector<double> values(8192, 2.0);
  const size_t bytes = values.size() * sizeof(double);
  const size_t before = residentPages(values.data(), bytes);
  ASSERT_EQ(before, mappedPages(values.data(), bytes)) << "all written, all resident";
  // The first half less a few bytes: every whole page inside it goes, the partial ones stay.
  const size_t half = values.size() / 2 - 3;
  detail::discardWholePages(values.data(), half * sizeof(double));
  const size_t dropped = before - residentPages(values.data(), bytes);
  EXPECT_GE(dropped, half * sizeof(double) / pageBytes() - 1);
  EXPECT_LE(dropped, half * sizeof(double) / pageBytes());
  const size_t firstWhole =
      ((reinterpret_cast<uintptr_t>(values.data()) + pageBytes() - 1) / pageBytes() * pageBytes() -
       reinterpret_cast<uintptr_t>(values.data())) / sizeof(double);
  EXPECT_EQ(values[firstWhole], 0.0) << "a dropped page reads as zero";
  EXPECT_EQ(values[half], 2.0) << "past the range: kept";
  EXPECT_EQ(values.back(), 2.0);
}

#endif
