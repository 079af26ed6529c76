// Shared plumbing of the `texgrad` subcommands: mesh/texture arguments, error reporting, progress.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "texgrad/apps/system_solver.h"
#include "texgrad/core/progress.h"
#include "texgrad/io/image.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/textured_mesh.h"
#include "texgrad/solver/solve_report.h"

namespace texgrad::cli {

/// Mesh argument: a file path read with `options`, or `builtin:NAME` for a procedural mesh (see
/// builtinMeshNames(); one UV set, so `options.uvSet` must be 0).
TexturedMesh loadMesh(const std::string& spec, const MeshReadOptions& options);

/// Names accepted after `builtin:` (sample, sphere, cube, cylinder, square, two-charts,
/// aligned-cube: UVs on texel centres at 256 x 256, its sample texture's size; jittered-cube: the
/// same moved off the lattice by up to 1e-4 texel).
std::string builtinMeshNames();

/// Texture for a mesh: the explicit path if given, else the mesh's slot texture (readMeshTexture),
/// else the built-in sample texture for `builtin:` meshes; throws InvalidInputError if none.
Image loadTexture(const TexturedMesh& mesh, const std::string& meshSpec,
                  const std::string& explicitPath, const std::string& slot = "baseColor");

/// loadTexture's texture for a mesh that names no `slot` texture: the built-in sample texture for
/// `builtin:` meshes; throws InvalidInputError asking for the file otherwise.
Image missingTexture(const std::string& meshSpec, const std::string& slot);

/// Parses "WxH" or "N" (square) into a resolution; throws InvalidInputError on anything else.
std::pair<int, int> parseResolution(const std::string& text);

/// A CLI11 validator for "WxH" / "N" resolutions.
const CLI::Validator& resolutionValidator();

/// CLI11 validators for finite numbers > 0 and >= 0, with a short message ("must be a number
/// > 0, got -1") instead of CLI11's range dump.
const CLI::Validator& positiveValidator();
const CLI::Validator& nonNegativeValidator();

/// Installs SIGINT, SIGTERM and SIGHUP handlers (unless the signal is ignored) that delete the
/// temporaries of outputs being written (removePendingTemporaries) and then re-raise the signal,
/// so an interrupted run leaves neither a partial output nor a hidden temporary behind.
void installInterruptCleanup();

/// Runs a subcommand body, turning texgrad errors into one line on stderr and an exit status.
int runGuarded(const std::function<void()>& body);

/// Prints a JSON document to stdout (pretty, newline-terminated).
void printJson(const nlohmann::json& document);

/// Registers the mesh reader's options: --weld-tolerance (model units; 0 = weld exactly
/// coincident positions only) and --uv-set (glTF TEXCOORD_N).
void addMeshReadOptions(CLI::App* cmd, MeshReadOptions& options);

/// Registers --wrap (auto, repeat, mirror, clamp: how the texture is sampled outside [0, 1]^2).
void addWrapOption(CLI::App* cmd, std::string& wrap);

/// The mesh as the texture in `slot` (or `texture`, the file the user names) reads it under
/// --wrap `wrap` (parseUvWrap, meshForPages): charts in other UV tiles moved into the image,
/// faces straddling a tile border cut; UDIM tiles are pages and stay in place, only cut.
/// `parentFace`, if given, receives each face's face in `mesh`.
TexturedMesh wrapMesh(TexturedMesh mesh, const std::string& wrap, const std::string& slot,
                      const std::string& texture = {}, std::vector<int32_t>* parentFace = nullptr);

/// Registers --raw (keep the solver's values at barely covered texels; the library's
/// rawSolution option).
void addRawSolutionFlag(CLI::App* cmd, bool& raw);

/// Solver flags shared by every command that solves (--solver, --cycles, --levels, ...).
struct SolverArgs {
  std::string kind = "multigrid";
  std::string precision = "float";
  int cycles = 6;
  int maxIterations = SolverSettings{}.maxIterations;
  double tolerance = 0.0;
  int levels = 4;
  int sweeps = 3;
  double lineRatio = MultigridOptions{}.lineRatio;
  int weakRowReach = MultigridOptions{}.weakRowReach;
  int threads = 0;
  /// The settings these flags describe; throws InvalidInputError on a bad value.
  SolverSettings settings() const;
};
/// Registers the solver flags on `cmd` with the command's defaults (kind, cycles, iterations,
/// tolerance). Each flag's value is checked by the library (parseSolverKind,
/// parseSinglePrecision, SolverSettings::validate), so the CLI refuses exactly what the library
/// refuses, with its message.
void addSolverOptions(CLI::App* cmd, SolverArgs& args, const SolverSettings& defaults);

/// Output flags shared by processing commands.
struct ReportArgs {
  bool json = false;     ///< print a JSON summary on stdout
  bool timings = false;  ///< print phase timings on stderr
  bool quiet = false;    ///< no summary line, and no progress unless --progress asks for it
  /// --progress: "bar" (one line redrawn), "lines" (one line per step, for logs and pipes),
  /// "none", or "auto": bar when stderr is a terminal and --quiet is not given, else none.
  std::string progress = "auto";
};
/// Registers --json, --timings, --quiet and --progress on `cmd`.
void addReportOptions(CLI::App* cmd, ReportArgs& args);

/// The progress display --progress and --quiet ask for, on stderr: stage, percentage and, for
/// solves and time steps, the count done and the most there can be ("solve 37% (12/320)").
ProgressCallback progressDisplay(const ReportArgs& args);

/// Runs `work` as the stage `name` of `progress`: reports 0 before and 1 after it.
template <typename Work>
auto runStage(const ProgressCallback& progress, std::string_view name, Work&& work) {
  reportProgress(progress, name, 0.0);
  if constexpr (std::is_void_v<std::invoke_result_t<Work>>) {
    work();
    reportProgress(progress, name, 1.0);
  } else {
    auto result = work();
    reportProgress(progress, name, 1.0);
    return result;
  }
}

/// Wall-clock timer of named stages, printed with --timings and included in --json.
class StageTimer {
 public:
  StageTimer();
  /// Ends the current stage under `name` and starts the next one.
  void lap(const std::string& name);
  /// Stages as {"name": seconds, ...} plus "total".
  nlohmann::json json() const;
  /// One line per stage on stderr, then the peak resident memory.
  void print() const;
  /// Seconds from construction to the last lap.
  double total() const { return last_ - start_; }

