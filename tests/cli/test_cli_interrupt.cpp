// A run killed while it writes its output leaves nothing behind: no output, no hidden temporary.
// The kill is real and lands during the write: the test watches the output folder (inotify) and
// signals `texgrad filter` the moment the temporary appears; the output is a 16-bit PNG of
// noise large enough that encoding it takes far longer than the signal takes to arrive.
// A run interrupted in the middle of a 2048x2048 solve (seen on its --progress lines) ends
// within a second, killed by the signal, and leaves no file either.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <spawn.h>
#include <sys/inotify.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "test_paths.h"
#include "texgrad/io/image_io.h"

extern char** environ;

namespace texgrad::test {
namespace {

/// Texels across the texture: a 2048 x 2048 16-bit PNG of noise takes about a second to encode.
constexpr int kTextureSize = 2048;
/// Give up waiting for the temporary after this long (the run itself takes a few seconds).
constexpr auto kTimeout = std::chrono::seconds(120);

/// A unit square whose one chart covers the UV square [0.45, 0.55]^2: few unknowns to solve,
/// while the output image is as large as the texture.
void writeSmallChartMesh(const std::filesystem::path& path) {
  std::ofstream out(path);
  out << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
         "vt 0.45 0.45\nvt 0.55 0.45\nvt 0.55 0.55\nvt 0.45 0.55\n"
         "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
}

void writeNoiseTexture(const std::filesystem::path& path) {
  Image image(kTextureSize, kTextureSize, 3, PixelFormat::UInt8);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> level(0, 255);
  for (float& p : image.pixels) p = static_cast<float>(level(rng)) / 255.0f;
  writeImage(path, image);
}

/// Starts `texgrad args...` with stdout to /dev/null, stderr to /dev/null (or to `stderrFd`, a
/// pipe's write end) and SIGINT/SIGTERM at their default (whatever the test runner set); returns
/// its pid.
pid_t startCli(const std::vector<std::string>& args, int stderrFd = -1) {
  std::vector<std::string> words{cliPath().string()};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  if (stderrFd >= 0)
    posix_spawn_file_actions_adddup2(&actions, stderrFd, STDERR_FILENO);
  else
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGTERM);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);
  pid_t pid = -1;
  const int error = posix_spawn(&pid, argv[0], &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  return error == 0 ? pid : -1;
}

/// Waits until a file whose name contains `.tmp-` is created in the watched folder; false if the
/// child exits first or the time runs out.
bool waitForTemporary(int watch, pid_t child) {
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  alignas(inotify_event) std::array<char, 4096> buffer{};
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd p{watch, POLLIN, 0};
    if (::poll(&p, 1, 100) > 0) {
      const ssize_t n = ::read(watch, buffer.data(), buffer.size());
      for (ssize_t at = 0; at < n;) {
        const auto* event = reinterpret_cast<const inotify_event*>(buffer.data() + at);
        if (event->len > 0 && std::string(event->name).find(".tmp-") != std::string::npos)
          return true;
        at += static_cast<ssize_t>(sizeof(inotify_event) + event->len);
      }
    }
    int status = 0;
    if (::waitpid(child, &status, WNOHANG) == child) return false;
  }
  return false;
}

class CliInterrupt : public ::testing::TestWithParam<int> {};

TEST_P(CliInterrupt, KilledDuringTheWriteLeavesNoFile) {
  const int sig = GetParam();
  const auto dir = tempDir("cli_interrupt_" + std::to_string(sig));
  writeSmallChartMesh(dir / "mesh.obj");
  writeNoiseTexture(dir / "texture.png");
  const int watch = ::inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
  ASSERT_GE(watch, 0);
  ASSERT_GE(::inotify_add_watch(watch, dir.c_str(), IN_CREATE), 0);
  const pid_t child =
      startCli({"filter", (dir / "mesh.obj").string(), (dir / "texture.png").string(), "--out",
                (dir / "out.png").string(), "--bit-depth", "16", "--quiet"});
  ASSERT_GT(child, 0);
  const bool sawTemporary = waitForTemporary(watch, child);
  if (sawTemporary) ::kill(child, sig);
  int status = 0;
  ::waitpid(child, &status, 0);
  ::close(watch);
  ASSERT_TRUE(sawTemporary) << "the run ended (status " << status << ") before it wrote";
  // Killed by the signal itself (the handler re-raises it), not an exit status.
  ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status;
  EXPECT_EQ(WTERMSIG(status), sig);
  std::vector<std::string> left;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    left.push_back(entry.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"mesh.obj", "texture.png"}));
  std::filesystem::remove_all(dir);
}

