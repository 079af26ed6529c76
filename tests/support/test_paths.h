// Paths the tests use: the shared mesh folder and the built CLI executable.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

namespace texgrad::test {

/// Folder with the shared meshes (../shared/data beside the repository).
inline std::filesystem::path sharedData() { return TEXGRAD_SHARED_DATA; }
/// Path of the built `texgrad` executable.
inline std::filesystem::path cliPath() { return TEXGRAD_CLI_PATH; }
/// A fresh empty temporary folder for one test, named after it and the test process: ctest runs
/// tests in parallel processes, and two tests (or two checkouts) using the same name must not
/// wipe each other's files.
inline std::filesystem::path tempDir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() /
             ("texgrad_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace texgrad::test
