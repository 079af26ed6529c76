// Shared plumbing of the `texgrad` subcommands (argument parsing, error line, progress bar).
#include "cli_common.h"

#include <sys/resource.h>
#include <unistd.h>

#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <new>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include "texgrad/core/error.h"
#include "texgrad/io/atomic_file.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/mesh_texture.h"
#include "texgrad/io/procedural.h"
#include "texgrad/io/texture_pages.h"
#include "texgrad/io/uv_tiles.h"

namespace texgrad::cli {
namespace {

constexpr std::string_view kBuiltinPrefix = "builtin:";
constexpr int kSampleTextureSize = 1024;
constexpr int kProgressBarWidth = 40;
/// UV offset of builtin:jittered-cube from the lattice, in texels (issue 31's reproduction).
constexpr double kJitteredCubeTexels = 1e-4;

bool isBuiltin(const std::string& spec) {
  return spec.rfind(kBuiltinPrefix, 0) == 0;
}

}  // namespace

std::string builtinMeshNames() {
  return "sample, sphere, cube, cylinder, square, two-charts, aligned-cube, jittered-cube";
}

TexturedMesh loadMesh(const std::string& spec, const MeshReadOptions& options) {
  options.validate();
  if (!isBuiltin(spec)) return readMesh(spec, options);
  if (options.uvSet != 0)
    throw InvalidInputError(spec + " has one UV set (0); --uv-set " +
                            std::to_string(options.uvSet) + " needs a glTF mesh");
  const std::string name = spec.substr(kBuiltinPrefix.size());
  if (name == "sample") return procedural::sampleTorus();
  if (name == "sphere") return procedural::cubeSphere();
  if (name == "cube") return procedural::cube();
  if (name == "cylinder") return procedural::cylinder();
  if (name == "square") return procedural::square();
  if (name == "two-charts") return procedural::twoChartSquare();
  if (name == "aligned-cube") return procedural::alignedCube();
  if (name == "jittered-cube") return procedural::alignedCube(4, kJitteredCubeTexels);
  throw InvalidInputError("unknown built-in mesh '" + spec +
                          "'; use builtin:NAME with NAME one of " + builtinMeshNames());
}

Image loadTexture(const TexturedMesh& mesh, const std::string& meshSpec,
                  const std::string& explicitPath, const std::string& slot) {
  if (!explicitPath.empty()) return readImage(explicitPath);
  if (std::optional<Image> texture = readMeshTexture(mesh, slot)) return std::move(*texture);
  return missingTexture(meshSpec, slot);
}

Image missingTexture(const std::string& meshSpec, const std::string& slot) {
  if (isBuiltin(meshSpec)) {
    const std::string name = meshSpec.substr(kBuiltinPrefix.size());
    const bool aligned = name == "aligned-cube" || name == "jittered-cube";
    const int size = aligned ? procedural::kAlignedCubeResolution : kSampleTextureSize;
    return procedural::sampleTexture(size, size);
  }
  throw InvalidInputError(meshSpec + " references no " + slot +
                          " texture; pass the texture file as an argument");
}

namespace {

/// Parses 1-6 decimal digits starting at `pos`, advancing it; nullopt if there are none or more.
std::optional<int> parseDigits(const std::string& text, size_t& pos) {
  const size_t start = pos;
  while (pos < text.size() && pos - start < 7 &&
         std::isdigit(static_cast<unsigned char>(text[pos])))
    ++pos;
  if (pos == start || pos - start > 6) return std::nullopt;
  return std::stoi(text.substr(start, pos - start));
}

}  // namespace

std::pair<int, int> parseResolution(const std::string& text) {
  size_t pos = 0;
  const std::optional<int> w = parseDigits(text, pos);
  std::optional<int> h = w;
  if (w && pos < text.size() && (text[pos] == 'x' || text[pos] == 'X'))
    h = parseDigits(text, ++pos);
  if (!w || !h || pos != text.size())
    throw InvalidInputError("resolution '" + text + "' is not WxH or N (e.g. 1024x1024 or 1024)");
  if (*w < 2 || *h < 2)
    throw InvalidInputError("resolution '" + text + "' is too small; use at least 2x2");
  return {*w, *h};
}

const CLI::Validator& resolutionValidator() {
  static const CLI::Validator validator(
      [](std::string& value) -> std::string {
        try {
          parseResolution(value);
          return {};
        } catch (const Error& e) {
          return e.what();
        }
      },
      "WxH", "resolution");
  return validator;
}

namespace {

/// A validator accepting finite numbers above `minimum` (or equal to it when `inclusive`).
CLI::Validator numberValidator(double minimum, bool inclusive, const std::string& name) {
  const std::string bound = (inclusive ? ">= " : "> ") + CLI::detail::to_string(minimum);
  return CLI::Validator(
      [=](std::string& value) -> std::string {
        double number = 0.0;
        const bool parsed = CLI::detail::lexical_cast(value, number) && std::isfinite(number);
        if (parsed && (number > minimum || (inclusive && number == minimum))) return {};
        return "must be a number " + bound + ", got " + value;
      },
      name, name);
}

}  // namespace

const CLI::Validator& positiveValidator() {
  static const CLI::Validator validator = numberValidator(0.0, false, "POSITIVE");
  return validator;
}

const CLI::Validator& nonNegativeValidator() {
  static const CLI::Validator validator = numberValidator(0.0, true, "NONNEGATIVE");
  return validator;
}

namespace {

/// " (12/320)" for a report that counts steps, else "".
std::string stepText(const Progress& p) {
  if (p.steps <= 0) return {};
  return " (" + std::to_string(p.step) + "/" + std::to_string(p.steps) + ")";
}

/// One line redrawn in place: stage, bar, percentage and step count; a newline once a stage ends.
ProgressCallback progressBar() {
  return [](const Progress& p) {
    const int filled = static_cast<int>(p.fraction * kProgressBarWidth + 0.5);
    std::fprintf(stderr, "\r%-24.*s [%-*s] %3d%%%-14s", static_cast<int>(p.stage.size()),
                 p.stage.data(), kProgressBarWidth,
                 std::string(static_cast<size_t>(filled), '#').c_str(),
                 static_cast<int>(p.fraction * 100.0 + 0.5), stepText(p).c_str());
    if (p.fraction >= 1.0) std::fputc('\n', stderr);
    std::fflush(stderr);
    return true;
  };
}

/// One line per report that starts a stage, moves it by a whole percent or ends it: at most 101
/// lines a stage however many steps it has ("texgrad: solve 37% (12/320)").
ProgressCallback progressLines() {
  struct State {
    std::string stage;
    int percent = -1;
  };
  return [state = std::make_shared<State>()](const Progress& p) {
    const int percent = static_cast<int>(p.fraction * 100.0);
    if (p.stage == state->stage && percent <= state->percent) return true;
    state->stage = p.stage;
    state->percent = percent;
    std::fprintf(stderr, "texgrad: %.*s %d%%%s\n", static_cast<int>(p.stage.size()), p.stage.data(),
                 percent, stepText(p).c_str());
    std::fflush(stderr);
    return true;
  };
}

}  // namespace

ProgressCallback progressDisplay(const ReportArgs& args) {
  if (args.progress == "bar") return progressBar();
  if (args.progress == "lines") return progressLines();
  if (args.progress == "auto" && !args.quiet && isatty(STDERR_FILENO)) return progressBar();
  return {};
}

namespace {

/// SIGINT/SIGTERM/SIGHUP: delete the outputs being written, then die of the same signal.
/// SA_RESETHAND has restored the default action, which runs when the handler returns (the
/// signal is blocked inside it) or at once; so the exit status still says "killed by sig".
extern "C" void removeTemporariesAndReraise(int sig) {
  removePendingTemporaries();
  ::raise(sig);
}

}  // namespace

void installInterruptCleanup() {
  struct sigaction action {};
  action.sa_handler = removeTemporariesAndReraise;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    // A signal the parent set to be ignored (`nohup`, background jobs) stays ignored.
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler != SIG_IGN)
      ::sigaction(sig, &action, nullptr);
  }
}

