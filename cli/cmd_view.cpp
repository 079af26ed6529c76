// `texgrad view`: serves the browser viewer for one mesh and app (filter, geodesic, react, lic,
// stitch);
// the solving is the apps', the serving the viewer module's; this file maps flags onto options.
#include <filesystem>
#include <iostream>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/image_io.h"
#include "texgrad/viewer/viewer_server.h"
#include "texgrad/viewer/viewer_session.h"

namespace texgrad::cli {
namespace {

struct ViewArgs {
  std::string mesh, texture, app = "filter", resolution, out, composite, segments;
  MeshReadOptions read;
  viewer::ViewerAppOptions appOptions;
  viewer::SessionOptions session;
  viewer::ServerOptions server;
};

/// The page an installed program ships with (<prefix>/share/texgrad/viewer, found from the
/// program's own path), else the source tree's viewer/dist of the build it came from.
std::filesystem::path defaultWebRoot() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    const std::filesystem::path installed =
        (self.parent_path() / TEXGRAD_VIEWER_FROM_BIN).lexically_normal();
    if (std::filesystem::exists(installed / "index.html", error)) return installed;
  }
  return TEXGRAD_VIEWER_DIST;
}

void runView(ViewArgs& args) {
  if (args.server.webRoot.empty()) args.server.webRoot = defaultWebRoot();
  const viewer::ViewerAppKind kind = viewer::parseViewerAppKind(args.app);
  args.appOptions.validate();
  args.session.savePath = args.out;
  args.session.validate();
  if (!args.out.empty()) checkTextureOutputArgs(args.out, args.mesh, "");
  args.server.validate();
  const bool stitch = kind == viewer::ViewerAppKind::Stitch;
  if (!stitch && (!args.composite.empty() || !args.segments.empty()))
    throw InvalidInputError("--composite and --segments are for --app stitch");
  if (stitch && !args.texture.empty() && !args.composite.empty())
    throw InvalidInputError("give the composite once: as TEXTURE or as --composite");
  if (stitch && args.composite.empty()) args.composite = args.texture;
  if (stitch && (args.composite.empty() || args.segments.empty()))
    throw InvalidInputError("--app stitch needs --composite TEXTURE and --segments MASK");
  TexturedMesh mesh = loadMesh(args.mesh, args.read);
  requireSinglePage(findTexturePages(mesh, "baseColor", stitch ? args.composite : args.texture),
                    "texgrad view",
                    "process the pages with filter, seams, geodesic, lic, react or stitch, or "
                    "view one page's image given as TEXTURE");
  Image texture = stitch ? readImage(args.composite) : loadTexture(mesh, args.mesh, args.texture);
  if (stitch) {
    args.appOptions.segments = readImage(args.segments);
    const Image& s = args.appOptions.segments;
    if (s.width != texture.width || s.height != texture.height)
      throw InvalidInputError("--segments is " + std::to_string(s.width) + "x" +
                              std::to_string(s.height) + " but --composite is " +
                              std::to_string(texture.width) + "x" + std::to_string(texture.height) +
                              "; they must match");
  }
  int width = texture.width, height = texture.height;
  if (!args.resolution.empty()) std::tie(width, height) = parseResolution(args.resolution);
  if (width != texture.width || height != texture.height)
    throw InvalidInputError("--resolution must match the texture (" +
                            std::to_string(texture.width) + "x" + std::to_string(texture.height) +
                            "); resample the texture first");
  const int32_t faces = static_cast<int32_t>(mesh.faceCount());
  std::cerr << "texgrad view: page from " << args.server.webRoot.string() << "\n";
  std::cerr << "texgrad view: building the " << width << "x" << height << " texel domain...\n";
  // The filter brush (S_beta), LIC (its metric) and stitch (S_beta) re-assemble; the geodesic
  // and reaction-diffusion apps use M and S only.
  OperatorOptions operatorOptions;
  operatorOptions.keepPieceIntegrals =
      kind != viewer::ViewerAppKind::Geodesic && kind != viewer::ViewerAppKind::React;
  TexelDomain domain(std::move(mesh), width, height, operatorOptions,
                     progressDisplay(ReportArgs{}));
  viewer::ViewerSession session(viewer::makeViewerApp(kind, domain, texture, args.appOptions),
                                faces, args.session);
  viewer::ViewerServer server(session, domain, args.server);
  if (!server.token().empty())
    std::cout << "texgrad view: bound to non-loopback " << args.server.host
              << "; every request must carry the access token " << server.token() << "\n";
  std::cout << "texgrad view: " << args.app << " app on " << domain.unknowns() << " texels, open "
            << server.url() << "\n"
            << std::flush;
  session.start();
  server.run();
  session.stop();
}

}  // namespace

