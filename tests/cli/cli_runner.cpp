// Test helper: runs the `texgrad` executable through the shell and captures its output.
#include "cli_runner.h"

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "test_paths.h"

namespace texgrad::test {
namespace {

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

CliResult runCli(const std::vector<std::string>& args, const std::filesystem::path& workDir) {
  std::string command = "cd " + quote(workDir.string()) + " && " + quote(cliPath().string());
  for (const auto& a : args) command += " " + quote(a);
  const auto outFile = workDir / ".cli_stdout", errFile = workDir / ".cli_stderr";
  command += " >" + quote(outFile.string()) + " 2>" + quote(errFile.string()) + " </dev/null";
  const int raw = std::system(command.c_str());
  CliResult result;
  result.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  result.out = slurp(outFile);
  result.err = slurp(errFile);
  std::filesystem::remove(outFile);
  std::filesystem::remove(errFile);
  return result;
}

int lineCount(const std::string& text) {
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) ++n;
  return n;
}

}  // namespace texgrad::test
