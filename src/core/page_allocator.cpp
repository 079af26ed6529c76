// Core: anonymous mappings for PageAllocator (see the header).
#include "texgrad/core/page_allocator.h"

#include <cstdint>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#if defined(__SANITIZE_ADDRESS__)
#define TEXGRAD_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TEXGRAD_ASAN 1
#endif
#endif

namespace texgrad {
bool ownPagesAvailable() {
#if defined(__linux__) && !defined(TEXGRAD_ASAN)
  return true;
#else
  return false;
#endif
}

#if defined(__linux__) && !defined(TEXGRAD_ASAN)

namespace {

/// Length of the mapping of a block of `bytes`: whole huge pages.
std::size_t mappedLength(std::size_t bytes) {
  return (bytes + kOwnPagesMinBytes - 1) & ~(kOwnPagesMinBytes - 1);
}

}  // namespace

void* mapOwnPages(std::size_t bytes) {
  // Mapped a huge page longer than needed, then trimmed to a huge-page boundary at both ends,
  // so that every 2 MB of the block can be one huge page.
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

#else

void* mapOwnPages(std::size_t) {
  throw std::bad_alloc();  // never called: ownPagesAvailable() is false
}

void unmapOwnPages(void*, std::size_t) noexcept {}

#endif

}  // namespace texgrad
