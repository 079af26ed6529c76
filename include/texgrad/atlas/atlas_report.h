// Diagnostics of an atlas for `texgrad info`: every problem with where it is and what it means.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/io/texture_pages.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// One class of problem found in the input, with the offending element ids.
struct AtlasIssue {
  std::string kind;           ///< short key, e.g. "degenerate-uv-triangles"
  std::string meaning;        ///< one sentence: what it means for processing
  std::vector<int64_t> ids;   ///< face / vertex / texel ids (what `idKind` says)
  std::string idKind;         ///< "face", "vertex", "uv", "texel", "chart", "edge"
  bool blocking = false;      ///< true if processing will refuse this input
};

/// Texel statistics at a resolution.
struct TexelStats {
  int width = 0, height = 0;
  int64_t active = 0, interior = 0, boundary = 0;
  int64_t multiChartTexels = 0;          ///< footprint meets 2+ charts
  int64_t texelsOutsideImage = 0;        ///< active texels outside the image rectangle
  std::optional<double> minGutterTexels; ///< min distance between different charts, in texels
  std::vector<int32_t> chartsTouchingBorder;
};

/// Everything `texgrad info` reports.
struct AtlasReport {
  int64_t vertices = 0, uvVertices = 0, faces = 0;
  int64_t charts = 0, seamEdges = 0, boundaryEdges = 0, nonManifoldEdges = 0;
  int64_t connectedComponents = 0;       ///< of the 3-D surface
  std::vector<int64_t> chartFaceCounts;
  std::vector<double> chartUvAreas;
  std::vector<AtlasIssue> issues;
  std::optional<TexelStats> texels;
};

/// Analyses mesh and atlas; if a resolution is given, also the texel grid statistics. With the
/// texture's `pages` (holding every face), a UV is outside when it leaves its face's UDIM tile.
AtlasReport analyzeAtlas(const TexturedMesh& mesh, const Atlas& atlas,
                         const TexelGrid* grid = nullptr, const PageLayout* pages = nullptr);

}  // namespace texgrad
