// Steps 3-5 of the function space (paper Sec. 4.1): the seam-continuous texel
// basis phi_t built from quadratic Lagrange elements on the cell pieces, plus point evaluation.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <random>
#include <span>
#include <utility>
#include <vector>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/atlas/cell_clipping.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad::fem {

/// Which function space the texels span.
enum class BasisKind : uint8_t {
  SeamContinuous,  ///< phi_t of paper Sec. 4.1: continuous across seams, partition of unity
  Bilinear,  ///< B_t restricted to M (Sec. 4.2 baseline, discontinuous across seams; see E_C)
};

/// Options of TexelBasis.
struct TexelBasisOptions {
  BasisKind kind = BasisKind::SeamContinuous;  ///< function space
  /// Checks the options; throws InvalidInputError naming the bad field.
  void validate() const;
};

/// A texel (by unknown index, TexelGrid::unknownOfTexel) and a coefficient or value.
struct TexelWeight {
  int32_t unknown = -1;
  double weight = 0.0;
};

/// A point of M: a face and a point of its UV triangle in grid coordinates (TexelGrid::toGrid).
struct SurfacePoint {
  int32_t face = -1;
  Eigen::Vector2d grid = Eigen::Vector2d::Zero();
};

/// What the basis construction saw; counts of inputs it could not represent exactly.
struct BasisReport {
  int uvDegenerateFaces = 0;   ///< faces with zero UV area: not part of M (their 3-D area is lost)
  int skippedSeams = 0;        ///< seams touching a UV-degenerate face (treated as open boundary)
  int seamVertexClasses = 0;   ///< mesh vertices merged across seams (classes of size > 1)
};

/// Basis data of one piece T ∩ cell that is not plain bilinear: fan triangulation (quadratic
/// elements, paper Sec. 4.1 step 1-2) and node coefficients B_{n,t} (step 3).
struct PieceBasis {
  std::vector<int32_t> texels;  ///< local texels (unknowns, ascending)
  /// Triangles of the fan (counter-clockwise, grid coordinates).
  std::vector<std::array<Eigen::Vector2d, 3>> elements;
  /// Row 6 e + n: coefficients of node n of element e on the local texels; nodes 0..2 are the
  /// corners, 3..5 the midpoints of edges (0,1), (1,2), (2,0).
  Eigen::MatrixXd coefficients;
};

/// A seam as the basis splits it: its two face edges and the parameters (along side 0) where
/// either side crosses a lattice line, so that between two breaks both sides stay in one cell.
struct SeamTrace {
  std::array<FaceEdge, 2> edge;  ///< side 0 and side 1 (from corner `corner` to the next)
  bool sameDirection = false;    ///< parameter s on side 0 is s on side 1 (else 1 - s)
  std::vector<double> breaks;    ///< ascending, from 0 to 1 inclusive
};

/// Quadratic Lagrange shape functions at barycentric coordinates b (node order of PieceBasis).
std::array<double, 6> quadraticShape(const Eigen::Vector3d& b);

/// The texel basis of one mesh + atlas + grid: clips faces on demand, knows the seam-equivalence
/// classes of nodes, evaluates phi_t anywhere on M. The mesh and grid must outlive it.
class TexelBasis {
 public:
  /// Precomputes seam splits (paper Sec. 4.1) and vertex classes; O(faces + seam length).
  TexelBasis(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& grid,
             const TexelBasisOptions& options = {});

  /// Grid the unknowns live on.
  const TexelGrid& grid() const { return grid_; }
  /// Mesh the basis was built on.
  const TexturedMesh& mesh() const { return mesh_; }
  /// Options the basis was built with.
  const TexelBasisOptions& options() const { return options_; }
  /// Construction diagnostics.
  const BasisReport& report() const { return report_; }
  /// Number of faces of the mesh.
  int faceCount() const { return static_cast<int>(corners_.size()); }
  /// True if face f has positive UV area (is part of M).
  bool faceValid(int face) const { return valid_[face] != 0; }
  /// Grid coordinates of face f's corners.
  const std::array<Eigen::Vector2d, 3>& faceCorners(int face) const { return corners_[face]; }

