// `texgrad stitch`: merge textures from several sources without lighting seams (paper §7.2).
#include <cstdio>
#include <iostream>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "texgrad/apps/stitch.h"
#include "texgrad/core/error.h"
#include "texgrad/core/path_exists.h"
#include "texgrad/io/image_io.h"

namespace texgrad::cli {
namespace {

struct StitchArgs {
  std::string mesh, composite, segments, partials, confidence, lock, out, resolution, bitDepth;
  StitchOptions options;
  SolverArgs solver;
  ReportArgs report;
  MeshReadOptions read;
  std::string wrap = "auto";
};

/// Expands a printf pattern with one integer, the view number (e.g. 'texels-%02d.png'), for 0,
/// 1, ... while the view's file exists (over several pages: its first page's file, named by
/// pageOutputPath's rule after the view number is put in, so a %04d is never a UDIM token here).
std::vector<std::string> expandPattern(const std::string& pattern, const std::string& flag,
                                       const PageLayout& layout) {
  const size_t percent = pattern.find('%');
  if (percent == std::string::npos || pattern.find('%', percent + 1) != std::string::npos ||
      pattern.find_first_of("di", percent) == std::string::npos)
    throw InvalidInputError(flag + " '" + pattern +
                            "' must contain exactly one integer field such as %02d");
  std::vector<std::string> files;
  for (int k = 0; k < 1000; ++k) {
    std::vector<char> buffer(pattern.size() + 32);
    std::snprintf(buffer.data(), buffer.size(), pattern.c_str(), k);
    if (!pathExists(pageOutputPath(buffer.data(), layout, 0))) {
      if (k == 0) continue;  // numbering may start at 1
      break;
    }
    files.emplace_back(buffer.data());
  }
  if (files.empty()) throw IoError("no file matches " + flag + " '" + pattern + "'");
  return files;
}

/// Per-source gains as nested JSON arrays (one array of channel gains per source).
nlohmann::json gainsJson(const Eigen::MatrixXd& gains) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index s = 0; s < gains.rows(); ++s) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < gains.cols(); ++c) row.push_back(gains(s, c));
    rows.push_back(row);
  }
  return rows;
}

void runStitch(StitchArgs args) {
  StageTimer timer;
  args.options.solver = args.solver.settings();
  checkTextureOutputArgs(args.out, args.mesh, args.bitDepth);
  const bool compositeMode = !args.composite.empty();
  if (compositeMode == !args.partials.empty())
    throw InvalidInputError(
        "give either --composite with --segments, or --partials with "
        "--confidence");
  const ProgressCallback progress = progressDisplay(args.report);
  reportProgress(progress, "read", 0.0);
  TexturedMesh mesh = wrapMesh(loadMesh(args.mesh, args.read), args.wrap, "baseColor");
  // Over several pages (UDIM tiles, one image per material) every input is one image per page,
  // read into the pages' layout, where the sources are stitched at once (seams between pages
  // too); the page sizes are those of the first input's pages.
  PageLayout layout = findTexturePages(mesh, "baseColor");
  std::vector<std::string> partialFiles, confidenceFiles;
  if (compositeMode) {
    if (args.segments.empty()) throw InvalidInputError("--composite needs --segments MASK");
  } else {
    if (args.confidence.empty()) throw InvalidInputError("--partials needs --confidence PATTERN");
    partialFiles = expandPattern(args.partials, "--partials", layout);
    confidenceFiles = expandPattern(args.confidence, "--confidence", layout);
  }
  readPagedImageSizes(layout, compositeMode ? args.composite : partialFiles.front());
  checkPagedOutputArgs(args.out, layout, args.bitDepth);
  if (!layout.single()) mesh = placeOnPages(mesh, layout);
  Image composite, segments;
  std::vector<Image> partials, confidences;
  if (compositeMode) {
    composite = readPagedImage(layout, args.composite);
    segments = readPagedImage(layout, args.segments, PageGapFill::Zero);  // gaps: no source
  } else {
    for (const std::string& f : partialFiles) partials.push_back(readPagedImage(layout, f));
    for (const std::string& f : confidenceFiles) confidences.push_back(readPagedImage(layout, f));
  }
  if (!args.lock.empty()) args.options.lock = readPagedImage(layout, args.lock);
  reportProgress(progress, "read", 1.0);
  timer.lap("read");
  const TexelDomain domain(std::move(mesh), layout.width, layout.height, {}, progress);
  timer.lap("operators");
  const StitchResult result =
      compositeMode ? stitchComposite(domain, composite, segments, args.options, progress)
                    : stitchPartials(domain, partials, confidences, args.options, progress);
  timer.lap("solve");
  const PixelFormat stored = runStage(progress, "write", [&] {
    return writePagedTexture(args.out, domain.mesh(), layout, result.image, args.bitDepth,
                             args.report.quiet);
  });
  timer.lap("write");
  printWrittenPages(args.report.quiet, args.out, layout, result.image, stored, domain.unknowns(),
                    timer.total());
  if (args.report.timings) timer.print();
  if (args.report.json)
    printJson({{"command", "stitch"},
               {"mode", compositeMode ? "composite" : "partials"},
               {"texels", domain.unknowns()},
               {"sources", result.sources},
               {"locked_texels", result.lockedTexels},
               {"source_gains", gainsJson(result.sourceGains)},
               {"source_illumination", gainsJson(result.sourceIllumination)},
               {"solve", toJson(result.report)},
               {"stages", timer.json()},
               {"peak_rss_bytes", peakResidentBytes()},
               {"output", args.out}});
}

}  // namespace

