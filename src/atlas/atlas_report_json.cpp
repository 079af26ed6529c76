// The JSON form of AtlasReport (keys in snake_case, as the CLI's other --json outputs).
#include "texgrad/atlas/atlas_report_json.h"

#include <nlohmann/json.hpp>

namespace texgrad {
namespace {

nlohmann::json issueJson(const AtlasIssue& issue) {
  return {{"kind", issue.kind},
          {"meaning", issue.meaning},
          {"id_kind", issue.idKind},
          {"ids", issue.ids},
          {"blocking", issue.blocking}};
}

nlohmann::json texelsJson(const TexelStats& t) {
  return {{"width", t.width},
          {"height", t.height},
          {"active", t.active},
          {"interior", t.interior},
          {"boundary", t.boundary},
          {"multi_chart_texels", t.multiChartTexels},
          {"texels_outside_image", t.texelsOutsideImage},
          {"charts_touching_border", t.chartsTouchingBorder},
          {"min_gutter_texels",
           t.minGutterTexels ? nlohmann::json(*t.minGutterTexels) : nlohmann::json(nullptr)}};
}

/// Each distinct image per slot that the mesh file names; reported, not read.
nlohmann::json texturesJson(const TexturedMesh& mesh) {
  nlohmann::json list = nlohmann::json::array();
  for (const TextureRef& t : mesh.textures)
    list.push_back(
        {{"slot", t.slot},
         {"file", t.path.empty() ? nlohmann::json(nullptr) : nlohmann::json(t.path.string())},
         {"named_by", t.origin}});
  return list;
}

/// {"baseColor": {"udim": bool, "pages": [{name, file, width, height, faces}], "problems": [...]}}
nlohmann::json pagesJson(const std::vector<SlotPages>& slots) {
  nlohmann::json j = nlohmann::json::object();
  for (const SlotPages& s : slots) {
    nlohmann::json pages = nlohmann::json::array();
    for (const TexturePage& page : s.layout.pages)
      pages.push_back({{"name", page.name},
                       {"file", page.path.empty() ? nlohmann::json(nullptr)
                                                  : nlohmann::json(page.path.string())},
                       {"width", page.width},
                       {"height", page.height},
                       {"faces", page.faces}});
    j[s.slot] = {{"udim", s.layout.udim}, {"pages", pages}, {"problems", s.problems}};
  }
  return j;
}

}  // namespace

std::string atlasReportJson(const AtlasReport& r, const TexturedMesh& mesh,
                            const std::vector<SlotPages>& pages, const std::string& meshName) {
  nlohmann::json j;
  j["mesh"] = meshName;
  j["vertices"] = r.vertices;
  j["uv_vertices"] = r.uvVertices;
  j["faces"] = r.faces;
  j["charts"] = r.charts;
  j["seam_edges"] = r.seamEdges;
  j["boundary_edges"] = r.boundaryEdges;
  j["non_manifold_edges"] = r.nonManifoldEdges;
  j["connected_components"] = r.connectedComponents;
  j["chart_faces"] = r.chartFaceCounts;
  j["chart_uv_areas"] = r.chartUvAreas;
  j["issues"] = nlohmann::json::array();
  for (const AtlasIssue& issue : r.issues) j["issues"].push_back(issueJson(issue));
  if (r.texels) j["texels"] = texelsJson(*r.texels);
  j["textures"] = texturesJson(mesh);
  j["missing_files"] = mesh.missingFiles;
  j["pages"] = pagesJson(pages);
  return j.dump(2);
}

}  // namespace texgrad
