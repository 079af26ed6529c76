// Core: anonymous mappings for PageAllocator (see the header).
#include "texgrad/core/page_allocator.h"

#include <cstdint>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

#if defined(__SANITIZE_ADDRESS__)
#define TEXGRAD_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TEXGRAD_ASAN 1
#endif
#endif

namespace texgrad::detail {

#if defined(__linux__) && !defined(TEXGRAD_ASAN)

namespace {

/// Length of the mapping of a block of `bytes`: whole base pages. Not whole huge pages: the last
/// part of a huge page would be faulted in whole (up to 2 MB more resident per block).
std::size_t mappedLength(std::size_t bytes) {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  return (bytes + page - 1) / page * page;
}

}  // namespace

bool ownPagesAvailable() {
  return true;
}

void* mapOwnPages(std::size_t bytes) {
  if (bytes > SIZE_MAX / 2) throw std::bad_alloc();
  // Mapped a huge page longer than needed, then trimmed at both ends so that the block starts on
  // a huge-page boundary and each of its whole 2 MB can be one huge page.
  const std::size_t length = mappedLength(bytes);
  const std::size_t over = length + kOwnPagesMinBytes;
  void* raw = mmap(nullptr, over, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) throw std::bad_alloc();
  const auto begin = reinterpret_cast<uintptr_t>(raw);
  const uintptr_t aligned = (begin + kOwnPagesMinBytes - 1) & ~(kOwnPagesMinBytes - 1);
  if (aligned > begin) munmap(raw, aligned - begin);
  const uintptr_t end = begin + over;
  if (end > aligned + length)
    munmap(reinterpret_cast<void*>(aligned + length), end - aligned - length);
  auto* block = reinterpret_cast<void*>(aligned);
  madvise(block, length, MADV_HUGEPAGE);  // advice only: ignored where huge pages are off
  return block;
}

void unmapOwnPages(void* block, std::size_t bytes) noexcept {
  munmap(block, mappedLength(bytes));
}

void discardWholePages(void* begin, std::size_t bytes) noexcept {
  const auto page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
  const auto first = (reinterpret_cast<uintptr_t>(begin) + page - 1) / page * page;
  const uintptr_t end = (reinterpret_cast<uintptr_t>(begin) + bytes) / page * page;
  // Advice the kernel always takes for private anonymous memory: the pages are freed now and
  // come back zero-filled. Heap blocks are such memory too; glibc keeps no data inside a block
  // in use, so a block whose pages were dropped can still be freed and reused.
  if (end > first) madvise(reinterpret_cast<void*>(first), end - first, MADV_DONTNEED);
}

#else

bool ownPagesAvailable() {
  return false;
}

void* mapOwnPages(std::size_t) {
  throw std::bad_alloc();  // never called: ownPagesAvailable() is false
}

void unmapOwnPages(void*, std::size_t) noexcept {}

void discardWholePages(void*, std::size_t) noexcept {}

#endif

}  // namespace texgrad::detail
