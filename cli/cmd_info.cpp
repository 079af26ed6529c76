// `texgrad info`: prints the atlas diagnostics of a mesh (text or JSON); no processing.
#include <algorithm>
#include <filesystem>
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/atlas_report.h"
#include "texgrad/atlas/atlas_report_json.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/core/path_exists.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/texture_page_report.h"
#include "texgrad/io/texture_pages.h"

namespace texgrad::cli {
namespace {

struct InfoArgs {
  std::string mesh;
  std::string resolution;
  std::string texture;
  bool json = false;
  MeshReadOptions read;
  std::string wrap = "auto";
  int maxIds = 20;
};

void printIds(const AtlasIssue& issue, int maxIds) {
  std::cout << "    " << issue.idKind << " ids:";
  const size_t shown = std::min(issue.ids.size(), static_cast<size_t>(maxIds));
  for (size_t k = 0; k < shown; ++k) std::cout << " " << issue.ids[k];
  if (issue.ids.size() > shown) std::cout << " ... (" << issue.ids.size() << " in all)";
  std::cout << "\n";
}

/// "1024x1024" or "?" when the image could not be read.
std::string sizeText(const TexturePage& page) {
  if (page.width <= 0) return "?";
  return std::to_string(page.width) + "x" + std::to_string(page.height);
}

/// Prints the pages of each slot; returns true if there is a problem to warn about.
bool printPages(const std::vector<SlotPages>& slots) {
  bool problems = false;
  for (const SlotPages& s : slots) {
    if (s.layout.pages.size() > 1 || s.layout.udim) {
      std::cout << "  " << s.slot << " pages " << s.layout.pages.size()
                << (s.layout.udim ? " (UDIM tiles)" : " (one per image)") << "\n";
      for (const TexturePage& page : s.layout.pages)
        std::cout << "    page " << page.name << ": "
                  << (page.path.empty() ? std::string("embedded") : page.path.string()) << ", "
                  << sizeText(page) << ", " << page.faces
                  << (page.faces == 1 ? " face\n" : " faces\n");
    }
    for (const std::string& problem : s.problems) std::cout << "  warning " << problem << "\n";
    problems = problems || !s.problems.empty();
  }
  return problems;
}

/// Prints the textures, their pages and missing files; returns true if there is anything to warn
/// about.
bool printTextures(const TexturedMesh& mesh, const std::vector<SlotPages>& pages) {
  for (const TextureRef& t : mesh.textures)
    std::cout << "  " << t.slot
              << " texture: " << (t.path.empty() ? std::string("embedded") : t.path.string())
              << (t.origin.empty() ? "" : ", named by " + t.origin) << ", on " << t.faces
              << (t.faces == 1 ? " face\n" : " faces\n");
  bool missingImage = false;
  for (const TextureRef& t : mesh.textures)
    if (!t.path.empty() && !hasUdimToken(t.path) && !pathExists(t.path)) {  // tiles: pages
      std::cout << "  warning the " << t.slot << " image " << t.path.string() << " (" << t.origin
                << ") was not found\n";
      missingImage = true;
    }
  for (const std::string& missing : mesh.missingFiles) std::cout << "  warning " << missing << "\n";
  const bool pageProblems = printPages(pages);
  return missingImage || !mesh.missingFiles.empty() || pageProblems;
}

void printText(const std::string& name, const AtlasReport& r, const TexturedMesh& mesh,
               const std::vector<SlotPages>& pages, int maxIds) {
  std::cout << name << "\n"
            << "  vertices " << r.vertices << ", uv vertices " << r.uvVertices << ", faces "
            << r.faces << ", surface components " << r.connectedComponents << "\n"
            << "  charts " << r.charts << ", seam edges " << r.seamEdges << ", boundary edges "
            << r.boundaryEdges << ", non-manifold edges " << r.nonManifoldEdges << "\n";
  for (size_t c = 0; c < r.chartFaceCounts.size(); ++c)
    std::cout << "    chart " << c << ": " << r.chartFaceCounts[c] << " faces, UV area "
              << r.chartUvAreas[c] << "\n";
  if (r.texels) {
    const TexelStats& t = *r.texels;
    std::cout << "  texels at " << t.width << "x" << t.height << ": active " << t.active
              << " (interior " << t.interior << ", boundary " << t.boundary << ")\n"
              << "    min gutter between charts: "
              << (t.minGutterTexels ? std::to_string(*t.minGutterTexels) + " texels" : "n/a")
              << ", texels meeting two charts: " << t.multiChartTexels
              << ", active texels outside the image: " << t.texelsOutsideImage << "\n";
  }
  const bool textureWarnings = printTextures(mesh, pages);
  if (r.issues.empty() && !textureWarnings) std::cout << "  no problems found\n";
  for (const AtlasIssue& issue : r.issues) {
    std::cout << "  " << (issue.blocking ? "ERROR " : "warning ") << issue.kind << " ("
              << issue.ids.size() << "): " << issue.meaning << "\n";
    if (!issue.ids.empty()) printIds(issue, maxIds);
  }
}

void runInfo(const InfoArgs& args) {
  const TexturedMesh mesh =
      wrapMesh(loadMesh(args.mesh, args.read), args.wrap, "baseColor", args.texture);
  const Atlas atlas = buildAtlas(mesh);
  std::optional<TexelGrid> grid;
  std::string resolution = args.resolution;
  if (resolution.empty() && !args.texture.empty() && !hasUdimToken(args.texture)) {
    const Image texture = readImage(args.texture);
    resolution = std::to_string(texture.width) + "x" + std::to_string(texture.height);
  }
  if (!resolution.empty()) {
    const auto [w, h] = parseResolution(resolution);
    grid = buildTexelGrid(mesh, atlas, w, h);
  }
  const std::vector<SlotPages> pages = reportTexturePages(mesh, args.texture);
  const AtlasReport report =
      analyzeAtlas(mesh, atlas, grid ? &*grid : nullptr, slotLayout(pages, "baseColor"));
  if (args.json) {
    std::cout << atlasReportJson(report, mesh, pages, args.mesh) << "\n";
  } else {
    printText(args.mesh, report, mesh, pages, args.maxIds);
  }
}

}  // namespace

void addInfoCommand(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "info",
      "Report the atlas structure of a mesh (charts, seams, boundary and non-manifold edges, "
      "degenerate/flipped/overlapping UVs) and, at a resolution, its texel classes. Nothing is "
      "written.");
  cmd->add_option("mesh", args->mesh, "Mesh file (.obj .ply .gltf .glb) or builtin:NAME")
      ->required();
  cmd->add_option("--resolution,-r", args->resolution,
                  "Texture size WxH (or N) for texel statistics; default: size of --texture, "
                  "else no texel statistics")
      ->check(resolutionValidator());
  cmd->add_option("--texture,-t", args->texture,
                  "Texture whose size sets the resolution when --resolution is not given; "
                  "with a UDIM token (<UDIM> or %04d) its tiles are listed as pages instead");
  cmd->add_flag("--json", args->json, "Print the report as JSON on stdout (default: text)");
  addMeshReadOptions(cmd, args->read);
  addWrapOption(cmd, args->wrap);
  cmd->add_option("--max-ids", args->maxIds, "How many element ids to list per problem (text)")
      ->default_val(20)
      ->check(CLI::NonNegativeNumber);
  cmd->callback([args] { exitStatus = runGuarded([&] { runInfo(*args); }); });
}

}  // namespace texgrad::cli
