// CLI contract for the solver flags: every flag accepts exactly the values the library's
// SolverSettings accepts and refuses the others with the library's own message, at once.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "test_paths.h"
#include "texgrad/apps/system_solver.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image.h"
#include "texgrad/io/image_io.h"

namespace texgrad::test {
namespace {

/// One value of one solver flag and how the same value reaches the library's settings.
struct OptionValue {
  std::string flag, value;
  std::function<void(SolverSettings&)> set;
};

/// The library's verdict on a value: "" if SolverSettings accepts it, else its message.
std::string libraryVerdict(const OptionValue& option) {
  try {
    SolverSettings settings;
    option.set(settings);
    settings.validate();
  } catch (const InvalidInputError& e) {
    return e.what();
  }
  return {};
}

std::vector<OptionValue> solverOptionValues() {
  using S = SolverSettings;
  std::vector<OptionValue> values;
  auto add = [&](const std::string& flag, const std::vector<std::string>& texts,
                 const std::function<void(S&, const std::string&)>& set) {
    for (const std::string& text : texts)
      values.push_back({flag, text, [set, text](S& s) { set(s, text); }});
  };
  add("--solver", {"direct", "magic"},
      [](S& s, const std::string& v) { s.kind = parseSolverKind(v); });
  add("--precision", {"double", "half"},
      [](S& s, const std::string& v) { s.singlePrecision = parseSinglePrecision(v); });
  add("--cycles", {"1", "0"}, [](S& s, const std::string& v) { s.cycles = std::stoi(v); });
  add("--max-iterations", {"1", "0"},
      [](S& s, const std::string& v) { s.maxIterations = std::stoi(v); });
  add("--tolerance", {"1", "1.5"}, [](S& s, const std::string& v) { s.tolerance = std::stod(v); });
  add("--levels", {"16", "17"},
      [](S& s, const std::string& v) { s.multigrid.levels = std::stoi(v); });
  add("--sweeps", {"1", "101"},
      [](S& s, const std::string& v) { s.multigrid.sweeps = std::stoi(v); });
  add("--line-ratio", {"1", "0.5"},
      [](S& s, const std::string& v) { s.multigrid.lineRatio = std::stod(v); });
  add("--weak-row-reach", {"8", "9"},
      [](S& s, const std::string& v) { s.multigrid.weakRowReach = std::stoi(v); });
  add("--threads", {"1", "-1"},
      [](S& s, const std::string& v) { s.multigrid.threads = std::stoi(v); });
  return values;
}

TEST(CliSolverOptions, EveryFlagHasTheLibrarysVerdictAndMessage) {
  const auto dir = tempDir("cli_solver_options");
  writeImage(dir / "small.png", Image(16, 16, 3, PixelFormat::UInt8));  // a quick filter
  // The values the library accepts (one per flag, at the edge of its range) run a real filter
  // together; each value it refuses must be refused alone while the flags are parsed, before
  // the (here missing) mesh is read.
  std::vector<std::string> good{"filter", "builtin:square", "small.png", "--out", "f.png", "-q"};
  int refused = 0;
  for (const OptionValue& option : solverOptionValues()) {
    const std::string verdict = libraryVerdict(option);
    const std::string what = option.flag + "=" + option.value;  // "=": "-1" is not a flag
    if (verdict.empty()) {
      good.push_back(what);
      continue;
    }
    ++refused;
    const CliResult r = runCli({"filter", "missing.obj", "--out", "f.png", what}, dir);
    EXPECT_NE(r.status, 0) << what << ": the library refuses it (" << verdict << ")";
    EXPECT_EQ(lineCount(r.err), 1) << what << "\n" << r.err;
    EXPECT_NE(r.err.find(verdict), std::string::npos)
        << what << ": expected the library's message '" << verdict << "' in: " << r.err;
  }
  EXPECT_EQ(good.size(), 6u + 10u);  // one accepted value of each of the ten flags
  EXPECT_EQ(refused, 10);
  const CliResult r = runCli(good, dir);
  EXPECT_EQ(r.status, 0) << "the library accepts every value, the CLI said\n" << r.err;
}

TEST(CliSolverOptions, LineRatioBelowOneIsRefusedByBothWithOneMessage) {
  MultigridOptions options;
  options.lineRatio = 0.5;
  std::string message;
  try {
    options.validate();
  } catch (const InvalidInputError& e) {
    message = e.what();
  }
  ASSERT_FALSE(message.empty());
  const CliResult r = runCli({"filter", "missing.obj", "--out", "f.png", "--line-ratio", "0.5"},
                             tempDir("cli_line_ratio"));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
}

}  // namespace
}  // namespace texgrad::test
