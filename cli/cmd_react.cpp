// `texgrad react`: a Gray–Scott reaction-diffusion pattern grown on the surface, in the atlas.
#include <iostream>
#include <string>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "texgrad/apps/dilate.h"
#include "texgrad/apps/reaction_diffusion.h"

namespace texgrad::cli {
namespace {

struct ReactArgs {
  std::string mesh, out, preset = "stripes", resolution = "512", bitDepth;
  int steps = 3000;
  double patternScale = 1.0;
  ReactionDiffusionOptions options;
  SolverArgs solver;
  ReportArgs report;
  MeshReadOptions read;
  std::string wrap = "auto";
};

/// Largest --steps accepted.
constexpr long long kMaxSteps = 100000000;

/// Accepts whole numbers from 0 to kMaxSteps, with a message naming what is wrong.
const CLI::Validator& stepCountValidator() {
  static const CLI::Validator validator(
      [](std::string& value) -> std::string {
        long long steps = -1;
        if (CLI::detail::lexical_cast(value, steps) && steps >= 0 && steps <= kMaxSteps) return {};
        return "must be a whole number from 0 to " + std::to_string(kMaxSteps) + ", got " + value;
      },
      "STEPS", "step count");
  return validator;
}

void runReact(ReactArgs args) {
  StageTimer timer;
  args.options.solver = args.solver.settings();
  const GrayScottRates rates = presetRates(parseReactionPreset(args.preset));
  args.options.feed = rates.feed;
  args.options.kill = rates.kill;
  // Features scale with sqrt(D): --scale s multiplies both rates by s^2.
  args.options.diffusionU *= args.patternScale * args.patternScale;
  args.options.diffusionV *= args.patternScale * args.patternScale;
  args.options.seedRadius *= args.patternScale;
  args.options.validate();
  checkTextureOutputArgs(args.out, args.mesh, args.bitDepth);
  const auto [width, height] = parseResolution(args.resolution);
  const ProgressCallback progress = progressDisplay(args.report);
  reportProgress(progress, "read", 0.0);
  TexturedMesh mesh = wrapMesh(loadMesh(args.mesh, args.read), args.wrap, "baseColor");
  reportProgress(progress, "read", 1.0);
  timer.lap("read");
  PagedTexture paged = placeOnPagesOfSize(std::move(mesh), width, height);
  checkPagedOutputArgs(args.out, paged.layout, args.bitDepth);
  TexelDomain domain(std::move(paged.mesh), paged.layout.width, paged.layout.height,
                     OperatorOptions::assembledOnce(), progress);
  timer.lap("operators");
  // Only M is kept for the steps: S and the rest are freed once both systems are formed.
  const ReactionResult result =
      reactionDiffusion(domain, domain.releaseOperators(), args.options, args.steps, progress);
  timer.lap("steps");
  const Image padded = dilateGutters(domain.mesh(), domain.atlas(), domain.grid(), result.image);
  const PixelFormat stored = runStage(progress, "write", [&] {
    return writePagedTexture(args.out, domain.mesh(), paged.layout, padded, args.bitDepth,
                             args.report.quiet);
  });
  timer.lap("write");
  printWrittenPages(args.report.quiet, args.out, paged.layout, padded, stored, domain.unknowns(),
                    timer.total());
  if (args.report.timings) timer.print();
  if (args.report.json)
    printJson({{"command", "react"},
               {"texels", domain.unknowns()},
               {"resolution", {width, height}},
               {"preset", args.preset},
               {"feed", args.options.feed},
               {"kill", args.options.kill},
               {"steps", args.steps},
               {"time_step", args.options.timeStep},
               {"solver", toString(args.options.solver.kind)},
               {"u_range", {result.u.minCoeff(), result.u.maxCoeff()}},
               {"v_range", {result.v.minCoeff(), result.v.maxCoeff()}},
               {"stages", timer.json()},
               {"peak_rss_bytes", peakResidentBytes()},
               {"output", args.out}});
}

}  // namespace

void addReactCommand(CLI::App& app) {
  auto args = std::make_shared<ReactArgs>();
  CLI::App* cmd = app.add_subcommand(
      "react",
      "Grow a Gray-Scott reaction-diffusion pattern on the surface and write it as a texture. "
      "Each time step solves (M + dt D S) c' = M (c + dt R(u, v)) for both species with the "
      "texel operators, so the pattern has surface-true scale and no seams. Light = low u (the "
      "pattern).");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option("--out,-o", args->out,
                  "Output image (.png .jpg .exr .tif), or .gltf/.glb for a copy of a glTF asset "
                  "with the pattern as base colour" +
                      std::string(kPagedOutputHelp))
      ->required();
  cmd->add_option("--preset", args->preset,
                  "stripes (F = 0.050, k = 0.065) or dots (F = 0.030, k = 0.062), Pearson's "
                  "parametrisation")
      ->default_val("stripes")
      ->check(CLI::IsMember({"stripes", "dots"}));
  cmd->add_option(
         "--steps", args->steps,
         "Time steps (dt = --time-step); more lets the pattern fill the surface and settle")
      ->default_val(3000)
      ->check(stepCountValidator());
  cmd->add_option("--time-step", args->options.timeStep,
                  "dt in Pearson's time units; diffusion is implicit, reaction explicit (keep "
                  "<= 1 for accuracy)")
      ->default_val(1.0)
      ->check(positiveValidator());
  cmd->add_option("--scale", args->patternScale,
                  "Pattern size multiplier (diffusion rates scale with its square)")
      ->default_val(1.0)
      ->check(positiveValidator());
  cmd->add_option("--seed", args->options.seed,
                  "Seed of the initial spots (same seed, same pattern)")
      ->default_val(1);
  cmd->add_option("--seed-spots", args->options.seedSpots,
                  "Number of initial spots placed at random over the surface")
      ->default_val(args->options.seedSpots)
      ->check(CLI::Range(0, 1000000));
  cmd->add_option("--resolution,-r", args->resolution, "Output texture size WxH (or N)")
      ->default_val("512")
      ->check(resolutionValidator());
  cmd->add_option("--bit-depth", args->bitDepth, bitDepthHelp("8"));
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  addSolverOptions(cmd, args->solver, defaultReactionSolver());
  addReportOptions(cmd, args->report);
  cmd->callback([args] { exitStatus = runGuarded([&] { runReact(*args); }); });
}

}  // namespace texgrad::cli
