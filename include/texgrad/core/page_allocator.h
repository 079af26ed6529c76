// Core: an allocator that gives large blocks pages of their own, returned to the system when
// freed, for short-lived arrays that would otherwise leave a resident hole in the heap.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

namespace texgrad {

/// Blocks of at least this many bytes get pages of their own (the transparent huge page size).
inline constexpr std::size_t kOwnPagesMinBytes = std::size_t(1) << 21;

/// A fresh anonymous mapping of `bytes` bytes (zero-filled), aligned to and marked for
/// transparent huge pages; throws std::bad_alloc if the system refuses it.
void* mapOwnPages(std::size_t bytes);
/// Returns a block of mapOwnPages(bytes) to the system.
void unmapOwnPages(void* block, std::size_t bytes) noexcept;
/// True if PageAllocator maps large blocks here (Linux without AddressSanitizer, whose heap
/// checks the bounds of every block: there it uses the heap).
bool ownPagesAvailable();

/// Allocator whose blocks of kOwnPagesMinBytes and more are mapOwnPages blocks, unmapped when
/// freed; smaller ones come from the heap. For a large array that lives only while longer-lived
/// data are allocated around it (the grid's cell cover): from a heap that keeps freed memory for
/// reuse (reuseFreedMemory) it would leave a hole as large as itself, resident and often unused
/// through the peak (docs/memory.md).
template <typename T>
struct PageAllocator {
  using value_type = T;
  PageAllocator() = default;
  template <typename U>
  PageAllocator(const PageAllocator<U>&) noexcept {}  // NOLINT(google-explicit-constructor)

  /// Storage for n objects.
  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes >= kOwnPagesMinBytes && ownPagesAvailable())
      return static_cast<T*>(mapOwnPages(bytes));
    return std::allocator<T>().allocate(n);
  }
  /// Frees storage of allocate(n).
  void deallocate(T* p, std::size_t n) noexcept {
    const std::size_t bytes = n * sizeof(T);
    if (bytes >= kOwnPagesMinBytes && ownPagesAvailable())
      unmapOwnPages(p, bytes);
    else
      std::allocator<T>().deallocate(p, n);
  }
  template <typename U>
  bool operator==(const PageAllocator<U>&) const noexcept {
    return true;
  }
};

/// A vector whose large storage is pages of its own (PageAllocator).
template <typename T>
using PageVector = std::vector<T, PageAllocator<T>>;

}  // namespace texgrad
