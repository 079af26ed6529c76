// Core: an allocator that gives large blocks pages of their own, returned to the system when
// freed, for short-lived arrays that would otherwise leave a resident hole in the heap.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

namespace texgrad {

/// Bytes of a transparent huge page on x86-64 and arm64 with 4 KB base pages.
inline constexpr std::size_t kHugePageBytes = std::size_t(1) << 21;
/// Blocks of at least this many bytes get pages of their own, starting on a multiple of it.
inline constexpr std::size_t kOwnPagesMinBytes = kHugePageBytes;

namespace detail {

/// A fresh zero-filled anonymous mapping of `bytes` bytes (rounded up to whole pages), starting
/// on a multiple of kOwnPagesMinBytes and marked for transparent huge pages; throws
/// std::bad_alloc if the system refuses it.
void* mapOwnPages(std::size_t bytes);
/// Returns a block of mapOwnPages(bytes) to the system.
void unmapOwnPages(void* block, std::size_t bytes) noexcept;
/// True if PageAllocator maps large blocks (Linux without AddressSanitizer); elsewhere, and under
/// AddressSanitizer (whose heap checks every block's bounds), every block comes from the heap.
bool ownPagesAvailable();

}  // namespace detail

/// Allocator whose blocks of kOwnPagesMinBytes and more are pages of their own, unmapped when
/// freed, and smaller ones heap blocks: for a large array that lives only while longer-lived
/// data are allocated around it (the grid's cell cover), which a heap that keeps freed memory
/// for reuse (reuseFreedMemory) would leave behind as a resident hole (docs/memory.md).
template <typename T>
struct PageAllocator {
  using value_type = T;
  PageAllocator() = default;
  template <typename U>
  PageAllocator(const PageAllocator<U>&) noexcept {}  // NOLINT(google-explicit-constructor)

  /// Storage for n objects.
  T* allocate(std::size_t n) {
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes >= kOwnPagesMinBytes && detail::ownPagesAvailable())
      return static_cast<T*>(detail::mapOwnPages(bytes));
    return std::allocator<T>().allocate(n);
  }
  /// Frees storage of allocate(n).
  void deallocate(T* p, std::size_t n) noexcept {
    const std::size_t bytes = n * sizeof(T);
    if (bytes >= kOwnPagesMinBytes && detail::ownPagesAvailable())
      detail::unmapOwnPages(p, bytes);
    else
      std::allocator<T>().deallocate(p, n);
  }
  /// Every PageAllocator frees what any other allocated (it holds no state).
  template <typename U>
  bool operator==(const PageAllocator<U>&) const noexcept {
    return true;
  }
};

/// A vector whose large storage is pages of its own (PageAllocator).
template <typename T>
using PageVector = std::vector<T, PageAllocator<T>>;

}  // namespace texgrad
