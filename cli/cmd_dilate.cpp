// `texgrad dilate`: pads the gutters of a texture (seam-aware first ring, then averaging rings).
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "texgrad/apps/dilate.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/image_coverage.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/image_io.h"

namespace texgrad::cli {
namespace {

struct DilateArgs {
  std::string mesh, texture, out, bitDepth;
  DilateOptions options;
  double weldTolerance = 0.0;
  bool quiet = false;
};

void runDilate(const DilateArgs& args) {
  args.options.validate();
  checkImageOutputArgs(args.out, args.bitDepth);
  StageTimer timer;
  const TexturedMesh mesh = loadMesh(args.mesh, args.weldTolerance);
  requireUvsInImage(mesh);
  const Image texture = loadTexture(mesh, args.mesh, args.texture);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, texture.width, texture.height);
  const Image padded = dilateGutters(mesh, atlas, grid, texture, args.options);
  const PixelFormat stored = writeImage(args.out, padded, requestedFormat(args.bitDepth));
  timer.lap("write");
  printWritten(args.quiet, args.out, padded, stored, -1, timer.total());
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
  cmd->add_option("texture", args->texture,
                  "Texture to pad (default: the mesh's base-colour texture)");
  cmd->add_option("--out,-o", args->out, "Output image")->required();
  auto* radius = cmd->add_option("--radius", args->options.radius, "Rings of gutter texels to fill")
                     ->default_val(4)
                     ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--infinite", args->options.infinite, "Fill every gutter texel of the image")
      ->excludes(radius);
  cmd->add_option("--bit-depth", args->bitDepth, bitDepthHelp("the input texture's"));
  cmd->add_flag("--quiet,-q", args->quiet, "No summary line");
  addWeldToleranceOption(cmd, args->weldTolerance);
  cmd->callback([args] { exitStatus = runGuarded([&] { runDilate(*args); }); });
}

}  // namespace texgrad::cli
