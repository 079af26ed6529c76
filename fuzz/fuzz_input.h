// Helpers shared by the fuzz targets (fuzz/): a private scratch folder for readers that take a
// path, and the rule that only texgrad's typed errors count as a clean refusal.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <system_error>

namespace texgrad::fuzz {

/// A folder of this process's own (fuzz jobs may run side by side), removed when it exits.
inline const std::filesystem::path& scratch() {
  struct Folder {
    std::filesystem::path path = std::filesystem::temp_directory_path() /
                                 ("texgrad_fuzz_" + std::to_string(static_cast<long>(getpid())));
    Folder() { std::filesystem::create_directories(path); }
    ~Folder() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Folder folder;
  return folder.path;
}

/// Writes `bytes` to scratch()/name and returns the path.
inline std::filesystem::path writeScratch(const std::string& name, std::string_view bytes) {
  const std::filesystem::path path = scratch() / name;
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

/// The input as text.
inline std::string_view asText(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

}  // namespace texgrad::fuzz