/// Reads lines from `fd` until one reports the solve at `step` or later ("texgrad: solve P%
/// (k/N)" with k >= step); false if the pipe closes (the child ended) or the time runs out.
bool waitForSolveStep(int fd, int step) {
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  std::string pending;
  std::array<char, 4096> buffer{};
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n <= 0) return false;
    pending.append(buffer.data(), static_cast<size_t>(n));
    for (size_t end; (end = pending.find('\n')) != std::string::npos; pending.erase(0, end + 1)) {
      const std::string line = pending.substr(0, end);
      const size_t open = line.find(" (");
      if (line.rfind("texgrad: solve ", 0) == 0 && open != std::string::npos &&
          std::stoi(line.substr(open + 2)) >= step)
        return true;
    }
  }
  return false;
}

/// Waits up to `limit` for the child to end; its wait status, or nullopt if it still runs.
std::optional<int> waitFor(pid_t child, std::chrono::duration<double> limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  do {
    int status = 0;
    if (::waitpid(child, &status, WNOHANG) == child) return status;
    ::usleep(2000);
  } while (std::chrono::steady_clock::now() < deadline);
  return std::nullopt;
}

/// How soon an interrupted solve must end (issue 27: within a second).
constexpr std::chrono::duration<double> kStopWithin{1.0};

TEST(CliInterruptSlow, SigintMidSolveAt2048EndsWithinASecondAndLeavesNoFile) {
  const auto dir = tempDir("cli_interrupt_solve");
  writeNoiseTexture(dir / "texture.png");
  std::array<int, 2> pipeFds{};
  ASSERT_EQ(::pipe2(pipeFds.data(), O_CLOEXEC), 0);
  // Plain V-cycles with no tolerance: 200 of them at 2048^2 take minutes, so the interrupt
  // lands in the middle of the solve.
  const pid_t child =
      startCli({"filter", "builtin:sphere", (dir / "texture.png").string(), "--out",
                (dir / "out.png").string(), "--beta", "0.3", "--solver", "multigrid", "--cycles",
                "200", "--tolerance", "0", "--progress", "lines"},
               pipeFds[1]);
  ::close(pipeFds[1]);
  ASSERT_GT(child, 0);
  const bool solving = waitForSolveStep(pipeFds[0], 2);
  const auto start = std::chrono::steady_clock::now();
  if (solving) ::kill(child, SIGINT);
  const std::optional<int> status = waitFor(child, solving ? kStopWithin : kTimeout);
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  if (!status) {
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
  }
  ::close(pipeFds[0]);
  ASSERT_TRUE(solving) << "the run ended before its solve reached cycle 2";
  ASSERT_TRUE(status) << "still running " << took.count() << " s after SIGINT";
  std::printf("SIGINT mid-solve at 2048^2: ended %.3f s after the signal\n", took.count());
  EXPECT_TRUE(WIFSIGNALED(*status) || WEXITSTATUS(*status) != 0) << "status " << *status;
  std::vector<std::string> left;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    left.push_back(entry.path().filename().string());
  EXPECT_EQ(left, (std::vector<std::string>{"texture.png"}));
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Signals, CliInterrupt, ::testing::Values(SIGTERM, SIGINT),
                         [](const ::testing::TestParamInfo<int>& p) {
                           return std::string(p.param == SIGTERM ? "Sigterm" : "Sigint");
                         });

}  // namespace
}  // namespace texgrad::test