int runGuarded(const std::function<void()>& body) {
  try {
    body();
    return 0;
  } catch (const Error& e) {
    std::cerr << "texgrad: error: " << e.what() << "\n";
  } catch (const Cancelled&) {
    std::cerr << "texgrad: cancelled\n";
  } catch (const std::bad_alloc&) {
    std::cerr << "texgrad: error: out of memory; try a lower --resolution\n";
  } catch (const std::exception& e) {
    std::cerr << "texgrad: internal error: " << e.what()
              << " (please report this with the input that caused it)\n";
  }
  return 1;
}

void printJson(const nlohmann::json& document) {
  std::cout << document.dump(2) << "\n";
}

void addMeshReadOptions(CLI::App* cmd, MeshReadOptions& options) {
  cmd->add_option("--weld-tolerance", options.weldTolerance,
                  "Weld 3-D positions closer than this (model units) to recover seams; "
                  "0 = exact matches only")
      ->default_val(0.0)
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--uv-set", options.uvSet,
                  "UV set to read: glTF TEXCOORD_N (every primitive must have it); OBJ, PLY "
                  "and builtin meshes have only 0")
      ->default_val(0)
      ->check(CLI::NonNegativeNumber);
}

void addWrapOption(CLI::App* cmd, std::string& wrap) {
  cmd->add_option("--wrap", wrap,
                  "How the texture is sampled outside [0, 1]^2: repeat (charts in other unit UV "
                  "tiles are moved into the image, faces straddling a tile border are cut there "
                  "and joined by a seam), mirror (every other tile mirrored), clamp (UVs used as "
                  "they are; an atlas wholly outside the image is refused), or auto (the mesh's "
                  "sampler: glTF's wrapS/wrapT, OBJ -clamp; repeat when it names none). Not used "
                  "for UDIM tiles (a texture named with <UDIM> or %04d): a UV outside one tile "
                  "lies in another, so faces straddling tiles are cut at the border and joined by "
                  "a seam, and every tile stays in place")
      ->default_val("auto")
      ->check(CLI::IsMember({"auto", "repeat", "mirror", "clamp"}));
}

