// `texgrad seams`: re-solve the texels along chart boundaries for the smoothest values.
#include <iostream>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "texgrad/apps/seams.h"
#include "texgrad/atlas/seam_jump.h"
#include "texgrad/io/image_io.h"

namespace texgrad::cli {
namespace {

struct SeamsArgs {
  std::string mesh, texture, out, mask, slot = "baseColor", bitDepth;
  SeamsOptions options;
  ReportArgs report;
  MeshReadOptions read;
  std::string wrap = "auto";
};

void runSeams(const SeamsArgs& args) {
  StageTimer timer;
  checkTextureOutputArgs(args.out, args.mesh, args.bitDepth);
  const ProgressCallback progress = progressDisplay(args.report);
  reportProgress(progress, "read", 0.0);
  PagedTexture paged =
      loadPagedTexture(wrapMesh(loadMesh(args.mesh, args.read), args.wrap, args.slot, args.texture),
                       args.mesh, args.texture, args.slot);
  checkPagedOutputArgs(args.out, paged.layout, args.bitDepth);
  if (!args.mask.empty()) requireSinglePage(paged.layout, "--mask", "leave it out");
  const Image& texture = paged.image;
  const Image mask = args.mask.empty() ? Image() : readImage(args.mask);
  reportProgress(progress, "read", 1.0);
  timer.lap("read");
  const TexelDomain domain(std::move(paged.mesh), texture.width, texture.height,
                           OperatorOptions::assembledOnce(), progress);
  timer.lap("operators");
  // --json's seam jump before is measured now, on a stage of its own: the texture's storage
  // becomes the result's (`texture` is not read after the move below).
  SeamJump before;
  if (args.report.json) {
    before = measureSeamJump(domain.mesh(), domain.atlas(), texture);
    timer.lap("seam jump");
  }
  const SeamsResult result =
      smoothSeams(domain, std::move(paged.image), mask, args.options, progress);
  timer.lap("solve");
  if (result.unanchoredTexels > 0 && !args.report.quiet)
    std::cerr << "texgrad: note: " << result.unanchoredTexels
              << " texels kept as they are: no fixed texel ties them to the rest (charts too "
                 "thin for an interior texel at this resolution, or a mask over whole charts)\n";
  const PixelFormat stored = runStage(progress, "write", [&] {
    return writePagedTexture(args.out, domain.mesh(), paged.layout, result.image, args.bitDepth,
                             args.report.quiet);
  });
  timer.lap("write");
  printWrittenPages(args.report.quiet, args.out, paged.layout, result.image, stored,
                    domain.unknowns(), timer.total());
  if (args.report.timings) timer.print();
  if (args.report.json) {
    const SeamJump after = measureSeamJump(domain.mesh(), domain.atlas(), result.image);
    printJson({{"command", "seams"},
               {"texels", domain.unknowns()},
               {"free_texels", result.freeTexels},
               {"unanchored_texels", result.unanchoredTexels},
               {"seam_jump_before", before.rms},
               {"seam_jump_after", after.rms},
               {"stages", timer.json()},
               {"peak_rss_bytes", peakResidentBytes()},
               {"output", args.out}});
  }
}

}  // namespace

void addSeamsCommand(CLI::App& app) {
  auto args = std::make_shared<SeamsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "seams",
      "Hide texture seams: replace the texels whose footprint a chart boundary crosses (or the "
      "texels under --mask) by the smoothest values that agree with all other texels (a "
      "Dirichlet problem in the seam-continuous texel space). Texels under stacked or mirrored "
      "charts away from their boundaries are kept; so are groups of texels with no other texel "
      "to agree with (a chart too thin for an interior texel and not joined by seams to one that "
      "has them; --json counts them as unanchored_texels). Other texels are unchanged bit for "
      "bit.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option(
      "texture", args->texture,
      std::string("Texture (default: the mesh's --texture-slot texture)") + kPagedInputHelp);
  cmd->add_option("--out,-o", args->out,
                  std::string("Output image, or .gltf/.glb for a glTF copy") + kPagedOutputHelp)
      ->required();
  cmd->add_option("--mask", args->mask,
                  "Re-solve the active texels under this mask (white) instead of the chart "
                  "boundary texels");
  cmd->add_option("--texture-slot", args->slot, "Texture of the mesh to use and replace")
      ->default_val("baseColor");
  cmd->add_option("--bit-depth", args->bitDepth, bitDepthHelp("the input's"));
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  addRawSolutionFlag(cmd, args->options.rawSolution);
  addReportOptions(cmd, args->report);
  cmd->callback([args] { exitStatus = runGuarded([&] { runSeams(*args); }); });
}

}  // namespace texgrad::cli
