// `texgrad texture`: calibrated photos to one seamless texture (project every photo, stitch the
// partials with gain and shading compensation, pad the gutters).
#include <iostream>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "photo_args.h"
#include "texgrad/apps/dilate.h"
#include "texgrad/apps/stitch.h"
#include "texgrad/core/error.h"

namespace texgrad::cli {
namespace {

struct TextureArgs {
  std::string mesh, resolution = "2048", out, bitDepth, select = "all";
  PhotoArgs photos;
  StitchOptions stitch;
  DilateOptions dilate;
  SolverArgs solver;
  ReportArgs report;
  MeshReadOptions read;
  std::string wrap = "auto";
};

void runTexture(TextureArgs args) {
  StageTimer timer;
  args.stitch.solver = args.solver.settings();
  args.stitch.validate();
  args.dilate.validate();
  const auto [width, height] = parseResolution(args.resolution);
  checkTextureOutputArgs(args.out, args.mesh, args.bitDepth);
  const bool best = args.select == "best";
  const std::vector<Camera> cameras = readPhotoCameras(args.photos);
  const ProgressCallback progress = progressDisplay(args.report);
  TexturedMesh mesh = runStage(progress, "read", [&] {
    return wrapMesh(loadMesh(args.mesh, args.read), args.wrap, "baseColor");
  });
  // Over several pages (UDIM tiles, one image per material) each page is width x height and the
  // photos are projected onto their layout at once: seams between pages are stitched too.
  PagedTexture paged = placeOnPagesOfSize(std::move(mesh), width, height);
  checkPagedOutputArgs(args.out, paged.layout, args.bitDepth);
  timer.lap("read");
  TexelDomain domain(std::move(paged.mesh), paged.layout.width, paged.layout.height, {}, progress);
  timer.lap("operators");
  // Only the compact views (or, with --select best, the running best view) stay in memory; the
  // projector's surface points and normals go once every photo is projected.
  std::vector<PartialView> partials;
  BestViewComposite composite;
  PixelFormat format = PixelFormat::UInt8;
  nlohmann::json views = nlohmann::json::array();
  int kept = 0;
  {
    const PhotoProjector projector(domain, args.photos.options);
    timer.lap("surface points");
    kept = projectEachPhoto(
        projector, cameras, args.photos, progress, args.report.quiet,
        [&](size_t k, PhotoProjection&& view) {
          views.push_back({{"camera", cameras[k].name}, {"seen_texels", view.seenTexels}});
          if (best) {
            composite.add(view, static_cast<int>(views.size()) - 1);
          } else {
            format = view.partial.format;
            partials.push_back(compactPartial(domain.grid(), view.partial, view.confidence));
          }
        });
  }
  if (kept == 0)
    throw InvalidInputError("no camera of '" + args.photos.cameras +
                            "' sees the mesh: check that the cameras and the mesh share one "
                            "coordinate frame");
  int64_t partialBytes = 0;
  for (const PartialView& p : partials) partialBytes += p.storageBytes();
  timer.lap("project");
  const StitchResult result =
      best ? stitchComposite(domain, domain.releaseOperators(), composite.composite,
                             composite.segments, args.stitch, progress)
           : stitchPartials(domain, domain.releaseOperators(), std::move(partials), format,
                            args.stitch, progress);
  timer.lap("stitch");
  const Image padded =
      dilateGutters(domain.mesh(), domain.atlas(), domain.grid(), result.image, args.dilate);
  timer.lap("dilate");
  const PixelFormat stored = runStage(progress, "write", [&] {
    return writePagedTexture(args.out, domain.mesh(), paged.layout, padded, args.bitDepth,
                             args.report.quiet);
  });
  timer.lap("write");
  printWrittenPages(args.report.quiet, args.out, paged.layout, padded, stored, domain.unknowns(),
                    timer.total());
  if (args.report.timings) timer.print();
  if (args.report.json)
    printJson({{"command", "texture"},
               {"select", args.select},
               {"texels", domain.unknowns()},
               {"cameras", cameras.size()},
               {"views", views},
               {"partials_bytes", partialBytes},
               {"solve", toJson(result.report)},
               {"stages", timer.json()},
               {"peak_rss_bytes", peakResidentBytes()},
               {"output", args.out}});
}

}  // namespace

void addTextureCommand(CLI::App& app) {
  auto args = std::make_shared<TextureArgs>();
  CLI::App* cmd = app.add_subcommand(
      "texture",
      "Make one seamless texture from calibrated photos: project every photo onto the atlas "
      "(as `texgrad project`), stitch the views with each view's exposure, colour cast and "
      "shading compensated (as `texgrad stitch --partials`), then pad the gutters (as `texgrad "
      "dilate`). One photo is in memory at a time, plus each view's colour and confidence at the "
      "texels it sees.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  addPhotoOptions(cmd, args->photos);
  cmd->add_option("--resolution,-r", args->resolution,
                  "Texture size WxH (or N for N x N); of each page for a texture over several "
                  "pages (the mesh's map_Kd with a <UDIM> or %04d token, or one image per "
                  "material)")
      ->check(resolutionValidator());
  cmd->add_option("--out,-o", args->out,
                  std::string("Output image, or .gltf/.glb for a glTF copy") + kPagedOutputHelp)
      ->required();
  cmd->add_option("--select", args->select,
                  "all: blend every view's gradients by confidence; best: keep only the most "
                  "confident view per texel and remove the jumps between the chosen regions "
                  "(composite + mask stitching)")
      ->check(CLI::IsMember({"all", "best"}));
  cmd->add_option("--alpha", args->stitch.alpha,
                  "Screening weight: larger keeps the photos' absolute colours (paper 1e2)")
      ->default_val(1e2)
      ->check(CLI::PositiveNumber);
  cmd->add_flag("!--no-gain-compensation", args->stitch.compensateGains,
                "Keep each view's exposure, colour cast and lighting (by default each view's "
                "illumination, estimated where views overlap, is divided out before stitching)");
  cmd->add_flag("!--gain-only", args->stitch.compensateIllumination,
                "Compensate one gain per view and channel only; by default the gain may vary "
                "with the surface normal, exp(a + b . n), which also removes smooth per-view "
                "shading");
  cmd->add_option("--dilate-radius", args->dilate.radius, "Rings of gutter texels to fill")
      ->default_val(4)
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--bit-depth", args->bitDepth, bitDepthHelp("the photos'"));
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  SolverSettings solverDefaults;
  solverDefaults.cycles = 10;
  solverDefaults.maxIterations = 200;
  addSolverOptions(cmd, args->solver, solverDefaults);
  addReportOptions(cmd, args->report);
  cmd->callback([args] { exitStatus = runGuarded([&] { runTexture(*args); }); });
}

}  // namespace texgrad::cli