  /// Clips face f into pieces T ∩ cell with all seam points inserted (no pieces if invalid).
  void clipFace(int face, FaceClip& clip) const;
  /// True if phi restricted to the piece is exactly bilinear (no node of it is on a seam).
  bool isPlain(int face, std::span<const PieceVertex> polygon) const;
  /// Builds the quadratic elements and node coefficients of a piece of face f.
  void buildPieceBasis(int face, std::span<const PieceVertex> polygon, PieceBasis& out) const;
  /// Appends the bilinear weights B_t(p) of the (up to four) texels around p, dropping zeros.
  void bilinearWeights(const Eigen::Vector2d& p, std::vector<TexelWeight>& out,
                       double scale = 1.0) const;
  /// Unknowns of the four texels of cell (a, b) in the order (a,b), (a+1,b), (a,b+1), (a+1,b+1);
  /// -1 for texels that are inactive or outside the grid.
  std::array<int32_t, 4> cellTexels(int a, int b) const;

  /// Number of seams the basis joins (seams touching UV-degenerate faces are left out).
  int seamCount() const { return static_cast<int>(seams_.size()); }
  /// Seam i with its break parameters.
  SeamTrace seamTrace(int seam) const;

  /// phi_t(point) for every texel with a nonzero value, ascending by unknown. A point within
  /// rounding of a face edge is evaluated on that edge (phi can be steep across thin seam pieces).
  std::vector<TexelWeight> evaluate(const SurfacePoint& point) const;
  /// sum_t x_t phi_t(point).
  double evaluate(const SurfacePoint& point, const Eigen::VectorXd& x) const;
  /// A point of M drawn uniformly with respect to UV area.
  SurfacePoint randomPoint(std::mt19937_64& rng) const;
  /// A random pair of seam-equivalent points p ~ q (same surface point on two sides of a seam).
  std::pair<SurfacePoint, SurfacePoint> randomSeamPair(std::mt19937_64& rng) const;
  /// Barycentric coordinates of a point with respect to its face's UV triangle.
  Eigen::Vector3d barycentric(const SurfacePoint& point) const;
  /// 3-D position (mesh units) of a point of M.
  Eigen::Vector3d position(const SurfacePoint& point) const;

 private:
  struct SeamSplit {
    std::array<std::vector<EdgeEvent>, 2> side;  ///< events along each side's face edge
    std::array<FaceEdge, 2> edge;
    bool sameDirection = false;
  };
  int seamSide(int face, int edge) const { return seamSideOfEdge_[3 * face + edge]; }
  /// Where a point lies in its face's clip: a piece and, for points on a face edge, the
  /// polygon segment (index of its first vertex) and the parameter along it.
  struct Location {
    const FacePiece* piece = nullptr;
    int segment = -1;
    double parameter = 0.0;
  };
  /// Face edge the point lies on up to rounding of its coordinates, or -1.
  int edgeOfPoint(const SurfacePoint& point) const;
  /// Piece (and edge segment) of the face's clip that holds the point.
  Location locate(const SurfacePoint& point, const FaceClip& clip) const;
  Eigen::Vector2d partnerPoint(int seamSide, int index) const;
  int edgeIndex(int face, const PieceVertex& v, int edge) const;
  void vertexWeights(int face, const PieceVertex& v, std::vector<TexelWeight>& out) const;
  void midpointWeights(int face, const PieceVertex& v, const PieceVertex& w,
                       std::vector<TexelWeight>& out) const;
  void buildSeams(const Atlas& atlas);
  void buildVertexClasses();

  const TexturedMesh& mesh_;
  const TexelGrid& grid_;
  TexelBasisOptions options_;
  BasisReport report_;
  std::vector<std::array<Eigen::Vector2d, 3>> corners_;
  std::vector<uint8_t> valid_;
  std::vector<double> cumulativeArea_;
  std::vector<SeamSplit> seams_;
  std::vector<int32_t> seamSideOfEdge_;  ///< per 3 f + e: 2 * seam + side, or -1
  std::vector<int32_t> classOfCorner_;   ///< per 3 f + c: vertex class with > 1 node, or -1
  std::vector<int32_t> classBegin_;      ///< class c's weights: classWeights_[begin[c], begin[c+1])
  std::vector<TexelWeight> classWeights_;
};

/// Merges duplicate unknowns (summing in order) and sorts ascending; removes exact zeros.
void mergeWeights(std::vector<TexelWeight>& weights);

}  // namespace texgrad::fem