TexturedMesh wrapMesh(TexturedMesh mesh, const std::string& wrap, const std::string& slot,
                      const std::string& texture, std::vector<int32_t>* parentFace) {
  const UvWrap mode = parseUvWrap(wrap, mesh, slot);
  WrappedMesh wrapped = meshForPages(std::move(mesh), mode, slot, texture);
  if (parentFace) *parentFace = std::move(wrapped.parentFace);
  return std::move(wrapped.mesh);
}

void addRawSolutionFlag(CLI::App* cmd, bool& raw) {
  cmd->add_flag("--raw", raw,
                "Keep the exact solution at barely covered texels (the charts cover less than "
                "1/1000 of the texel's bilinear kernel): the surface hardly determines their "
                "values, which can lie far outside the input's range. By default each is clamped "
                "into the range of its input value and its neighbours' values, what the surface "
                "shows there");
}

SolverSettings SolverArgs::settings() const {
  SolverSettings s;
  s.kind = parseSolverKind(kind);
  s.singlePrecision = parseSinglePrecision(precision);
  s.cycles = cycles;
  s.maxIterations = maxIterations;
  s.tolerance = tolerance;
  s.multigrid.levels = levels;
  s.multigrid.sweeps = sweeps;
  s.multigrid.lineRatio = lineRatio;
  s.multigrid.weakRowReach = weakRowReach;
  s.multigrid.threads = threads;
  s.validate();
  return s;
}

