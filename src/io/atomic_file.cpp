// Write-to-temporary-then-rename: every file texgrad writes goes through here, so a failed or
// interrupted command never leaves a half-written output behind.
#include "texgrad/io/atomic_file.h"

#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

#include "texgrad/core/error.h"

namespace texgrad {
namespace {

/// `.NAME.tmp-PID-N.EXT` beside `target`: hidden, unique per process and call, and ending in the
/// target's extension, so that a leftover from a crash still shows what kind of file it is.
std::filesystem::path temporaryPathFor(const std::filesystem::path& target) {
  static std::atomic<unsigned long> counter{0};
  const std::string name = "." + target.stem().string() + ".tmp-" + std::to_string(::getpid()) +
                           "-" + std::to_string(counter++) + target.extension().string();
  return target.parent_path() / name;
}

/// Room for one registered temporary's path, terminating zero included (Linux PATH_MAX).
constexpr size_t kMaxPathBytes = 4096;

/// States of a registry slot. A signal handler only reads slots it moves Pending -> Taken, and a
/// Taken slot is never written again, so the handler never sees a path being copied.
enum SlotState : int { kFree, kFilling, kPending, kTaken };

/// One registered temporary: what removePendingTemporaries may unlink.
struct PendingSlot {
  std::atomic<int> state{kFree};
  std::array<char, kMaxPathBytes> path{};
};
static_assert(std::atomic<int>::is_always_lock_free, "signal handlers need lock-free atomics");

std::array<PendingSlot, kMaxPendingTemporaries> pendingSlots;

/// Registers a temporary's absolute path for the lifetime of the object (no slot: unregistered).
class PendingTemporary {
 public:
  explicit PendingTemporary(const std::filesystem::path& temporary) {
    std::error_code ec;
    const std::filesystem::path absolute = std::filesystem::absolute(temporary, ec);
    const std::string& path = (ec ? temporary : absolute).native();
    if (path.size() >= kMaxPathBytes) return;
    for (PendingSlot& slot : pendingSlots) {
      int expected = kFree;
      if (!slot.state.compare_exchange_strong(expected, kFilling)) continue;
      std::memcpy(slot.path.data(), path.c_str(), path.size() + 1);
      slot.state.store(kPending);
      slot_ = &slot;
      return;
    }
  }
  /// Frees the slot unless a signal handler has taken it (then the process is ending).
  ~PendingTemporary() {
    int expected = kPending;
    if (slot_ != nullptr) slot_->state.compare_exchange_strong(expected, kFree);
  }
  PendingTemporary(const PendingTemporary&) = delete;
  PendingTemporary& operator=(const PendingTemporary&) = delete;

 private:
  PendingSlot* slot_ = nullptr;
};

void removeQuietly(const std::filesystem::path& path) {
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
}

}  // namespace

void checkWritableTarget(const std::filesystem::path& target) {
  if (target.empty() || !target.has_filename())
    throw IoError("cannot write '" + target.string() + "': not a file name");
  const std::filesystem::path folder = target.parent_path();
  std::error_code ec;
  if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
    throw IoError("cannot write " + target.string() + ": folder " + folder.string() +
                  " does not exist; create it first");
  if (std::filesystem::is_directory(target, ec))
    throw IoError("cannot write " + target.string() + ": it is a folder");
  // The temporary is created in the folder, so the folder must be writable (the target itself
  // is replaced by a rename and need not be).
  const std::filesystem::path where = folder.empty() ? std::filesystem::path(".") : folder;
  if (::access(where.c_str(), W_OK | X_OK) != 0)
    throw IoError("cannot write " + target.string() + ": folder " + where.string() +
                  " is not writable: " + std::strerror(errno));
}

void writeAtomically(const std::filesystem::path& target,
                     const std::function<void(const std::filesystem::path& temporary)>& write) {
  checkWritableTarget(target);
  std::error_code ec;
  const std::filesystem::path temporary = temporaryPathFor(target);
  // Registered before `write` creates the file, released after the rename: at no moment does
  // the temporary exist unregistered.
  const PendingTemporary registration(temporary);
  try {
    write(temporary);
  } catch (...) {
    removeQuietly(temporary);
    throw;
  }
  std::filesystem::rename(temporary, target, ec);
  if (ec) {
    removeQuietly(temporary);
    throw IoError("cannot write " + target.string() + ": " + ec.message());
  }
}

void removePendingTemporaries() noexcept {
  for (PendingSlot& slot : pendingSlots) {
    int expected = kPending;
    if (slot.state.compare_exchange_strong(expected, kTaken)) ::unlink(slot.path.data());
  }
}

}  // namespace texgrad