void addStitchCommand(CLI::App& app) {
  auto args = std::make_shared<StitchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "stitch",
      "Merge textures captured from several sources (cameras, scans) into one without visible "
      "seams between them: gradients inside each source are kept, jumps between sources are "
      "removed (paper Sec. 7.2). Either a composite texture with a source mask, or N partial "
      "textures with confidence maps.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option("--composite", args->composite,
                  std::string("Composite texture (each texel from one source)") + kPagedInputsHelp);
  cmd->add_option("--segments", args->segments,
                  "Source mask for --composite: one colour per source, black = no source (texels "
                  "between pages belong to none)");
  cmd->add_option("--partials", args->partials,
                  "printf pattern of the partial textures, e.g. 'texels-%02d.png': its one integer "
                  "field is the view number (%04d too); over several pages, view k's page is the "
                  "expanded name with <UDIM> replaced by the tile, else with the page name before "
                  "the extension (texels-00.1001.png), as `texgrad project` writes them");
  cmd->add_option("--confidence", args->confidence,
                  "printf pattern of the confidence maps (0 = unseen, 1 = best), one per partial");
  cmd->add_option("--lock", args->lock,
                  "Mask (white = locked): these texels keep their input value exactly");
  cmd->add_option("--out,-o", args->out,
                  std::string("Output image, or .gltf/.glb for a glTF copy") + kPagedOutputHelp)
      ->required();
  cmd->add_option("--alpha", args->options.alpha,
                  "Screening weight: larger keeps the sources' absolute colours (paper 1e2)")
      ->default_val(1e2)
      ->check(CLI::PositiveNumber);
  cmd->add_flag("!--no-gain-compensation", args->options.compensateGains,
                "Keep each source's exposure, colour cast and lighting (by default each source's "
                "illumination, estimated where sources meet, is divided out before stitching)");
  cmd->add_flag("!--gain-only", args->options.compensateIllumination,
                "Compensate one gain per source and channel only; by default the gain may vary "
                "with the surface normal, exp(a + b . n), which also removes smooth per-view "
                "shading");
  cmd->add_option("--bit-depth", args->bitDepth, bitDepthHelp("the input's"));
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  addRawSolutionFlag(cmd, args->options.rawSolution);
  SolverSettings solverDefaults;
  solverDefaults.cycles = 10;
  // --solver cg: 20 iterations per cycle, the limit stitch had before it got its own flag.
  solverDefaults.maxIterations = 200;
  addSolverOptions(cmd, args->solver, solverDefaults);
  addReportOptions(cmd, args->report);
  cmd->callback([args] { exitStatus = runGuarded([&] { runStitch(*args); }); });
}

}  // namespace texgrad::cli