namespace {

/// A CLI11 check that asks the library: `set` stores the flag's value in default settings (or
/// parses it), and the library's InvalidInputError message becomes CLI11's validation error.
/// Text that is not a `Value` passes here, and CLI11's conversion refuses it.
template <typename Value>
CLI::Validator libraryCheck(const std::string& range,
                            const std::function<void(SolverSettings&, Value)>& set) {
  return CLI::Validator(
      [set](std::string& text) -> std::string {
        Value value{};
        if (!CLI::detail::lexical_cast(text, value)) return {};
        SolverSettings settings;
        try {
          set(settings, value);
          settings.validate();
        } catch (const InvalidInputError& e) {
          return e.what();
        }
        return {};
      },
      range);
}

/// A number as --help quotes it (1e-08, 0.5), not std::to_string's six decimals.
std::string numberText(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

std::string rangeText(int low, int high) {
  return std::to_string(low) + " to " + std::to_string(high);
}

}  // namespace

void addSolverOptions(CLI::App* cmd, SolverArgs& args, const SolverSettings& defaults) {
  using Settings = SolverSettings;
  using Multigrid = MultigridOptions;
  cmd->add_option("--solver", args.kind,
                  "multigrid (V-cycles, paper Sec. 6), cg (conjugate gradients preconditioned by "
                  "one V-cycle per iteration: converges where plain V-cycles are slow) or direct "
                  "(CHOLMOD: exact, slower, more memory)")
      ->default_val(toString(defaults.kind))
      ->check(libraryCheck<std::string>("{multigrid,cg,direct}", [](Settings& s, std::string v) {
        s.kind = parseSolverKind(v);
      }));
  cmd->add_option("--cycles", args.cycles,
                  "multigrid: V-cycles per solve (more = closer to the exact solution); not used "
                  "by cg (see --max-iterations) or direct")
      ->default_val(defaults.cycles)
      ->check(libraryCheck<int>(">= 1", [](Settings& s, int v) { s.cycles = v; }));
  cmd->add_option("--max-iterations", args.maxIterations,
                  "cg: most CG iterations per solve, one V-cycle each (it stops earlier at "
                  "--tolerance); not used by multigrid or direct")
      ->default_val(defaults.maxIterations)
      ->check(libraryCheck<int>(">= 1", [](Settings& s, int v) { s.maxIterations = v; }));
  cmd->add_option("--tolerance", args.tolerance,
                  "Stop once the relative residual |b - A x| / |b| is at most this (0 to 1). 0 = "
                  "the solver's default: multigrid runs every --cycles, cg stops at " +
                      numberText(SolverSettings::kDefaultCgTolerance) +
                      "; direct is exact and ignores it")
      ->default_val(defaults.tolerance)
      ->check(libraryCheck<double>("0 to 1", [](Settings& s, double v) { s.tolerance = v; }));
  cmd->add_option("--levels", args.levels, "Multigrid coarsening levels (paper default 4)")
      ->default_val(defaults.multigrid.levels)
      ->check(libraryCheck<int>(rangeText(0, Multigrid::kMaxLevels),
                                [](Settings& s, int v) { s.multigrid.levels = v; }));
  cmd->add_option("--sweeps", args.sweeps, "Gauss-Seidel sweeps per level (paper default 3)")
      ->default_val(defaults.multigrid.sweeps)
      ->check(libraryCheck<int>(rangeText(1, Multigrid::kMaxSweeps),
                                [](Settings& s, int v) { s.multigrid.sweeps = v; }));
  cmd->add_option("--line-ratio", args.lineRatio,
                  "Also relax texels by lines along a grid axis when their stencil couples more "
                  "than this many times as strongly along it as across (stretched charts); 0 = off")
      ->default_val(defaults.multigrid.lineRatio)
      ->check(libraryCheck<double>("0 or >= " + numberText(Multigrid::kMinLineRatio),
                                   [](Settings& s, double v) { s.multigrid.lineRatio = v; }));
  cmd->add_option("--weak-row-reach", args.weakRowReach,
                  "Solve texels within this many texels of a barely covered boundary texel "
                  "directly with the boundary; 0 = off (the paper's split)")
      ->default_val(defaults.multigrid.weakRowReach)
      ->check(libraryCheck<int>(rangeText(0, Multigrid::kMaxWeakRowReach),
                                [](Settings& s, int v) { s.multigrid.weakRowReach = v; }));
  cmd->add_option("--precision", args.precision,
                  "float or double V-cycles (factorisations are always double; a solve whose "
                  "float cycle diverges changes to double cycles, but react, which keeps no "
                  "copy of its systems, stops and asks for double)")
      ->default_val(defaults.singlePrecision ? "float" : "double")
      ->check(libraryCheck<std::string>("{float,double}", [](Settings& s, std::string v) {
        s.singlePrecision = parseSinglePrecision(v);
      }));
  cmd->add_option("--threads", args.threads, "Worker threads; 0 = all cores")
      ->default_val(defaults.multigrid.threads)
      ->check(libraryCheck<int>(rangeText(0, Multigrid::kMaxThreads),
                                [](Settings& s, int v) { s.multigrid.threads = v; }));
}

void addReportOptions(CLI::App* cmd, ReportArgs& args) {
  cmd->add_flag("--json", args.json,
                "Print a JSON summary (texels, phases, cycles, residuals, peak memory) on stdout");
  cmd->add_flag("--timings", args.timings,
                "Print the time of each stage and the peak resident memory on stderr");
  cmd->add_flag("--quiet,-q", args.quiet,
                "No summary line, and no progress unless --progress asks for it");
  cmd->add_option("--progress", args.progress,
                  "Progress on stderr of every stage (read, operators, solver set-up, solve with "
                  "its cycle or iteration count, write): bar (one line redrawn), lines (a line "
                  "per step, for logs and pipes), none, or auto (bar when stderr is a terminal "
                  "and --quiet is not given)")
      ->check(CLI::IsMember({"auto", "bar", "lines", "none"}));
}

namespace {
double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

StageTimer::StageTimer() : start_(now()), last_(start_) {}

void StageTimer::lap(const std::string& name) {
  const double t = now();
  stages_.emplace_back(name, t - last_);
  last_ = t;
}

nlohmann::json StageTimer::json() const {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [name, seconds] : stages_) j[name] = seconds;
  j["total"] = last_ - start_;
  return j;
}

void StageTimer::print() const {
  for (const auto& [name, seconds] : stages_)
    std::fprintf(stderr, "  %-12s %8.3f s\n", name.c_str(), seconds);
  std::fprintf(stderr, "  %-12s %8.3f s\n", "total", last_ - start_);
  std::fprintf(stderr, "  %-12s %8.1f MB\n", "peak memory", double(peakResidentBytes()) / 1e6);
}

int64_t peakResidentBytes() {
  // Linux reports ru_maxrss in KiB (the high-water mark of the resident set, VmHWM).
  constexpr int64_t kBytesPerMaxRssUnit = 1024;
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return int64_t(usage.ru_maxrss) * kBytesPerMaxRssUnit;
}

nlohmann::json toJson(const SolveReport& report) {
  return {{"iterations", report.iterations},
          {"converged", report.converged},
          {"diverged", report.diverged},
          {"residuals", report.residuals},
          {"rms_change", report.rmsChange},
          {"seconds",
           {{"relaxation", report.times.relaxation},
            {"boundary", report.times.boundary},
            {"coarse", report.times.coarse},
            {"transfer", report.times.transfer},
            {"total", report.times.total()}}}};
}

std::optional<PixelFormat> requestedFormat(const std::string& bitDepth) {
  if (bitDepth.empty()) return std::nullopt;
  return parsePixelFormat(bitDepth);
}

void requireGltfMeshFor(const std::string& out, const std::filesystem::path& meshSource) {
  if (isGltfPath(out) && !isGltfPath(meshSource))
    throw InvalidInputError("--out " + out +
                            " asks for a glTF asset, but the mesh was not read "
                            "from glTF; write an image (.png, .exr, ...) instead");
}

void checkTextureOutputArgs(const std::string& out, const std::string& meshSpec,
                            const std::string& bitDepth) {
  const std::filesystem::path source = isBuiltin(meshSpec) ? "" : meshSpec;
  requireGltfMeshFor(out, source);
  checkMeshTextureOutput(out, source, requestedFormat(bitDepth));
}

void checkImageOutputArgs(const std::string& out, const std::string& bitDepth) {
  checkImageOutput(out, requestedFormat(bitDepth));
}

std::string bitDepthHelp(const std::string& defaultText) {
  return "8, 16, half or float (default: " + defaultText +
         "); a depth the output format cannot hold is an error (.jpg: 8; .png and glTF: 8 or "
         "16; .exr: half or float; .tif: 8, 16 or float)";
}

void printWarnings(bool quiet, const std::vector<std::string>& warnings) {
  if (!quiet)
    for (const std::string& warning : warnings)
      std::cerr << "texgrad: warning: " << warning << "\n";
}

namespace {

/// 512340 as "512,340".
std::string groupedDigits(int64_t value) {
  std::string digits = std::to_string(value);
  for (auto k = static_cast<std::ptrdiff_t>(digits.size()) - 3; k > 0; k -= 3)
    digits.insert(static_cast<size_t>(k), ",");
  return digits;
}

std::string_view channelsName(int channels) {
  static constexpr std::array<std::string_view, 4> names{"1-channel", "2-channel", "RGB", "RGBA"};
  return channels >= 1 && channels <= 4 ? names[static_cast<size_t>(channels - 1)] : "?";
}

}  // namespace

void printWritten(bool quiet, const std::string& path, const Image& image, PixelFormat stored,
                  int64_t texels, double seconds) {
  if (quiet) return;
  std::ostringstream line;
  line << "wrote " << path << ": " << image.width << "x" << image.height << " "
       << channelsName(image.channels) << " " << pixelFormatName(stored);
  if (texels >= 0) line << ", " << groupedDigits(texels) << " texels solved";
  char time[32];
  std::snprintf(time, sizeof time, " in %.1f s", seconds);
  std::cerr << line.str() << time << "\n";
}

}  // namespace texgrad::cli
