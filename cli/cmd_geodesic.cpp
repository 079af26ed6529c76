// `texgrad geodesic`: heat-method geodesic distances from source points, written as a texture
// (paper Sec. 7.3).
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "cli_common.h"
#include "cli_pages.h"
#include "commands.h"
#include "texgrad/apps/dilate.h"
#include "texgrad/apps/distance_colour_map.h"
#include "texgrad/apps/geodesic.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"

namespace texgrad::cli {
namespace {

/// Resolution when the mesh names no texture to take the size from.
constexpr int kDefaultResolution = 1024;
/// A --source-uv farther than this many texels from every chart is refused, not snapped: it
/// names no point of the surface (points in a chart's gutter or on its edge are still snapped).
constexpr double kMaxUvSnapTexels = 2.0;

struct GeodesicArgs {
  std::string mesh, out, png, resolution, offset = "near-field", boundary = "average";
  std::vector<int64_t> sourceVertices;
  std::vector<std::string> sourceUvs, sourcePoints;
  int isolines = 10;
  GeodesicOptions options;
  SolverArgs solver;
  ReportArgs report;
  MeshReadOptions read;
  std::string wrap = "auto";
};

/// Parses `count` comma-separated numbers ("0.5,0.25"); throws InvalidInputError naming `flag`.
Eigen::VectorXd parseNumbers(const std::string& text, int count, const std::string& flag,
                             const std::string& shape) {
  Eigen::VectorXd values(count);
  std::istringstream in(text);
  for (int i = 0; i < count; ++i) {
    std::string part;
    const bool more = static_cast<bool>(std::getline(in, part, ','));
    size_t used = 0;
    double value = 0.0;
    try {
      value = more ? std::stod(part, &used) : 0.0;
    } catch (const std::exception&) {
      used = 0;
    }
    if (!more || used != part.size() || part.empty() || !std::isfinite(value))
      throw InvalidInputError(flag + " '" + text + "' is not " + shape);
    values[i] = value;
  }
  std::string rest;
  if (std::getline(in, rest)) throw InvalidInputError(flag + " '" + text + "' is not " + shape);
  return values;
}

std::vector<GeodesicSource> parseSources(const GeodesicArgs& args) {
  std::vector<GeodesicSource> sources;
  for (int64_t v : args.sourceVertices) sources.push_back(GeodesicSource::atVertex(v));
  for (const std::string& uv : args.sourceUvs)
    sources.push_back(
        GeodesicSource::atUv(parseNumbers(uv, 2, "--source-uv", "U,V (two numbers)")));
  for (const std::string& p : args.sourcePoints)
    sources.push_back(
        GeodesicSource::atPoint(parseNumbers(p, 3, "--source-point", "X,Y,Z (three numbers)")));
  if (sources.empty())
    throw InvalidInputError(
        "no source given; pass --source-vertex I, --source-uv U,V or --source-point X,Y,Z");
  return sources;
}

/// --resolution, else the size of the mesh's base-colour texture, else 1024 x 1024.
std::pair<int, int> chooseResolution(const GeodesicArgs& args, const TexturedMesh& mesh) {
  if (!args.resolution.empty()) return parseResolution(args.resolution);
  if (!mesh.texture("baseColor")) return {kDefaultResolution, kDefaultResolution};
  try {
    const Image texture = loadTexture(mesh, args.mesh, "");
    return {texture.width, texture.height};
  } catch (const Error& e) {
    std::cerr << "texgrad: note: cannot read the mesh's texture for its size (" << e.what()
              << "); using " << kDefaultResolution << "x" << kDefaultResolution << "\n";
    return {kDefaultResolution, kDefaultResolution};
  }
}

/// The mesh placed on its pages: each --resolution, else each page image's size for a
/// multi-page texture, else chooseResolution's one page.
PagedTexture placeOnGeodesicPages(const GeodesicArgs& args, TexturedMesh mesh) {
  if (args.resolution.empty())
    if (std::optional<PagedTexture> paged = placeOnPagesOfImages(mesh)) {
      checkPagedOutputArgs(args.out, paged->layout, "");
      if (!args.png.empty()) checkPagedOutputArgs(args.png, paged->layout, "");
      return std::move(*paged);
    }
  const auto [width, height] = chooseResolution(args, mesh);
  PagedTexture paged = placeOnPagesOfSize(std::move(mesh), width, height);
  checkPagedOutputArgs(args.out, paged.layout, "");
  if (!args.png.empty()) checkPagedOutputArgs(args.png, paged.layout, "");
  return paged;
}

/// "U,V" as the user would type it.
std::string uvText(const Eigen::Vector2d& uv) {
  char text[64];
  std::snprintf(text, sizeof text, "%.6g,%.6g", uv.x(), uv.y());
  return text;
}

/// Throws InvalidInputError for a UV source more than kMaxUvSnapTexels from every chart.
void requireUvSourcesOnCharts(const TexelDomain& domain, const std::vector<GeodesicSource>& sources,
                              const std::string& meshName) {
  const TexelGrid& grid = domain.grid();
  const double texel = 1.0 / std::min(grid.imageWidth, grid.imageHeight);  // UV units
  for (const GeodesicSource& s : sources) {
    if (s.kind != GeodesicSource::Kind::Uv) continue;
    const ResolvedSource r = resolveSource(domain, s);
    if (r.snapDistance <= kMaxUvSnapTexels * texel) continue;
    char distance[32];
    std::snprintf(distance, sizeof distance, "%.0f", r.snapDistance / texel);
    throw InvalidInputError("--source-uv " + uvText(s.uv) + " lies outside every chart of " +
                            meshName + " (nearest chart point at UV " + uvText(r.uv) + ", " +
                            distance +
                            " texels away); pick a UV inside a chart (`texgrad mask` "
                            "shows them) or use --source-point");
  }
}

nlohmann::json vectorJson(const Eigen::Vector2d& v) {
  return {v.x(), v.y()};
}
nlohmann::json vectorJson(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

void runGeodesic(GeodesicArgs args) {
  StageTimer timer;
  args.options.solver = args.solver.settings();
  args.options.offset = parseGeodesicOffset(args.offset);
  args.options.boundary = parseGeodesicBoundary(args.boundary);
  args.options.validate();
  const std::vector<GeodesicSource> sources = parseSources(args);
  checkImageOutputArgs(args.out, "");
  if (!args.png.empty()) checkImageOutputArgs(args.png, "");
  const ProgressCallback progress = progressDisplay(args.report);
  reportProgress(progress, "read", 0.0);
  TexturedMesh mesh = loadMesh(args.mesh, args.read);
  for (const GeodesicSource& s : sources)  // fail before the expensive operator build
    if (s.kind == GeodesicSource::Kind::Vertex &&
        (s.vertex < 0 || s.vertex >= static_cast<int64_t>(mesh.positions.size())))
      throw InvalidInputError("--source-vertex " + std::to_string(s.vertex) + " is out of range; " +
                              args.mesh + " has " + std::to_string(mesh.positions.size()) +
                              " vertices (0-based)");
  mesh = wrapMesh(std::move(mesh), args.wrap, "baseColor");  // vertex indices are kept
  PagedTexture paged = placeOnGeodesicPages(args, std::move(mesh));
  if (!args.sourceUvs.empty())
    requireSinglePage(paged.layout, "--source-uv", "use --source-point or --source-vertex");
  const int width = paged.layout.width, height = paged.layout.height;
  reportProgress(progress, "read", 1.0);
  timer.lap("read");
  const TexelDomain domain(std::move(paged.mesh), width, height, OperatorOptions::assembledOnce(),
                           progress);
  requireUvSourcesOnCharts(domain, sources, args.mesh);
  timer.lap("operators");
  const GeodesicResult result = geodesicDistance(domain, sources, args.options, progress);
  timer.lap("geodesic");
  reportProgress(progress, "write", 0.0);

  Image distances(width, height, 1, PixelFormat::Float);
  scatterTexels(domain.grid(), result.distances, distances);
  const PixelFormat stored = writePagedImage(
      args.out, paged.layout,
      dilateGutters(domain.mesh(), domain.atlas(), domain.grid(), distances), PixelFormat::Float);
  std::optional<PixelFormat> pictureStored;
  Image picture;
  if (!args.png.empty()) {
    picture = dilateGutters(
        domain.mesh(), domain.atlas(), domain.grid(),
        distanceColourMap(domain.grid(), result.distances, result.maxDistance, args.isolines));
    pictureStored = writePagedImage(args.png, paged.layout, picture, PixelFormat::UInt8);
  }
  reportProgress(progress, "write", 1.0);
  timer.lap("write");
  printWrittenPages(args.report.quiet, args.out, paged.layout, distances, stored, domain.unknowns(),
                    timer.total());
  if (pictureStored)
    printWrittenPages(args.report.quiet, args.png, paged.layout, picture, *pictureStored, -1,
                      timer.total());
  if (args.report.timings) timer.print();
  if (!args.report.json) return;
  nlohmann::json resolved = nlohmann::json::array();
  for (const ResolvedSource& s : result.sources)
    resolved.push_back({{"uv", vectorJson(s.uv)},
                        {"position", vectorJson(s.position)},
                        {"face", s.point.face},
                        {"snap_distance", s.snapDistance}});
  printJson(
      {{"command", "geodesic"},
       {"texels", domain.unknowns()},
       {"resolution", {width, height}},
       {"alpha", args.options.alpha},
       {"offset", toString(args.options.offset)},
       {"boundary", toString(args.options.boundary)},
       {"solver", toString(args.options.solver.kind)},
       {"units", "model"},
       {"unit_scale", std::sqrt(domain.operators().report().metric.surfaceArea)},
       {"sources", resolved},
       {"max_distance", result.maxDistance},
       {"unreachable_texels", result.unreachableTexels},
       {"farthest",
        {{"uv", vectorJson(result.farthestUv)}, {"position", vectorJson(result.farthestPosition)}}},
       {"diffusion", toJson(result.diffusionReport)},
       {"distance", toJson(result.distanceReport)},
       {"geodesic_seconds",
        {{"setup", result.timings.setup},
         {"diffusion", result.timings.diffusion},
         {"divergence", result.timings.divergence},
         {"distance", result.timings.distance}}},
       {"stages", timer.json()},
       {"peak_rss_bytes", peakResidentBytes()},
       {"output", args.out},
       {"png", args.png}});
}

}  // namespace

void addGeodesicCommand(CLI::App& app) {
  auto args = std::make_shared<GeodesicArgs>();
  CLI::App* cmd = app.add_subcommand(
      "geodesic",
      "Geodesic distance on the surface from one or more source points, by the heat method "
      "(paper Sec. 7.3): diffuse a unit impulse, (alpha M + S) u = delta, then solve "
      "S y = div(-grad u / |grad u|). Writes one float channel of distances in model units "
      "(the mesh's own length unit), ~0 at the sources; +inf on parts of the surface no source "
      "connects to; gutter texels are padded.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option(
         "--out,-o", args->out,
         std::string("Distance image, one float channel (.exr recommended)") + kPagedOutputHelp)
      ->required();
  cmd->add_option("--png", args->png,
                  "Also write a colour picture: viridis from 0 to the largest distance, with "
                  "--isolines contour lines");
  cmd->add_option("--isolines", args->isolines,
                  "Contour lines in the --png picture, equally spaced between 0 and the largest "
                  "distance (0 = none)")
      ->default_val(10)
      ->check(CLI::Range(0, 10000));
  cmd->add_option("--source-vertex", args->sourceVertices,
                  "Source at a mesh vertex (0-based index into the file's positions); repeatable")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option(
         "--source-uv", args->sourceUvs,
         "Source at texture coordinates U,V of the image (after --wrap has moved the charts "
         "into it; snapped to the nearest chart; refused if more than 2 texels outside every "
         "chart); repeatable")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--source-point", args->sourcePoints,
                  "Source at the surface point nearest to X,Y,Z (model units); repeatable")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--resolution,-r", args->resolution,
                  "Texture size WxH (or N); default: the mesh's texture size, else 1024")
      ->check(resolutionValidator());
  cmd->add_option("--alpha", args->options.alpha,
                  "Diffusion screening on the unit-area surface (heat time 1/alpha): larger "
                  "follows the surface more tightly near the source, smaller smooths the distance "
                  "and loses precision far away; paper default 1e3")
      ->default_val(1e3)
      ->check(positiveValidator());
  cmd->add_option("--offset", args->offset,
                  "How the distance constant is fixed: near-field (match the straight-line "
                  "distance 2-4 texels from each source; removes a ~0.4-texel bias) or source "
                  "(exactly 0 at the sources, as in the paper)")
      ->default_val("near-field")
      ->check(CLI::IsMember({"near-field", "source"}));
  cmd->add_option("--boundary", args->boundary,
                  "On meshes with open boundary: average (mean of Neumann and Dirichlet "
                  "diffusions, Crane et al. 2013; level sets do not bend at the boundary) or "
                  "neumann (paper; one system less)")
      ->default_val("average")
      ->check(CLI::IsMember({"average", "neumann"}));
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  addSolverOptions(cmd, args->solver, GeodesicOptions().solver);
  addReportOptions(cmd, args->report);
  cmd->callback([args] { exitStatus = runGuarded([&] { runGeodesic(*args); }); });
}

}  // namespace texgrad::cli
