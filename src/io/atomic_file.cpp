// Write-to-temporary-then-rename: every file texgrad writes goes through here, so a failed or
// interrupted command never leaves a half-written output behind.
#include "texgrad/io/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <string>
#include <system_error>

#include "texgrad/core/error.h"

namespace texgrad {
namespace {

/// `.NAME.tmp-PID-N.EXT` beside `target`: hidden, unique per process and call, and ending in the
/// target's extension so writers that pick the file format from the name (OpenImageIO) still do.
std::filesystem::path temporaryPathFor(const std::filesystem::path& target) {
  static std::atomic<unsigned long> counter{0};
  const std::string name = "." + target.stem().string() + ".tmp-" + std::to_string(::getpid()) +
                           "-" + std::to_string(counter++) + target.extension().string();
  return target.parent_path() / name;
}

void removeQuietly(const std::filesystem::path& path) {
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
}

}  // namespace

void writeAtomically(const std::filesystem::path& target,
                     const std::function<void(const std::filesystem::path& temporary)>& write) {
  if (target.empty() || !target.has_filename())
    throw IoError("cannot write '" + target.string() + "': not a file name");
  const std::filesystem::path folder = target.parent_path();
  std::error_code ec;
  if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
    throw IoError("cannot write " + target.string() + ": folder " + folder.string() +
                  " does not exist; create it first");
  if (std::filesystem::is_directory(target, ec))
    throw IoError("cannot write " + target.string() + ": it is a folder");

  const std::filesystem::path temporary = temporaryPathFor(target);
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

}  // namespace texgrad
