// Apps (private): the one-point quadrature samples of the texel-basis gradients behind the heat
// method's normalised-gradient divergence (paper Sec. 7.3), streamed once per geodesic update.
#pragma once

#include <tbb/task_arena.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <cstdint>
#include <vector>

#include "texgrad/apps/geodesic.h"

namespace texgrad {

/// Unknowns per parallel task in the geodesic app's per-unknown loops.
constexpr Eigen::Index kGeodesicUnknownsPerTask = 1 << 14;

/// One-point quadrature samples of the texel-basis gradients (paper Sec. 7.3): one per plain
/// piece T ∩ cell (at its centroid) and one per quadratic element of seam pieces (at its
/// centroid). div_h(omega)_t = sum_q weight_q dphi_t(q) . X_q with X_q = g^-1 omega_q.
struct GeodesicGradients {
  /// Piece with exactly bilinear basis: four cell texels, centroid in cell-local coordinates.
  /// Compact (the divergence streams every sample once per update); the metric comes from the
  /// face.
  struct CellSample {
    std::array<int32_t, 4> texels;  ///< order (a,b), (a+1,b), (a,b+1), (a+1,b+1); -1 if absent
    int32_t cellX;                  ///< a
    float fx, fy;                   ///< centroid, cell-local
    float area;                     ///< area in texel units
    int32_t face;                   ///< index into faceMetrics
  };
  /// Per face: sqrt|g| and g^-1.
  struct FaceMetric {
    double root = 0.0, hxx = 0.0, hxy = 0.0, hyy = 0.0;
  };
  /// Quadratic element of a seam piece: gradients of its local texels at the centroid.
  struct SeamSample {
    int32_t begin, end;  ///< range in seamTexels / seamGradients
    double weight, hxx, hxy, hyy;
  };

  std::vector<CellSample> cells;  ///< sorted by cell row, then cell column (stable)
  std::vector<FaceMetric> faceMetrics;
  std::vector<int64_t> rowBegin;  ///< cells of row b: [rowBegin[b + 1], rowBegin[b + 2]), b >= -1
  std::vector<SeamSample> seams;
  std::vector<int32_t> seamTexels;
  std::vector<Eigen::Vector2d> seamGradients;
  std::vector<Eigen::Vector2d> seamDirections;  ///< per seam sample: X of the last divergence
  std::vector<int32_t> seamTargets;             ///< the distinct texels of seamTexels, ascending
  std::vector<int32_t> seamTargetOfEntry;  ///< per seam entry: index of its texel in seamTargets
  std::vector<double> seamSums;            ///< per seam target: sum of the last divergence
  /// Area of one chart's piece inside one cell, and that area times tr(g^-1) sqrt|g| of its face.
  struct CellCover {
    int32_t cell, chart;  ///< TexelGrid::cellIndex, Atlas chart
    double area, stiffness;
  };
  /// Cut cell (covered by one chart, not fully, four active texels) and the weight of its twist
  /// penalty (see stabiliser()).
  struct CutCell {
    std::array<int32_t, 4> texels;  ///< cell texels in CellSample order
    double weight;
  };
  std::vector<CutCell> cutCells;
  tbb::task_arena arena;

  /// Samples of `domain`, built and later summed on `threads` threads (0: all).
  GeodesicGradients(const TexelDomain& domain, int threads);

  void build(const TexelDomain& domain);
  /// Fills cutCells from the per-piece covers (cell, chart, area, area * tr(g^-1) sqrt|g|).
  void collectCutCells(const fem::TexelBasis& basis, const TexelGrid& grid,
                       std::vector<CellCover> covers);
  /// Ghost penalty for the distance step (n x n, unit-area surface, PSD, 3 x 3 texel pattern):
  /// sum over cut cells of weight * (y00 - y10 - y01 + y11)^2. The twist y00 - y10 - y01 + y11
  /// vanishes on linear functions, so the penalty is consistent; it gives the uncovered part of
  /// each cut cell the stiffness the twist mode would have if the cell were covered, so a texel
  /// that its chart barely covers takes the value the plane through its cell extends to.
  Eigen::SparseMatrix<double> stabiliser(Eigen::Index n) const;
  /// Frees every sample and cut cell (the arena stays): for a one-shot caller that has taken
  /// the divergence and the stabiliser it needs.
  void releaseSamples();
  /// Sets div (n values) to div_h(-du/|du|) of the function with coefficients u (one-point
  /// quadrature).
  void divergence(const double* u, double* div, Eigen::Index n);
  /// The cell-sample part of divergence for the samples [first, last) of one cell row.
  static void addRowDivergence(const CellSample* first, const CellSample* last,
                               const FaceMetric* metrics, const double* u, double* div);
};

}  // namespace texgrad
