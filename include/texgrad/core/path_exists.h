// Asking whether a file a user's input names exists, without exceptions.
#pragma once

#include <filesystem>
#include <system_error>

namespace texgrad {

/// True if `path` names an existing file or folder; false, never an exception, when it does not or
/// cannot be asked about (a name longer than the system allows, a parent that is a file, no
/// permission): names inside a user's file are untrusted, and the caller's "not found" message
/// then says what to do.
inline bool pathExists(const std::filesystem::path& path) noexcept {
  std::error_code ec;
  return std::filesystem::exists(path, ec) && !ec;
}

}  // namespace texgrad
