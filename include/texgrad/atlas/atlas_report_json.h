// The atlas report as JSON: what `texgrad info --json` prints and Python's Mesh.atlas_report
// returns, written in one place so the two cannot drift apart.
#pragma once

#include <string>
#include <vector>

#include "texgrad/atlas/atlas_report.h"
#include "texgrad/io/texture_page_report.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// The report, the textures `mesh` names (slot, file or null when embedded, what named it), the
/// files it names that are missing and each slot's `pages` (reportTexturePages: name, file,
/// width, height, faces; udim; problems), as a JSON object indented by two spaces; "mesh" holds
/// `meshName` (the name the user gave).
std::string atlasReportJson(const AtlasReport& report, const TexturedMesh& mesh,
                            const std::vector<SlotPages>& pages, const std::string& meshName);

}  // namespace texgrad
