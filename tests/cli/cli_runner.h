// Runs the built `texgrad` executable in a test and captures exit status, stdout and stderr.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace texgrad::test {

/// Result of one CLI invocation.
struct CliResult {
  int status = -1;
  std::string out;
  std::string err;
};

/// Runs `texgrad` with the given arguments (each shell-quoted) inside `workDir`.
CliResult runCli(const std::vector<std::string>& args, const std::filesystem::path& workDir);

/// Number of non-empty lines in `text`.
int lineCount(const std::string& text);

}  // namespace texgrad::test
