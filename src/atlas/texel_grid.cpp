// buildTexelGrid: the grid's extent from the UV bounds, exact cell coverage per chart from the
// lattice clipper, then the lattice's classification (classifyLattice).
#include "texgrad/atlas/texel_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "texgrad/atlas/cell_clipping.h"
#include "texgrad/core/error.h"

namespace texgrad {
namespace {

/// A grid of more cells than this, and than kMaxImageMultiple times the image's, spans UVs
/// far outside [0, 1]^2: almost surely not an atlas.
constexpr double kTilingCells = 1u << 28;
/// Image cells a grid may span before it counts as tiling: UVs over about 2 x 2 texture widths.
constexpr double kMaxImageMultiple = 4.0;
/// Largest grid we build (cells): a 32768² texture's, its texels and a ring of cells around them
/// (cell indices are 32-bit).
constexpr double kMaxCells = 32771.0 * 32771.0;

double uvTriangleArea2(const std::array<Eigen::Vector2d, 3>& c) {
  const Eigen::Vector2d e1 = c[1] - c[0], e2 = c[2] - c[0];
  return e1.x() * e2.y() - e1.y() * e2.x();
}

void setExtent(const TexturedMesh& mesh, TexelGrid& g) {
  double lx = std::numeric_limits<double>::infinity(), ly = lx, hx = -lx, hy = -lx;
  for (const Triangle& t : mesh.uvTriangles)
    for (int32_t k : t) {
      const Eigen::Vector2d p(snapToLattice(mesh.uvs[k].x() * g.imageWidth - 0.5),
                              snapToLattice(mesh.uvs[k].y() * g.imageHeight - 0.5));
      lx = std::min(lx, p.x());
      hx = std::max(hx, p.x());
      ly = std::min(ly, p.y());
      hy = std::max(hy, p.y());
    }
  if (!(lx <= hx)) return;  // no faces: empty grid
  const double cells = (std::ceil(hx) - std::floor(lx) + 2) * (std::ceil(hy) - std::floor(ly) + 2);
  const double imageCells = (g.imageWidth + 1.0) * (g.imageHeight + 1.0);
  if (cells > std::max(kTilingCells, kMaxImageMultiple * imageCells)) {
    std::ostringstream msg;
    msg << "UV coordinates span " << (hx - lx) / g.imageWidth << " x " << (hy - ly) / g.imageHeight
        << " texture widths; texgrad needs an atlas inside about [0,1]^2 (no tiling UVs)";
    throw InvalidInputError(msg.str());
  }
  if (cells > kMaxCells) {
    std::ostringstream msg;
    msg << "a " << g.imageWidth << "x" << g.imageHeight << " texture is larger than texgrad "
        << "supports (32768x32768); downscale it or split the atlas over several pages (UDIM "
        << "tiles)";
    throw InvalidInputError(msg.str());
  }
  g.x0 = static_cast<int>(std::floor(lx));
  g.y0 = static_cast<int>(std::floor(ly));
  g.nx = static_cast<int>(std::ceil(hx)) - g.x0 + 1;
  g.ny = static_cast<int>(std::ceil(hy)) - g.y0 + 1;
}

/// Faces per parallel clipping task.
constexpr int32_t kFacesPerTask = 256;

/// A face's share of one cell.
struct CellShare {
  int32_t cell;
  int32_t chart;
  double area;
};

/// Clips faces [begin, end) to the cell lattice, appending their cell shares in face order.
void clipFaces(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& g, int32_t begin,
               int32_t end, std::vector<CellShare>& shares) {
  FaceClip clip;
  std::array<std::vector<EdgeEvent>, 3> events;
  for (int32_t f = begin; f < end; ++f) {
    std::array<Eigen::Vector2d, 3> c;
    for (int k = 0; k < 3; ++k) c[k] = g.toGrid(mesh.uvs[mesh.uvTriangles[f][k]]);
    if (uvTriangleArea2(c) == 0.0) continue;  // UV-degenerate: covers nothing
    std::array<std::span<const EdgeEvent>, 3> spans;
    for (int e = 0; e < 3; ++e) {
      events[e] = latticeCrossings(c[e], c[(e + 1) % 3]);
      spans[e] = events[e];
    }
    clipTriangleToCells(c, spans, clip);
    for (const FacePiece& piece : clip.pieces)
      shares.push_back({g.cellIndex(piece.cellX, piece.cellY), atlas.chartOfFace[f],
                        piece.full ? 1.0 : polygonArea(clip.polygon(piece))});
  }
}

/// Accumulates covered area per cell and the charts meeting each cell. Faces are clipped in
/// parallel; the sums run in face order, so the result does not depend on the thread count.
void coverCells(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& g,
                CellCover& cover) {
  const auto faces = static_cast<int32_t>(mesh.faceCount());
  const int32_t tasks = (faces + kFacesPerTask - 1) / kFacesPerTask;
  std::vector<std::vector<CellShare>> shares(static_cast<size_t>(tasks));
  tbb::parallel_for(0, tasks, [&](int32_t t) {
    clipFaces(mesh, atlas, g, t * kFacesPerTask, std::min(faces, (t + 1) * kFacesPerTask),
              shares[static_cast<size_t>(t)]);
  });
  for (std::vector<CellShare>& task : shares) {
    for (const CellShare& share : task) {
      const auto cell = static_cast<size_t>(share.cell);
      cover.area[cell] += share.area;
      int32_t& owner = cover.chart[cell];
      if (owner >= 0 && owner != share.chart) cover.severalCharts[cell] = 1;
      if (owner < 0 || share.chart < owner) owner = share.chart;
    }
    std::vector<CellShare>().swap(task);
  }
}

}  // namespace

TexelGrid buildTexelGrid(const TexturedMesh& mesh, const Atlas& atlas, int width, int height) {
  if (width <= 0 || height <= 0)
    throw InvalidInputError("texture resolution must be positive, got " + std::to_string(width) +
                            "x" + std::to_string(height));
  TexelGrid g;
  g.imageWidth = width;
  g.imageHeight = height;
  setExtent(mesh, g);
  CellCover cover(g.cellCount());
  coverCells(mesh, atlas, g, cover);
  classifyLattice(g, std::move(cover));
  return g;
}

}  // namespace texgrad
