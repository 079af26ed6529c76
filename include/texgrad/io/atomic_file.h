// Write-to-temporary-then-rename helper so no command ever leaves a half-written output.
#pragma once

#include <filesystem>
#include <functional>

namespace texgrad {

/// Calls `write` with a temporary path next to `target`, then renames it onto `target`. If
/// `write` throws, the temporary is removed and the exception propagates; `target` is untouched.
void writeAtomically(const std::filesystem::path& target,
                     const std::function<void(const std::filesystem::path& temporary)>& write);

}  // namespace texgrad
