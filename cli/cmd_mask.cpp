// `texgrad mask`: writes an image of the texel classification at a resolution.
#include "cli_common.h"
#include "commands.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/image_coverage.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/atlas/texel_mask.h"
#include "texgrad/io/image_io.h"

namespace texgrad::cli {
namespace {

struct MaskArgs {
  std::string mesh;
  std::string resolution;
  std::string out;
  std::string kind = "active";
  std::string bitDepth;
  MeshReadOptions read;
  std::string wrap = "auto";
  bool quiet = false;
};

void runMask(const MaskArgs& args) {
  const MaskKind kind = parseMaskKind(args.kind);
  const auto [w, h] = parseResolution(args.resolution);
  checkImageOutputArgs(args.out, args.bitDepth);
  StageTimer timer;
  const TexturedMesh mesh =
      wrapMesh(loadMesh(args.mesh, args.read), args.wrap, "baseColor");
  requireUvsInImage(mesh);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, w, h);
  const Image mask = texelMask(grid, kind);
  const PixelFormat stored = writeImage(args.out, mask, requestedFormat(args.bitDepth));
  timer.lap("write");
  printWritten(args.quiet, args.out, mask, stored, -1, timer.total());
}

}  // namespace

void addMaskCommand(CLI::App& app) {
  auto args = std::make_shared<MaskArgs>();
  CLI::App* cmd = app.add_subcommand(
      "mask",
      "Write an image showing which texels are active, interior or boundary, which chart "
      "owns each texel, or where footprints meet several charts.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option("--resolution,-r", args->resolution, "Texture size WxH (or N)")
      ->required()
      ->check(resolutionValidator());
  cmd->add_option("--out,-o", args->out, "Output image (.png .tif .exr .jpg)")->required();
  cmd->add_option("--kind,-k", args->kind,
                  "active | boundary | interior (white on those texels), chart (a colour per "
                  "chart), coverage (white: one chart, red: footprint meets several charts)")
      ->default_val("active")
      ->check(CLI::IsMember({"active", "boundary", "interior", "chart", "coverage"}));
  cmd->add_option("--bit-depth", args->bitDepth, bitDepthHelp("8"));
  cmd->add_flag("--quiet,-q", args->quiet, "No summary line");
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  cmd->callback([args] { exitStatus = runGuarded([&] { runMask(*args); }); });
}

}  // namespace texgrad::cli
