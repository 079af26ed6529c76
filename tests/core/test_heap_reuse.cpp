// Core tests: the allocator setting programs opt into (reuseFreedMemory: the one-shot CLI
// commands and the benchmarks), and that test programs start with the C library's default.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "texgrad/core/heap_reuse.h"

using namespace texgrad;

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)

namespace {

/// The /proc/self/smaps entry of the mapping that contains `address` (empty if none).
std::string mappingOf(const void* address) {
  const auto a = reinterpret_cast<uintptr_t>(address);
  std::ifstream in("/proc/self/smaps");
  std::string line, entry;
  bool inside = false;
  while (std::getline(in, line)) {
    uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream head(line);
    // A mapping's first line: "begin-end perms offset dev inode [path]" in hexadecimal.
    if (head >> std::hex >> begin >> dash >> end && dash == '-' &&
        line.find(':') > line.find(' ')) {
      if (inside) return entry;
      inside = a >= begin && a < end;
      entry.clear();
    }
    if (inside) entry += line + "\n";
  }
  return inside ? entry : std::string();
}

/// The bracketed choice of a /sys/kernel/mm/transparent_hugepage setting ("" if unreadable).
std::string hugePageMode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string text;
  std::getline(in, text);
  const size_t open = text.find('['), close = text.find(']');
  return open < close && close != std::string::npos ? text.substr(open + 1, close - open - 1)
                                                     : std::string();
}

}  // namespace

TEST(HeapReuse, TestProgramsStartWithTheDefaultAllocator) {
  // A fresh run of this program ("threadsafe" death tests re-execute it and run this test
  // alone): no library code or static initializer has changed malloc, so a block far above
  // glibc's mapping threshold gets a mapping of its own, as in a library user's program.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        const size_t bytes = size_t(64) << 20;
        char* block = static_cast<char*>(std::malloc(bytes));
        const bool inHeap = mappingOf(block + bytes / 2).find("[heap]") != std::string::npos;
        std::free(block);
        std::exit(inHeap ? 1 : 0);
      },
      ::testing::ExitedWithCode(0), "");
}

TEST(HeapReuse, LargeBlocksComeFromTheHeapWithHugePages) {
  ASSERT_TRUE(reuseFreedMemory());  // a second call (the next test's) is harmless
  const std::string mode = hugePageMode();
  std::ifstream overcommit("/proc/sys/vm/overcommit_memory");
  int overcommitMode = 0;
  overcommit >> overcommitMode;
  const size_t bytes = size_t(64) << 20;  // far above glibc's usual mapping threshold
  char* block = static_cast<char*>(std::malloc(bytes));
  ASSERT_NE(block, nullptr);
  // Its middle: the block may begin in the heap's first, unmarked megabyte or two.
  const std::string mapping = mappingOf(block + bytes / 2);
  std::free(block);
  ASSERT_FALSE(mapping.empty());
  EXPECT_NE(mapping.find("[heap]"), std::string::npos) << "not served from the heap:\n"
                                                        << mapping;
  if (mode != "madvise" || overcommitMode == 2)
    GTEST_SKIP() << "transparent huge pages are '" << mode << "' and overcommit mode is "
                 << overcommitMode << ": the huge-page reserve applies to 'madvise' mode only";
  const size_t field = mapping.find("THPeligible:");
  ASSERT_NE(field, std::string::npos) << mapping;
  EXPECT_EQ(std::stoi(mapping.substr(field + 12)), 1)
      << "the heap block is not marked for transparent huge pages:\n"
      << mapping;
}

TEST(HeapReuse, WorkerThreadsAllocateFromTheSameHeap) {
  ASSERT_TRUE(reuseFreedMemory());
  // A block freed by one thread must be reusable by all: a worker's block comes from the
  // process heap, not from a per-thread arena (an anonymous mapping of its own).
  void* block = nullptr;
  std::thread worker([&] { block = std::malloc(size_t(1) << 20); });
  worker.join();
  ASSERT_NE(block, nullptr);
  const std::string mapping = mappingOf(block);
  std::free(block);
  EXPECT_NE(mapping.find("[heap]"), std::string::npos) << "a worker thread's block is not in "
                                                        << "the heap:\n"
                                                        << mapping;
}

#else

TEST(HeapReuse, ChangesNothingWithoutGlibcMalloc) {
  EXPECT_FALSE(reuseFreedMemory());
}

#endif
