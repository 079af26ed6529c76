// Operators of paper Sec. 5 on the texel basis (fem/): mass M, stiffness S, per-cell stiffness
// modulation, the texel-pair list A, d, the Whitney Hodge star *1, mass_h and div_h.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/core/float_system.h"
#include "texgrad/core/progress.h"
#include "texgrad/fem/metric.h"
#include "texgrad/fem/texel_basis.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// Sparse matrix type of all operators (column-major, int indices).
using SparseMatrixd = Eigen::SparseMatrix<double>;
/// Read-only view of a SparseMatrixd whose storage another object owns (the stiffness matrix
/// shares the mass matrix's index arrays). Binding it to `const SparseMatrixd&` copies it.
using SparseViewd = Eigen::Map<const SparseMatrixd>;
/// Parameter type that binds a SparseMatrixd or a SparseViewd without copying either.
using SparseRefd = Eigen::Ref<const SparseMatrixd>;
/// Mean of the diagonal entries of a square sparse matrix (0 for an empty one).
double meanDiagonal(const SparseRefd& a);
/// Bytes allocated by a sparse matrix: values and inner indices (their capacity), the outer
/// indices, and the per-column counts of an uncompressed matrix.
int64_t sparseStorageBytes(const SparseMatrixd& a);

/// Options of TexelOperators.
struct OperatorOptions {
  fem::BasisKind basis = fem::BasisKind::SeamContinuous;  ///< function space (paper Sec. 4)
  /// lambda of paper Sec. 4.2: weight of the soft seam-continuity energy E_C in
  /// screenedSystem() (alpha M + S + alpha lambda C). Only for the Bilinear basis (the
  /// seam-continuous basis needs none); larger values pull the two sides of every seam together.
  double seamContinuityWeight = 0.0;
  int facesPerTask = 64;  ///< faces per parallel task; fixed so results do not depend on threads
  /// Keep the per-piece integrals after the first assembly, so that setMetric() and
  /// modulatedStiffness() can re-assemble; false never holds them all (40-70 bytes per active
  /// texel, 140 MB for spot at 2048²): the plain pieces are integrated and assembled a window
  /// of cell rows at a time, into the same M and S bit for bit, for callers that only use M, S
  /// and the products below.
  bool keepPieceIntegrals = true;
  /// Stop the constructor once the pattern is built: M and S are assembled later, by the
  /// visiting TexelOperators::screenedSystem, straight into alpha M + S without ever holding S
  /// whole (docs/memory.md). Needs keepPieceIntegrals = false.
  bool deferAssembly = false;
  /// Checks the options; throws InvalidInputError naming the bad field.
  void validate() const;
  /// Defaults for callers that never re-assemble (no setMetric or modulatedStiffness): the
  /// piece integrals are freed once M and S are assembled.
  static OperatorOptions assembledOnce();
};

/// A scalar signal on the surface (psi of paper Sec. 5.3), evaluated at points of M.
using SurfaceScalar = std::function<double(const fem::SurfacePoint&)>;
/// A 1-form on the surface (omega of paper Sec. 5.3) as components (w_x, w_y) on the texel
/// coordinate differentials dx, dy of the point's face; for a 3-D gradient v use J^T v.
using SurfaceOneForm = std::function<Eigen::Vector2d(const fem::SurfacePoint&)>;

/// An entry of a matrix formed from M and S on their shared pattern: (row, column, M_rc, S_rc).
using EntryCombination =
    std::function<double(Eigen::Index row, Eigen::Index column, double mass, double stiffness)>;

/// One complete column of M and of S (their rows too: both are symmetric), as the visiting
/// TexelOperators::screenedSystem hands it out before combining it into alpha M + S.
struct OperatorColumn {
  int column = 0;                     ///< the unknown
  std::span<const int> rows;          ///< its rows, ascending (the shared pattern)
  std::span<const double> mass;       ///< M's entries at those rows
  std::span<const double> stiffness;  ///< S's entries at those rows (S 1 = 0 formed)
};
/// Sees each column of M and S once; called concurrently for different columns (may be empty).
using ColumnVisitor = std::function<void(const OperatorColumn&)>;

/// A mass and a stiffness matrix on the same unknowns (TexelOperators::assembledFor,
/// buildMassStiffness).
struct MassStiffness {
  SparseMatrixd mass;       ///< M (|T| x |T|)
  SparseMatrixd stiffness;  ///< S (|T| x |T|)
};

/// What the assembly saw.
struct OperatorReport {
  int plainFullPieces = 0;     ///< pieces that are whole cells with exactly bilinear basis
  int plainPartialPieces = 0;  ///< other pieces with exactly bilinear basis
  int seamPieces = 0;          ///< pieces touching a seam (quadratic elements)
  int unexpectedCrossings = 0; ///< clipping inconsistencies (0 unless the input is pathological)
  fem::MetricReport metric;    ///< immersion-metric diagnostics
};

