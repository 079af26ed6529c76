// Core: a process-wide allocator setting for programs that run texgrad's large set-ups and solves.
#pragma once

namespace texgrad {

/// Asks the C library's malloc (glibc) to serve every block from its heap and to keep freed
/// memory for reuse, instead of mapping each large block (texel vectors, sparse products: tens of
/// megabytes, allocated and freed many times per set-up) afresh and unmapping it when freed.
/// Every first touch of a fresh mapping is a page fault, which is costly on virtual machines:
/// operator assembly of spot at 2048^2 went from 5.1 s to 1.1 s on the project's 2-core VM.
/// The heap also reserves half the physical memory as address space marked for transparent huge
/// pages (where the kernel leaves that choice to programs: 'madvise' mode), so a first touch
/// faults a 2 MB page instead of 512 small ones: spot at 2048^2 is ready to cycle (read,
/// operators, multigrid set-up) in 3.4-3.9 s instead of 4.6-5.6 s there (interleaved runs).
/// All threads share that heap (one malloc arena), so what a worker frees, any thread reuses.
/// Freed memory is not returned to the system before exit. A process-wide setting that a
/// program opts into: the library never calls it. Call once at start-up of a program that runs
/// one job and exits (the one-shot CLI commands and the benchmarks do; `texgrad view`, which
/// runs until stopped, and the tests keep the default); returns false, changing nothing, on
/// other C libraries and under AddressSanitizer (which has its own allocator).
bool reuseFreedMemory();

}  // namespace texgrad
