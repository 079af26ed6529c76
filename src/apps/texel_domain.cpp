// TexelDomain: the atlas -> grid -> operators pipeline in one place.
#include "texgrad/apps/texel_domain.h"

#include <vector>

#include "texgrad/atlas/image_coverage.h"
#include "texgrad/core/error.h"

namespace texgrad {

TexelDomain::TexelDomain(TexturedMesh mesh, int width, int height, const OperatorOptions& options,
                         const ProgressCallback& progress)
    : mesh_(std::move(mesh)) {
  requireUvsInImage(mesh_);  // before any expensive work: wholly outside, nothing would change
  reportProgress(progress, "atlas", 0.0);
  atlas_ = buildAtlas(mesh_);
  grid_ = buildTexelGrid(mesh_, atlas_, width, height);
  // Nothing reads the cells' charts after the grid's classification: freed before the operators
  // are built, whose peak is the one-shot filter's (4 bytes per image texel).
  decltype(grid_.cellChart)().swap(grid_.cellChart);
  if (grid_.unknownCount() == 0)
    throw InvalidInputError("the atlas covers no texel at " + std::to_string(width) + "x" +
                            std::to_string(height) + "; check the mesh's texture coordinates");
  reportProgress(progress, "atlas", 1.0);
  operators_ = std::make_unique<TexelOperators>(mesh_, atlas_, grid_, options, progress);
}

const TexelOperators& TexelDomain::operators() const {
  if (!operators_)
    throw InvalidInputError(
        "TexelDomain::operators: the operators were handed over by "
        "releaseOperators()");
  return *operators_;
}

std::unique_ptr<TexelOperators> TexelDomain::releaseOperators() {
  if (!operators_)
    throw InvalidInputError("TexelDomain::releaseOperators: the operators were handed over before");
  return std::move(operators_);
}

void TexelDomain::releaseImageMaps(KeptMaps kept) {
  if (operators_)
    throw InvalidInputError(
        "TexelDomain::releaseImageMaps: the domain still holds its operators; hand them over "
        "(releaseOperators) first");
  if (kept == KeptMaps::None) {
    std::vector<TexelClass>().swap(grid_.texelClass);
    std::vector<int32_t>().swap(grid_.chartOfUnknown);
    grid_.unknownOfTexel.clear();
  }
  std::vector<int32_t>().swap(grid_.multiChartTexels);
  std::vector<CellCoverage>().swap(grid_.cellCoverage);
  std::vector<int32_t>().swap(grid_.overlapCells);
}

}  // namespace texgrad
