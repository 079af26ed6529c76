// Test and benchmark support: every test and benchmark program allocates as the CLI does
// (texgrad::reuseFreedMemory), which also keeps the Release suite's run time down on VMs.
#include "texgrad/core/heap_reuse.h"

namespace {
[[maybe_unused]] const bool kHeapReuse = texgrad::reuseFreedMemory();
}  // namespace
