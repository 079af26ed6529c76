// `texgrad project`: calibrated photos onto the atlas, one partial texture and confidence map per
// camera (the `texgrad stitch --partials/--confidence` pair).
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "photo_args.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"

namespace texgrad::cli {
namespace {

struct ProjectArgs {
  std::string mesh, resolution, outDir;
  PhotoArgs photos;
  ReportArgs report;
  MeshReadOptions read;
  std::string wrap = "auto";
};

/// The page names of `layout` (the UDIM tiles or materials each view is written for).
nlohmann::json pageNames(const PageLayout& layout) {
  nlohmann::json names = nlohmann::json::array();
  for (const TexturePage& page : layout.pages) names.push_back(page.name);
  return names;
}

/// `dir`/`stem`-NN.png for view number `index`.
std::filesystem::path numbered(const std::filesystem::path& dir, const char* stem, int index) {
  char name[64];
  std::snprintf(name, sizeof name, "%s-%02d.png", stem, index);
  return dir / name;
}

void runProject(const ProjectArgs& args) {
  StageTimer timer;
  const auto [width, height] = parseResolution(args.resolution);
  // Camera file and photo headers first (cheap), so a bad one leaves no empty output folder.
  std::vector<Camera> cameras = readPhotoCameras(args.photos);
  std::error_code ec;
  std::filesystem::create_directories(args.outDir, ec);
  if (ec) throw IoError("cannot create the output folder '" + args.outDir + "': " + ec.message());
  checkImageOutputArgs(numbered(args.outDir, "partial", 0).string(), "");
  const ProgressCallback progress = progressDisplay(args.report);
  TexturedMesh mesh = runStage(progress, "read", [&] {
    return wrapMesh(loadMesh(args.mesh, args.read), args.wrap, "baseColor");
  });
  // Over several pages (UDIM tiles, one image per material) each page is width x height, the
  // photos are projected onto their layout, and each view is written one image per page.
  PagedTexture paged = placeOnPagesOfSize(std::move(mesh), width, height);
  timer.lap("read");
  // Projection reads the basis and S only (surface points, normals): no re-assembly.
  TexelDomain domain(std::move(paged.mesh), paged.layout.width, paged.layout.height,
                     OperatorOptions::assembledOnce(), progress);
  timer.lap("operators");
  const PhotoProjector projector(domain, args.photos.options);
  // The projector keeps what projecting needs (surface points, normals): free M and S.
  domain.releaseOperators().reset();
  timer.lap("surface points");
  nlohmann::json views = nlohmann::json::array();
  int index = 0;
  projectEachPhoto(projector, cameras, args.photos, progress, args.report.quiet,
                   [&](size_t k, PhotoProjection&& view) {
                     const auto partial = numbered(args.outDir, "partial", index);
                     const auto confidence = numbered(args.outDir, "confidence", index);
                     writePagedImage(partial.string(), paged.layout, view.partial,
                                     view.partial.format);
                     writePagedImage(confidence.string(), paged.layout, view.confidence,
                                     view.confidence.format);
                     views.push_back({{"camera", cameras[k].name},
                                      {"partial", partial.string()},
                                      {"confidence", confidence.string()},
                                      {"seen_texels", view.seenTexels}});
                     ++index;
                   });
  timer.lap("project");
  const size_t pages = paged.layout.pages.size();
  if (!args.report.quiet)
    std::fprintf(stderr,
                 "wrote %d partial textures and confidence maps (%s%dx%d) to %s in %.1f s\n", index,
                 pages == 1 ? "" : (std::to_string(pages) + " pages of ").c_str(), width, height,
                 args.outDir.c_str(), timer.total());
  if (args.report.timings) timer.print();
  if (args.report.json)
    printJson(
        {{"command", "project"},
         {"texels", domain.unknowns()},
         {"cameras", cameras.size()},
         {"pages", pageNames(paged.layout)},
         {"views", views},
         {"partials", (std::filesystem::path(args.outDir) / "partial-%02d.png").string()},
         {"confidence", (std::filesystem::path(args.outDir) / "confidence-%02d.png").string()},
         {"stages", timer.json()},
         {"peak_rss_bytes", peakResidentBytes()}});
}

}  // namespace

void addProjectCommand(CLI::App& app) {
  auto args = std::make_shared<ProjectArgs>();
  CLI::App* cmd = app.add_subcommand(
      "project",
      "Project calibrated photos onto the texture atlas: per camera that sees the mesh, a "
      "partial texture (each texel's colour sampled from the photo at its surface point) and a "
      "confidence map (0 = not seen; falls with viewing angle, coarser photo pixels and nearness "
      "to the photo's border), written as partial-NN.png / confidence-NN.png for `texgrad stitch "
      "--partials/--confidence`. Visibility by a depth test against the mesh. A texture over "
      "several pages (UDIM tiles, or one image per material) gives one image per page and view, "
      "the page name before the extension (partial-NN.1001.png or partial-NN.MATERIAL.png), which "
      "`texgrad stitch` reads back with the same patterns.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  addPhotoOptions(cmd, args->photos);
  cmd->add_option("--resolution,-r", args->resolution,
                  "Texture size WxH (or N for N x N); of each page for a texture over several "
                  "pages")
      ->required()
      ->check(resolutionValidator());
  cmd->add_option("--out-dir", args->outDir, "Folder for partial-NN.png and confidence-NN.png")
      ->required();
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  addReportOptions(cmd, args->report);
  cmd->callback([args] { exitStatus = runGuarded([&] { runProject(*args); }); });
}

}  // namespace texgrad::cli