void addViewCommand(CLI::App& app) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* cmd = app.add_subcommand(
      "view",
      "Serve an interactive viewer in the browser: paint filter strokes, click geodesic sources "
      "or run reaction-diffusion or LIC, and watch the solver refine one V-cycle (or time step) "
      "per "
      "frame; or stitch a composite and paint texels to lock. Binds to 127.0.0.1; any other --host "
      "prints a random access token that every request must carry.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option("texture", args->texture, "Texture (default: the mesh's base-colour texture)");
  cmd->add_option("--app", args->app, "Interactive app")
      ->check(CLI::IsMember({"filter", "geodesic", "react", "lic", "stitch"}))
      ->default_val("filter");
  cmd->add_option("--host", args->server.host, "Address to bind (IP literal or localhost)")
      ->default_val("127.0.0.1");
  cmd->add_option("--port", args->server.port, "TCP port (0: any free port)")->default_val(8080);
  cmd->add_option("--web-root", args->server.webRoot,
                  "Folder with the built page (default: share/texgrad/viewer of the prefix "
                  "this program is installed in, else the viewer/dist of its source tree)");
  cmd->add_option("--resolution", args->resolution, "WxH or N; must match the texture")
      ->check(resolutionValidator());
  cmd->add_option("--out,-o", args->out, "Where the page's Save button writes the result");
  cmd->add_option("--alpha", args->appOptions.alpha, "Filter: screening weight")->default_val(1e4);
  cmd->add_option("--beta", args->appOptions.beta, "Filter: global gradient scale")
      ->default_val(1.0);
  cmd->add_option("--sharpen-beta", args->appOptions.sharpenBeta,
                  "Filter: gradient scale the sharpen brush paints towards")
      ->default_val(3.0);
  cmd->add_option("--geodesic-alpha", args->appOptions.geodesicAlpha,
                  "Geodesic: screening weight of the diffusion step (heat time 1 / alpha)")
      ->default_val(1e3);
  cmd->add_option("--preset", args->appOptions.reactPreset,
                  "React: Gray-Scott parameters (stripes or dots)")
      ->check(CLI::IsMember({"stripes", "dots"}))
      ->default_val("stripes");
  cmd->add_option("--seed", args->appOptions.seed,
                  "React: seed of the initial spots; lic: of the noise (Reset adds 1)")
      ->default_val(1);
  cmd->add_option("--composite", args->composite,
                  "Stitch: composite texture (each texel from one source; or give it as TEXTURE)");
  cmd->add_option("--segments", args->segments,
                  "Stitch: source mask of the composite, one colour per source, black = none");
  cmd->add_option("--stitch-alpha", args->appOptions.stitchAlpha,
                  "Stitch: screening weight (larger keeps the sources' absolute colours)")
      ->default_val(1e2)
      ->check(CLI::PositiveNumber);
  cmd->add_flag("!--no-gain-compensation", args->appOptions.compensateGains,
                "Stitch: keep each source's exposure and colour cast");
  cmd->add_option("--max-fps", args->session.maxUpdatesPerSecond,
                  "Upper bound on solver steps (frames) per second")
      ->default_val(60.0);
  cmd->add_option("--max-iterations", args->session.maxIterations,
                  "Steps after a change before the solver idles")
      ->default_val(400);
  addMeshReadOptions(cmd, args->read);
  cmd->callback([args] { exitStatus = runGuarded([&] { runView(*args); }); });
}

}  // namespace texgrad::cli
