// Core: glibc malloc tuning for large, repeatedly allocated buffers (see the header).
#include "texgrad/core/heap_reuse.h"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>

#include "texgrad/core/page_allocator.h"

#if defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace texgrad {
namespace {

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
/// True if the kernel refuses to overcommit (vm.overcommit_memory = 2): there, a heap reserve
/// would be charged in full against the commit limit.
bool strictOvercommit() {
  std::ifstream in("/proc/sys/vm/overcommit_memory");
  int mode = 0;
  return (in >> mode) && mode == 2;
}

/// Grows the heap by half the physical memory at once (address space only: no page is touched)
/// and marks that range for transparent huge pages, then frees it to the heap's top, where the
/// next allocations are carved from. A first touch then faults a 2 MB page instead of 512 4 KB
/// pages. The kernel does not carry the mark over to later growth of the heap, hence the
/// reserve; allocations beyond it get ordinary pages.
void reserveHugePageHeap() {
  if (strictOvercommit()) return;
  const long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || pageSize <= 0) return;
  const size_t bytes = static_cast<size_t>(pages) * static_cast<size_t>(pageSize) / 2;
  void* block = std::malloc(bytes);
  if (!block) return;
  const uintptr_t begin =
      (reinterpret_cast<uintptr_t>(block) + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(block) + bytes) & ~(kHugePageBytes - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
  std::free(block);
}
#endif

}  // namespace

bool reuseFreedMemory() {
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  // M_MMAP_MAX = 0: no block gets its own mapping; M_TRIM_THRESHOLD = -1 (SIZE_MAX inside glibc):
  // the heap top is never handed back to the system; M_ARENA_MAX = 1: worker threads allocate
  // from the same heap, so memory one thread frees is reused by all (a per-thread arena keeps
  // its freed pages resident but out of the other threads' reach). mallopt returns 1 on success.
  if (mallopt(M_MMAP_MAX, 0) != 1 || mallopt(M_TRIM_THRESHOLD, -1) != 1 ||
      mallopt(M_ARENA_MAX, 1) != 1)
    return false;
  reserveHugePageHeap();
  return true;
#else
  return false;
#endif
}

}  // namespace texgrad
