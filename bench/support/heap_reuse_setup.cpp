// Benchmark support: every benchmark program allocates as the one-shot CLI commands do
// (texgrad::reuseFreedMemory at start-up), so timings match what `texgrad filter` etc. see.
#include "texgrad/core/heap_reuse.h"

namespace {
[[maybe_unused]] const bool kHeapReuse = texgrad::reuseFreedMemory();
}  // namespace
