// `texgrad dilate`: pads the gutters of a texture (seam-aware first ring, then averaging rings).
#include <cstdint>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "texgrad/apps/dilate.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/image_coverage.h"
#include "texgrad/atlas/texel_grid.h"

namespace texgrad::cli {
namespace {

struct DilateArgs {
  std::string mesh, texture, out, slot = "baseColor", bitDepth;
  DilateOptions options;
  ReportArgs report;
  MeshReadOptions read;
  std::string wrap = "auto";
};

/// Image texels whose value the padding changed (all in the gutter: active texels are kept).
int64_t changedTexels(const Image& before, const Image& after) {
  int64_t changed = 0;
  for (int j = 0; j < before.height; ++j)
    for (int i = 0; i < before.width; ++i)
      for (int c = 0; c < before.channels; ++c)
        if (before.at(i, j, c) != after.at(i, j, c)) {
          ++changed;
          break;
        }
  return changed;
}

void runDilate(const DilateArgs& args) {
  args.options.validate();
  checkTextureOutputArgs(args.out, args.mesh, args.bitDepth);
  StageTimer timer;
  const PagedTexture paged =
      loadPagedTexture(wrapMesh(loadMesh(args.mesh, args.read), args.wrap, args.slot, args.texture),
                       args.mesh, args.texture, args.slot);
  checkPagedOutputArgs(args.out, paged.layout, args.bitDepth);
  const TexturedMesh& mesh = paged.mesh;
  requireUvsInImage(mesh);
  const Image& texture = paged.image;
  timer.lap("read");
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, texture.width, texture.height);
  const Image padded = dilateGutters(mesh, atlas, grid, texture, args.options);
  timer.lap("dilate");
  const PixelFormat stored =
      writePagedTexture(args.out, mesh, paged.layout, padded, args.bitDepth, args.report.quiet);
  timer.lap("write");
  printWrittenPages(args.report.quiet, args.out, paged.layout, padded, stored, -1, timer.total());
  if (args.report.timings) timer.print();
  if (args.report.json)
    printJson({{"command", "dilate"},
               {"texels", grid.unknownCount()},
               {"resolution", {texture.width, texture.height}},
               {"radius", args.options.infinite ? nlohmann::json("infinite")
                                                : nlohmann::json(args.options.radius)},
               {"changed_texels", changedTexels(texture, padded)},
               {"stages", timer.json()},
               {"output", args.out}});
}

}  // namespace

void addDilateCommand(CLI::App& app) {
  auto args = std::make_shared<DilateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "dilate",
      "Fill the gutter texels around charts so mip-mapping and bilinear lookups do not bleed "
      "background in. Texels just outside a chart take the surface value across the seam where "
      "there is one; further rings average their filled neighbours. Active texels are unchanged.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option(
      "texture", args->texture,
      std::string("Texture to pad (default: the mesh's --texture-slot texture)") + kPagedInputHelp);
  cmd->add_option("--out,-o", args->out,
                  std::string("Output image, or .gltf/.glb for a glTF copy") + kPagedOutputHelp)
      ->required();
  auto* radius = cmd->add_option("--radius", args->options.radius, "Rings of gutter texels to fill")
                     ->default_val(4)
                     ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--infinite", args->options.infinite, "Fill every gutter texel of the image")
      ->excludes(radius);
  cmd->add_option("--texture-slot", args->slot, "Texture of the mesh to use and replace")
      ->default_val("baseColor");
  cmd->add_option("--bit-depth", args->bitDepth, bitDepthHelp("the input texture's"));
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  addReportOptions(cmd, args->report);
  cmd->callback([args] { exitStatus = runGuarded([&] { runDilate(*args); }); });
}

}  // namespace texgrad::cli
