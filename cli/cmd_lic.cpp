// `texgrad lic`: line integral convolution of a per-face vector field or of principal curvature
// directions, computed in the atlas with an anisotropic metric (paper §7.4).
#include <iostream>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "texgrad/apps/dilate.h"
#include "texgrad/apps/lic.h"
#include "texgrad/apps/vector_field.h"
#include "texgrad/core/error.h"
#include "texgrad/io/uv_tiles.h"

namespace texgrad::cli {
namespace {

struct LicArgs {
  std::string mesh, out, field, curvature = "max", resolution = "512", bitDepth;
  bool intrinsic = false, colour = false;
  int smoothing = CurvatureOptions{}.smoothingRounds;
  LicOptions options;
  SolverArgs solver;
  ReportArgs report;
  MeshReadOptions read;
  std::string wrap = "auto";
};

/// The --field file's vectors on the faces of the wrapped mesh (3-D vectors: a piece of a face
/// cut at a tile border has other edges), or the curvature field of the wrapped mesh (as the
/// Python module computes it on the mesh it is given).
FaceVectorField loadField(const LicArgs& args, TexturedMesh& mesh) {
  if (args.field.empty()) {
    mesh = wrapMesh(std::move(mesh), args.wrap, "baseColor");
    CurvatureOptions curvature;
    curvature.smoothingRounds = args.smoothing;
    return curvatureField(
        mesh, args.curvature == "min" ? CurvatureDirection::Minor : CurvatureDirection::Major,
        curvature);
  }
  const FieldBasis basis = args.intrinsic ? FieldBasis::Intrinsic : FieldBasis::Extrinsic;
  FaceVectorField field =
      extrinsicField(mesh, readFaceVectorField(args.field, basis, mesh.faceCount()));
  std::vector<int32_t> parentFace;
  mesh = wrapMesh(std::move(mesh), args.wrap, "baseColor", {}, &parentFace);
  field.vectors = followParentFaces(field.vectors, parentFace);
  return field;
}

void runLic(LicArgs args) {
  StageTimer timer;
  args.options.solver = args.solver.settings();
  args.options.channels = args.colour ? 3 : 1;
  args.options.validate();
  checkTextureOutputArgs(args.out, args.mesh, args.bitDepth);
  const auto [width, height] = parseResolution(args.resolution);
  const ProgressCallback progress = progressDisplay(args.report);
  reportProgress(progress, "read", 0.0);
  TexturedMesh mesh = loadMesh(args.mesh, args.read);
  const FaceVectorField field = loadField(args, mesh);  // wraps the mesh
  reportProgress(progress, "read", 1.0);
  timer.lap("read");
  PagedTexture paged = placeOnPagesOfSize(std::move(mesh), width, height);
  checkPagedOutputArgs(args.out, paged.layout, args.bitDepth);
  TexelDomain domain(std::move(paged.mesh), paged.layout.width, paged.layout.height, {}, progress);
  timer.lap("operators");
  const auto fieldTexel = fieldInTexelCoordinates(domain.mesh(), domain.grid(), field);
  const LicResult result = lineIntegralConvolution(domain, domain.releaseOperators(), fieldTexel,
                                                   args.options, progress);
  timer.lap("solve");
  const Image padded = dilateGutters(domain.mesh(), domain.atlas(), domain.grid(), result.image);
  const PixelFormat stored = runStage(progress, "write", [&] {
    return writePagedTexture(args.out, domain.mesh(), paged.layout, padded, args.bitDepth,
                             args.report.quiet);
  });
  timer.lap("write");
  printWrittenPages(args.report.quiet, args.out, paged.layout, padded, stored, domain.unknowns(),
                    timer.total());
  const bool sharpened = args.options.sharpenBeta != 1.0;
  if (!result.report.diffusion.converged || (sharpened && !result.report.sharpening.converged))
    std::cerr << "texgrad: warning: an LIC solve stopped before reaching its tolerance "
                 "(diffusion residual "
              << result.report.diffusion.residuals.back()
              << "); raise --max-iterations (cg) or --cycles (multigrid), or use --solver "
                 "direct\n";
  if (args.report.timings) timer.print();
  if (args.report.json)
    printJson({{"command", "lic"},
               {"texels", domain.unknowns()},
               {"resolution", {width, height}},
               {"field", args.field.empty() ? "curvature " + args.curvature : args.field},
               {"zero_field_faces", result.report.zeroFieldFaces},
               {"solver", toString(args.options.solver.kind)},
               {"setup_seconds", result.report.setupSeconds},
               {"solver_setup_seconds", result.report.solverSetupSeconds},
               {"diffusion", toJson(result.report.diffusion)},
               {"sharpening", toJson(result.report.sharpening)},
               {"stages", timer.json()},
               {"peak_rss_bytes", peakResidentBytes()},
               {"output", args.out}});
}

}  // namespace

void addLicCommand(CLI::App& app) {
  auto args = std::make_shared<LicArgs>();
  CLI::App* cmd = app.add_subcommand(
      "lic",
      "Line integral convolution (paper Sec. 7.4): random noise is diffused along a tangent "
      "vector field by solving (alpha M_h + S_h) x = alpha M_h noise with a metric h that "
      "shrinks lengths along the field, then sharpened in the gradient domain. The texture shows "
      "streaks following the field, continuous across seams. Field: a per-face file (--field) or "
      "principal curvature directions scaled by |k1 - k2| (--curvature, the default).");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option("--out,-o", args->out,
                  "Output image (.png .jpg .exr .tif), or .gltf/.glb for a copy of a glTF asset "
                  "with the LIC texture as base colour" +
                      std::string(kPagedOutputHelp))
      ->required();
  auto* field = cmd->add_option(
      "--field", args->field,
      "Vector field file: int32 count (= number of faces), then per face 3 float64 (a 3-D "
      "vector) or, with --intrinsic, 2 float64 (a, b) meaning a (v1 - v0) + b (v2 - v0); "
      "little-endian, in face order");
  cmd->add_flag("--intrinsic", args->intrinsic,
                "The --field file holds 2 coefficients per face on the face's edges")
      ->needs(field);
  cmd->add_option("--curvature", args->curvature,
                  "Principal direction to follow when no --field is given: max (larger |k|, "
                  "e.g. around a cylinder) or min (smaller |k|, along it)")
      ->default_val("max")
      ->check(CLI::IsMember({"max", "min"}))
      ->excludes(field);
  cmd->add_option("--curvature-smoothing", args->smoothing,
                  "Rounds of averaging the estimated shape operator over neighbouring faces "
                  "(more = smoother directions on noisy meshes)")
      ->default_val(args->smoothing)
      ->check(CLI::Range(0, 1000))
      ->excludes(field);
  cmd->add_option("--resolution,-r", args->resolution, "Output texture size WxH (or N)")
      ->default_val("512")
      ->check(resolutionValidator());
  cmd->add_option("--seed", args->options.seed, "Seed of the noise (same seed, same texture)")
      ->default_val(1);
  cmd->add_option("--epsilon", args->options.epsilon,
                  "Isotropic part of the metric relative to the (normalised) field: streaks are "
                  "about 1/sqrt(epsilon) times longer than wide; smaller = streakier, harder "
                  "to solve")
      ->default_val(1e-4)
      ->check(positiveValidator());
  cmd->add_option("--alpha", args->options.alpha,
                  "Screening weight of the diffusion: smaller = longer streaks (length ~ "
                  "epsilon^-1/4 / sqrt(alpha) on the unit-area surface)")
      ->default_val(1e4)
      ->check(positiveValidator());
  cmd->add_option("--sharpen", args->options.sharpenBeta,
                  "Gradient gain of the sharpening step that restores contrast across streaks; "
                  "1 = no sharpening")
      ->default_val(100.0)
      ->check(nonNegativeValidator());
  cmd->add_option("--sharpen-alpha", args->options.sharpenAlpha,
                  "Screening weight of the sharpening: larger = only finer detail is boosted")
      ->default_val(1e4)
      ->check(positiveValidator());
  cmd->add_flag("--color,--colour", args->colour,
                "Colour noise (random hues) instead of grey noise");
  cmd->add_option("--bit-depth", args->bitDepth, bitDepthHelp("8"));
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  // Plain V-cycles stall on the anisotropic metric (paper Sec. 8): default to multigrid-CG.
  addSolverOptions(cmd, args->solver, defaultLicSolver());
  addReportOptions(cmd, args->report);
  cmd->callback([args] { exitStatus = runGuarded([&] { runLic(*args); }); });
}

}  // namespace texgrad::cli