/// Stateful builder: clips and integrates the metric-independent parts once, then assembles
/// M and S for any per-face metric and S_beta = sum_c beta_c S_c for any per-cell beta cheaply
/// (while it keeps the piece integrals: OperatorOptions::keepPieceIntegrals).
/// Unknowns are TexelGrid::unknownOfTexel; mesh and grid must outlive the object.
class TexelOperators {
 public:
  /// Builds the basis, the per-piece integrals, the sparsity pattern, and M, S for the immersion
  /// metric of the unit-area surface (paper Sec. 7).
  TexelOperators(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& grid,
                 const OperatorOptions& options = {}, const ProgressCallback& progress = {});
  ~TexelOperators();
  TexelOperators(const TexelOperators&) = delete;
  TexelOperators& operator=(const TexelOperators&) = delete;

  /// Replaces the per-face metric (SPD 2x2 in texel coordinates, one per face; faces with zero UV
  /// area are ignored) and re-assembles M and S (no clipping or integration is redone). Throws
  /// InvalidInputError if the operators were built with keepPieceIntegrals = false.
  void setMetric(std::vector<Eigen::Matrix2d> metric);
  /// Current per-face metric.
  const std::vector<Eigen::Matrix2d>& metric() const;
  /// Frees the per-piece integrals now (as OperatorOptions::keepPieceIntegrals = false does
  /// after the first assembly), for an owner done re-assembling; M and S stay. setMetric,
  /// assembledFor and modulatedStiffness then throw InvalidInputError.
  void releasePieceIntegrals();
  /// M and S for another per-face metric (as setMetric takes it), on the same pattern, leaving
  /// this object's metric and matrices as they are (so operators shared by several apps stay
  /// unchanged). Throws InvalidInputError as setMetric does.
  MassStiffness assembledFor(const std::vector<Eigen::Matrix2d>& metric) const;

  /// Mass matrix M = *0 (|T| x |T|, SPD): M_st = int sqrt|g| phi_s phi_t (paper Sec. 5.2);
  /// units of surface area (1^T M 1 = surface area, 1 for the immersion metric).
  const SparseMatrixd& mass() const;
  /// Stiffness matrix S (|T| x |T|, symmetric PSD): S_st = int sqrt|g| g^-1(dphi_s, dphi_t) (paper
  /// Sec. 5.3 footnote 5), S_tt = -sum_{s != t} S_st so S 1 = 0 (rounding only); the negative of a
  /// Laplacian. A view on mass()'s pattern with S's own values (one index array for both
  /// matrices); valid while this object lives, and setMetric() changes the values in place.
  SparseViewd stiffness() const;
  /// Seam-continuity matrix C (|T| x |T|, symmetric PSD): x^T C x = E_C = integral over the
  /// seams of (f_side0 - f_side1)^2 with respect to surface length under the current metric
  /// (paper Sec. 4.2). Zero for the seam-continuous basis, whose functions have no seam jumps.
  const SparseMatrixd& seamContinuity() const;
  /// System matrix of the screened problem min alpha ||f - psi||^2 + ||df - omega||^2
  /// (+ alpha lambda E_C for the bilinear baseline): alpha M + S + alpha lambda C
  /// (paper Sec. 4.2 and 5.3); the right-hand side alpha mass_h(psi) + div_h(omega) is unchanged.
  SparseMatrixd screenedSystem(double alpha) const;
  /// screenedSystem(alpha) formed in M's own storage, consuming the operators: a one-shot caller
  /// that has no further use for M and S never holds a second copy of their pattern (117 bytes
  /// per active texel at spot 2048², docs/memory.md).
  static SparseMatrixd screenedSystem(std::unique_ptr<TexelOperators> operators, double alpha);
  /// screenedSystem(operators, alpha) that first shows `visit` each column of M and S: what a
  /// one-shot caller computes from them (a right-hand side) needs neither kept. Operators built
  /// with OperatorOptions::deferAssembly are assembled here (progress stage "assemble"), a
  /// window of cell rows at a time, each column of S held only until it is complete (S's 74
  /// bytes per active texel are never held whole); the same values, bit for bit, as assembling
  /// them first. Throws InvalidInputError if the grid's per-texel maps, which a deferred
  /// assembly reads, were freed.
  static SparseMatrixd screenedSystem(std::unique_ptr<TexelOperators> operators, double alpha,
                                      const ColumnVisitor& visit,
                                      const ProgressCallback& progress = {});
  /// screenedSystem(operators, alpha, visit, progress) as a FloatSystem: each entry of
  /// alpha M + S rounded to float (and kept exact too in the rows and columns of
  /// exactUnknowns()), each row's sum formed from the unrounded entries. A deferred
  /// assembly then holds M's values, too, only until their column is complete, and neither M
  /// nor A ever exists in double: about 8 bytes per entry instead of 12 (docs/memory.md). For float
  /// multigrid cycles (SystemSolver::takesFloatSystem). Throws InvalidInputError as that
  /// overload does, or if the operators have a seam-continuity weight (whose C may add entries).
  static FloatSystem screenedSystemInFloat(std::unique_ptr<TexelOperators> operators,
                                           double alpha, const ColumnVisitor& visit,
                                           const ProgressCallback& progress = {});
  /// Per unknown: 1 for those whose entries screenedSystemInFloat keeps exact (in double as
  /// well as float), the texels that have no regular interior stencil: those whose footprint is
  /// not inside one chart (TexelClass::Boundary) and those whose column reaches beyond their
  /// 3 x 3 lattice neighbours (seam entries). Reads the grid's texel classes.
  std::vector<uint8_t> exactUnknowns() const;
  /// True while the assembly of operators built with OperatorOptions::deferAssembly has not
  /// run: mass(), stiffness(), seamContinuity() and the products formed from them throw
  /// InvalidInputError until then (the pattern, texelPairs() and differential() are there).
  bool assemblyDeferred() const;
  /// One matrix on M's pattern with entry (r, c) = combine(r, c, M_rc, S_rc): the system matrix
  /// of an app that weighs M and S entry by entry (stitching's alpha W M W + S).
  SparseMatrixd combined(const EntryCombination& combine) const;
  /// combined(combine) formed in M's own storage, consuming the operators (as screenedSystem).
  static SparseMatrixd combined(std::unique_ptr<TexelOperators> operators,
                                const EntryCombination& combine);
  /// sum_c beta_c S_c with S_c the stiffness integrated over cell c only (paper Sec. 7.1);
  /// beta is indexed by TexelGrid::cellIndex. Same pattern as stiffness(). Needs the piece
  /// integrals (OperatorOptions::keepPieceIntegrals).
  SparseMatrixd modulatedStiffness(std::span<const double> betaPerCell) const;

