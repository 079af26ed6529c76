// Core: an allocator that gives large blocks pages of their own, returned to the system when
// freed, for short-lived arrays that would otherwise leave a resident hole in the heap; arrays on
// such pages that become resident only as they are written; and the release of pages a large
// array no longer needs while it lives.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
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
/// Lets the system drop the whole base pages inside [begin, begin + bytes), memory this process
/// owns (heap or mapped) and will not read again before writing it: they stop being resident and
/// read as zero if touched again. Linux without AddressSanitizer only; elsewhere nothing happens.
void discardWholePages(void* begin, std::size_t bytes) noexcept;

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

/// A fixed number of uninitialised values from PageAllocator: a mapped block becomes resident a
/// page at a time as it is first written, so an array filled in parts while other data are
/// released holds memory only for the parts written so far (the multigrid's level-0 stencils,
/// filled while the system matrix they come from is released). Or from the heap, where an
/// array filled at once is better placed (it may reuse a freed block).
template <typename T>
class PageArray {
  static_assert(std::is_trivially_default_constructible_v<T> &&
                std::is_trivially_destructible_v<T>);

 public:
  PageArray() = default;
  /// n values, not initialised: from PageAllocator, or from the heap if `ownPages` is false.
  explicit PageArray(std::size_t n, bool ownPages = true)
      : data_(n == 0      ? nullptr
              : ownPages ? PageAllocator<T>().allocate(n)
                         : std::allocator<T>().allocate(n)),
        size_(n),
        ownPages_(ownPages) {}
  ~PageArray() { reset(); }
  /// n zeros: a block of pages of its own reads as zero already, so only a heap block is
  /// written (the pages stay unresident until a value is written).
  static PageArray zeros(std::size_t n, bool ownPages = true) {
    PageArray array(n, ownPages);
    const bool mapped =
        ownPages && array.bytes() >= kOwnPagesMinBytes && detail::ownPagesAvailable();
    if (!mapped) std::fill_n(array.data_, n, T(0));
    return array;
  }
  /// Takes `other`'s values, leaving it empty.
  PageArray(PageArray&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)),
        size_(std::exchange(other.size_, 0)),
        ownPages_(other.ownPages_) {}
  /// Frees this array's values and takes `other`'s, leaving it empty.
  PageArray& operator=(PageArray&& other) noexcept {
    if (this != &other) {
      reset();
      data_ = std::exchange(other.data_, nullptr);
      size_ = std::exchange(other.size_, 0);
      ownPages_ = other.ownPages_;
    }
    return *this;
  }
  PageArray(const PageArray&) = delete;
  PageArray& operator=(const PageArray&) = delete;

  /// The first value (null when empty).
  T* data() noexcept { return data_; }
  /// The first value (null when empty).
  const T* data() const noexcept { return data_; }
  /// Number of values.
  std::size_t size() const noexcept { return size_; }
  /// Bytes allocated.
  std::size_t bytes() const noexcept { return size_ * sizeof(T); }

 private:
  void reset() noexcept {
    if (data_ && ownPages_) PageAllocator<T>().deallocate(data_, size_);
    if (data_ && !ownPages_) std::allocator<T>().deallocate(data_, size_);
    data_ = nullptr;
    size_ = 0;
  }
  T* data_ = nullptr;
  std::size_t size_ = 0;
  bool ownPages_ = true;
};

}  // namespace texgrad
