// Everything an app needs about one mesh at one texture resolution: atlas, texel grid, operators.
#pragma once

#include <memory>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/core/progress.h"
#include "texgrad/io/textured_mesh.h"
#include "texgrad/operators/texel_operators.h"

namespace texgrad {

/// A mesh with its atlas, texel grid and operators (M, S for the unit-area immersion metric),
/// built once and shared by apps, the CLI and the viewer. Not copyable (operators refer to it).
/// A one-shot caller may take the operators over (releaseOperators) to free them early.
class TexelDomain {
 public:
  /// Builds atlas, grid (width x height) and operators; throws InvalidInputError, before any of
  /// that work, if the UVs lie wholly outside the image (requireUvsInImage), and if the atlas
  /// covers no texel at this resolution.
  TexelDomain(TexturedMesh mesh, int width, int height, const OperatorOptions& options = {},
              const ProgressCallback& progress = {});
  TexelDomain(const TexelDomain&) = delete;
  TexelDomain& operator=(const TexelDomain&) = delete;

  const TexturedMesh& mesh() const { return mesh_; }
  const Atlas& atlas() const { return atlas_; }
  /// The texel grid, without its per-cell chart labels (cellChart is empty: only the grid's own
  /// classification and the atlas report, which builds its own grid, read them).
  const TexelGrid& grid() const { return grid_; }
  /// The operators; throws InvalidInputError once releaseOperators() has handed them over.
  const TexelOperators& operators() const;
  /// Hands the operators (M, S, C, the piece integrals: ~190 bytes per active texel; only the
  /// pattern if built with OperatorOptions::deferAssembly) over to
  /// the caller, who may free them once a solver holds what it needs (filterTexture's consuming
  /// overload); mesh, atlas and grid stay. The returned object refers to this domain's mesh and
  /// grid, so it must not outlive the domain. Throws InvalidInputError if already handed over.
  std::unique_ptr<TexelOperators> releaseOperators();
  /// False once releaseOperators() has handed the operators over.
  bool hasOperators() const { return operators_ != nullptr; }
  /// What releaseImageMaps keeps: none of the maps, or those GridHierarchy::build reads (texelClass,
  /// chartOfUnknown) so that a solver can still be made, with the unknown numbering (0.19 bytes
  /// per texel) so that chartOfTexel still works.
  enum class KeptMaps { None, ClassAndChart };
  /// Frees the grid's per-texel and per-cell maps (texelClass, chartOfUnknown, unknownOfTexel,
  /// multiChartTexels, cellCoverage, overlapCells: about 2 bytes per image texel and 4 per unknown)
  /// but those `kept`, keeping its size, placement and texelOfUnknown, for a one-shot caller
  /// once nothing reads them: filterTexture's consuming overload frees all but the class and
  /// chart before its solver builds its hierarchy, and those after. Throws InvalidInputError
  /// while the domain holds its operators (they were built from them; a deferred assembly,
  /// TexelOperators::screenedSystem, reads them too: free them after it).
  void releaseImageMaps(KeptMaps kept = KeptMaps::None);
  /// False once releaseImageMaps() has freed the grid's maps.
  bool hasImageMaps() const { return !grid_.texelClass.empty(); }
  /// Number of unknowns (active texels).
  int unknowns() const { return grid_.unknownCount(); }

 private:
  TexturedMesh mesh_;
  Atlas atlas_;
  TexelGrid grid_;
  std::unique_ptr<TexelOperators> operators_;
};

}  // namespace texgrad
