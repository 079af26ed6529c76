// `texgrad filter`: smooth or sharpen a texture in the gradient domain (paper §7.1).
#include <iostream>
#include <optional>
#include <vector>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "texgrad/apps/filter.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/image_levels.h"

namespace texgrad::cli {
namespace {

struct FilterArgs {
  std::string mesh, texture, out, betaMap, slot = "baseColor", bitDepth;
  std::vector<double> betaRange{0.0, 2.0};
  std::string basis = "continuous";
  double seamWeight = 0.0;
  FilterOptions options;
  SolverArgs solver;
  ReportArgs report;
  MeshReadOptions read;
  std::string wrap = "auto";
};

void runFilter(FilterArgs args) {
  StageTimer timer;
  args.options.solver = args.solver.settings();
  checkTextureOutputArgs(args.out, args.mesh, args.bitDepth);
  if (args.options.normalMap && args.slot == "baseColor") args.slot = "normal";
  const ProgressCallback progress = progressDisplay(args.report);
  reportProgress(progress, "read", 0.0);
  PagedTexture paged =
      loadPagedTexture(wrapMesh(loadMesh(args.mesh, args.read), args.wrap, args.slot, args.texture),
                       args.mesh, args.texture, args.slot);
  checkPagedOutputArgs(args.out, paged.layout, args.bitDepth);
  if (!args.betaMap.empty()) requireSinglePage(paged.layout, "--beta-map", "filter with --beta");
  const int width = paged.image.width, height = paged.image.height;
  reportProgress(progress, "read", 1.0);
  timer.lap("read");
  // Only a beta map (S_beta) re-assembles the stiffness; otherwise the piece integrals go, and
  // M and S are assembled only once the filter has the texture, straight into alpha M + S and
  // the right-hand side (OperatorOptions::deferAssembly: S is never held whole).
  OperatorOptions operatorOptions;
  operatorOptions.keepPieceIntegrals = !args.betaMap.empty();
  operatorOptions.deferAssembly = args.betaMap.empty();
  if (args.basis == "bilinear") {
    operatorOptions.basis = fem::BasisKind::Bilinear;
    operatorOptions.seamContinuityWeight = args.seamWeight;
  } else if (args.seamWeight != 0.0) {
    throw InvalidInputError(
        "--seam-weight applies to --basis bilinear only (the continuous "
        "basis has no seam jumps to penalise)");
  }
  // While the operators are built nothing reads the texture: an 8-bit one waits as its levels,
  // a byte per value instead of a float (18 B/t less at the operators' peak at spot's coverage).
  std::optional<std::vector<uint8_t>> levels = exactByteLevels(paged.image);
  if (levels) paged.image.pixels = std::vector<float>();
  TexelDomain domain(std::move(paged.mesh), width, height, operatorOptions, progress);
  timer.lap("operators");
  if (!args.betaMap.empty()) {
    const Image map = readImage(args.betaMap);
    args.options.betaPerCell =
        cellValuesFromMap(domain.grid(), map, args.betaRange[0], args.betaRange[1]);
  }
  // One run, one filter: the filter takes the texture, still as its levels if 8-bit (and writes
  // its result there), and frees the operators and the grid's maps once it no longer needs
  // them (docs/memory.md).
  const FilterResult result =
      levels ? filterTexture(domain, domain.releaseOperators(), std::move(paged.image),
                             std::move(*levels), args.options, progress)
             : filterTexture(domain, domain.releaseOperators(), std::move(paged.image),
                             args.options, progress);
  timer.lap("solve");
  const PixelFormat stored = runStage(progress, "write", [&] {
    return writePagedTexture(args.out, domain.mesh(), paged.layout, result.image, args.bitDepth,
                             args.report.quiet);
  });
  timer.lap("write");
  printWrittenPages(args.report.quiet, args.out, paged.layout, result.image, stored,
                    domain.unknowns(), timer.total());
  if (args.report.timings) timer.print();
  if (args.report.json)
    printJson({{"command", "filter"},
               {"texels", domain.unknowns()},
               {"resolution", {width, height}},
               {"pages", paged.layout.pages.size()},
               {"solver", toString(args.options.solver.kind)},
               {"init_seconds", result.initSeconds},
               {"update_seconds", result.updateSeconds},
               {"solve", toJson(result.report)},
               {"stages", timer.json()},
               {"peak_rss_bytes", peakResidentBytes()},
               {"output", args.out}});
}

}  // namespace

void addFilterCommand(CLI::App& app) {
  auto args = std::make_shared<FilterArgs>();
  CLI::App* cmd = app.add_subcommand(
      "filter",
      "Smooth (--beta < 1) or sharpen (--beta > 1) a texture by scaling its gradients on the "
      "surface and solving the screened Poisson equation (alpha M + S) x = (alpha M + beta S) x0 "
      "(paper Sec. 7.1); lengths are measured on the surface, not in UV. Seams: the output's "
      "texels are the coefficients of a function in the paper's seam-continuous texel basis, and "
      "that function is continuous across seams (to rounding, any beta). A renderer's bilinear "
      "lookup reads the texels next to a seam differently on each side; the jump between the two "
      "sides' lookups is texel-scale detail, which the filter scales by about beta like all such "
      "detail: on the shared test meshes at 1024x1024 the RMS jump is 0.0-0.7 times the input's "
      "at beta 0 and 1.98-2.10 times at beta 2. Sharpening thus amplifies the jumps the input "
      "has; run `texgrad seams` on the input or on the result to remove them (RMS jump then at "
      "most 1.02 8-bit steps on those meshes). The channels are solved one after another (less "
      "memory): --cycles and --max-iterations apply to each channel, and the reported iterations "
      "(--json's solve.iterations, the progress count) add up all channels'.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option("texture", args->texture,
                  std::string("Texture to filter (default: the mesh's texture in "
                              "--texture-slot)") +
                      kPagedInputHelp);
  cmd->add_option("--out,-o", args->out,
                  "Output image (.png .jpg .exr .tif), or .gltf/.glb for a copy of a glTF asset "
                  "with the filtered texture" +
                      std::string(kPagedOutputHelp))
      ->required();
  cmd->add_option("--beta", args->options.beta,
                  "Gradient scale: 0 = strongest smoothing, 1 = unchanged, > 1 sharpens")
      ->default_val(1.0);
  cmd->add_option("--alpha", args->options.alpha,
                  "Screening weight: larger keeps the result closer to the input (the filter "
                  "acts on finer detail only); paper default 1e4")
      ->default_val(1e4)
      ->check(CLI::PositiveNumber);
  cmd->add_option("--basis", args->basis,
                  "continuous (the paper's seam-continuous texel basis) or bilinear (the paper's "
                  "Sec. 4.2 baseline: plain bilinear texels, seams coupled only by --seam-weight)")
      ->check(CLI::IsMember({"continuous", "bilinear"}));
  cmd->add_option("--seam-weight", args->seamWeight,
                  "lambda of the soft seam energy E_C for --basis bilinear (paper Sec. 4.2, Fig. "
                  "5); 0 leaves the charts uncoupled")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--beta-map", args->betaMap,
                  "Image whose brightness (0..1) sets beta per texel cell, mapped onto "
                  "--beta-range (local filtering); replaces --beta");
  cmd->add_option("--beta-range", args->betaRange, "MIN MAX beta for black and white of --beta-map")
      ->expected(2)
      ->default_str("0 2");
  cmd->add_flag("--normal-map", args->options.normalMap,
                "The texture is a tangent-space normal map (RGB = (n + 1) / 2, OpenGL/glTF "
                "convention): filter unit vectors and renormalise");
  cmd->add_option("--texture-slot", args->slot,
                  "Which texture of the mesh to use and replace: baseColor, normal, emissive, "
                  "metallicRoughness, occlusion")
      ->default_val("baseColor");
  cmd->add_option("--bit-depth", args->bitDepth, bitDepthHelp("the input texture's"));
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  addRawSolutionFlag(cmd, args->options.rawSolution);
  addSolverOptions(cmd, args->solver, FilterOptions().solver);
  addReportOptions(cmd, args->report);
  cmd->callback([args] { exitStatus = runGuarded([&] { runFilter(*args); }); });
}

}  // namespace texgrad::cli