  /// Texel pairs A: (s, t), s < t, whose supports overlap (structural off-diagonals of S),
  /// ordered by s then t.
  std::vector<std::pair<int32_t, int32_t>> texelPairs() const;
  /// Difference operator d (|A| x |T|): row a = (s, t) has -1 at s and +1 at t (paper Sec. 5.1).
  SparseMatrixd differential() const;
  /// Whitney Hodge star *1 (|A| x |A|, SPD): int sqrt|g| g^-1(omega_a, omega_b) with
  /// omega_(s,t) = phi_s dphi_t - phi_t dphi_s (paper Sec. 5.2); d^T *1 d = S. Memory ~ 11 |A|.
  SparseMatrixd hodgeStar1() const;
  /// mass_h(psi) (|T|): int sqrt|g| phi_t psi (paper Sec. 5.3), quadrature of `degree` per element.
  Eigen::VectorXd massOf(const SurfaceScalar& psi, int degree = 4) const;
  /// div_h(omega) (|T|): int sqrt|g| g^-1(dphi_t, omega) (paper Sec. 5.3; no minus sign).
  Eigen::VectorXd divergenceOf(const SurfaceOneForm& omega, int degree = 4) const;

  /// The options these operators were built with.
  const OperatorOptions& options() const;
  /// The function space.
  const fem::TexelBasis& basis() const;
  /// Assembly diagnostics.
  const OperatorReport& report() const;
  /// Bytes held in the operators' containers: M, S's values, C, the piece integrals while kept,
  /// a deferred assembly's plan, per-face metric data (docs/memory.md). The basis, which scales
  /// with the mesh, is left out.
  int64_t storageBytes() const;

 private:
  /// system += alpha lambda C when the bilinear basis has a seam weight (paper Sec. 4.2).
  void addSeamScreening(double alpha, SparseMatrixd& system) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// alpha M + S formed in `matrices.mass`'s own storage, consuming both (left empty): a caller
/// done with M and S never holds a second copy of their pattern. M and S must share one pattern,
/// as TexelOperators::assembledFor returns them (throws InvalidInputError otherwise). Entry for
/// entry the same values as the expression alpha * M + S.
SparseMatrixd screenedSystem(MassStiffness&& matrices, double alpha);
/// `a` (symmetric, compressed) as a FloatSystem on a's own pattern arrays: each entry rounded to
/// float, those in the rows and columns of exactUnknown (one flag per unknown:
/// TexelOperators::exactUnknowns) kept exact too, each row's sum of a's entries in column order
/// rounded; a's double values are dropped. For a = screenedSystem(alpha), the same system as
/// screenedSystemInFloat gives.
FloatSystem roundedSystem(SparseMatrixd&& a, std::span<const uint8_t> exactUnknown);

/// Builds M and S of a mesh/atlas/grid for the immersion metric of the unit-area surface.
MassStiffness buildMassStiffness(const TexturedMesh& mesh, const Atlas& atlas,
                                 const TexelGrid& grid, const OperatorOptions& options = {});

}  // namespace texgrad
