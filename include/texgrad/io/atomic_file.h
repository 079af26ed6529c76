// Write-to-temporary-then-rename helper so no command ever leaves a half-written output.
#pragma once

#include <filesystem>
#include <functional>

namespace texgrad {

/// Throws IoError unless writeAtomically could write `target`: a file name whose folder exists
/// and is writable, and which is not a folder. Cheap; for checking outputs before any work.
void checkWritableTarget(const std::filesystem::path& target);

/// Calls `write` with a temporary path next to `target`, then renames it onto `target`. If
/// `write` throws, the temporary is removed and the exception propagates; `target` is untouched.
/// Throws IoError first if checkWritableTarget refuses `target`.
///
/// While `write` runs, the temporary's absolute path is registered (up to kMaxPendingTemporaries
/// at once) so that removePendingTemporaries can delete it if the process is being killed.
void writeAtomically(const std::filesystem::path& target,
                     const std::function<void(const std::filesystem::path& temporary)>& write);

/// How many writeAtomically calls can have their temporary registered at the same time; further
/// concurrent calls still write atomically but an interrupt may leave their temporary behind.
inline constexpr int kMaxPendingTemporaries = 16;

/// Deletes the temporaries of the writeAtomically calls in progress (unlink on paths registered
/// beforehand: async-signal-safe). For a SIGINT/SIGTERM handler that then ends the process; the
/// calls in progress fail afterwards, since their temporaries are gone. The library installs no
/// handler itself: front ends do (the CLI: cli_common.h, installInterruptCleanup).
void removePendingTemporaries() noexcept;

}  // namespace texgrad