 private:
  std::vector<std::pair<std::string, double>> stages_;
  double start_, last_;
};

/// The process's peak resident set size so far, in bytes (getrusage's ru_maxrss), printed by
/// --timings and reported as "peak_rss_bytes" in every solving command's --json.
int64_t peakResidentBytes();

/// JSON of a solve report: iterations, converged, residuals, RMS changes, phase times.
nlohmann::json toJson(const SolveReport& report);

/// Throws InvalidInputError naming --out if `out` asks for a glTF asset and the mesh was not read
/// from glTF (`meshSource`); writeMeshTexture refuses this too, in words without the flag.
void requireGltfMeshFor(const std::string& out, const std::filesystem::path& meshSource);

/// Unless `quiet`, prints `warnings` (source images a glTF copy left out) on stderr, one line each.
void printWarnings(bool quiet, const std::vector<std::string>& warnings);

/// --bit-depth's value as a format; nullopt when empty (the command's default).
std::optional<PixelFormat> requestedFormat(const std::string& bitDepth);

/// Checks, right after parsing and before any file is read, that writePagedTexture can write
/// `out` for the mesh `meshSpec` with `bitDepth` (checkMeshTextureOutput): every command that
/// writes calls this (or checkImageOutputArgs) first, so a bad output fails in no time.
void checkTextureOutputArgs(const std::string& out, const std::string& meshSpec,
                            const std::string& bitDepth);

/// The same for an output that is always an image file (checkImageOutput).
void checkImageOutputArgs(const std::string& out, const std::string& bitDepth);

/// --bit-depth's help: the values, the default `defaultText`, and that a depth the output's
/// format cannot hold is an error.
std::string bitDepthHelp(const std::string& defaultText);

/// Unless `quiet`, one line on stderr saying what was written: "wrote out.png: 1024x1024 RGB
/// 8-bit, 512,340 texels solved in 2.1 s" (`texels` < 0: no texel count).
void printWritten(bool quiet, const std::string& path, const Image& image, PixelFormat stored,
                  int64_t texels, double seconds);

}  // namespace texgrad::cli
