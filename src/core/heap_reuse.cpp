// Core: glibc malloc tuning for large, repeatedly allocated buffers (see the header).
#include "texgrad/core/heap_reuse.h"

#include <climits>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace texgrad {

bool reuseFreedMemory() {
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  // M_MMAP_MAX = 0: no block gets its own mapping; M_TRIM_THRESHOLD = INT_MAX: the heap top is
  // never handed back to the system (mallopt returns 1 on success).
  return mallopt(M_MMAP_MAX, 0) == 1 && mallopt(M_TRIM_THRESHOLD, INT_MAX) == 1;
#else
  return false;
#endif
}

}  // namespace texgrad
