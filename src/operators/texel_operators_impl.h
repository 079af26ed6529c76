// State of TexelOperators (private to operators/): per-piece metric-independent integrals grouped
// by cell-row band and the assembled matrices (which all share mass's sparsity pattern). Built
// either with all pieces kept (re-assembly) or streamed band by band (band_streaming.cpp).
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "piece_integrals.h"
#include "texgrad/operators/texel_operators.h"

namespace texgrad {
namespace detail {

/// Sets a symmetric matrix's diagonal entry in column `column` (rows `rows`, ascending, values
/// `values`) to minus the sum of the column's other entries, so the matrix maps constants to
/// zero by construction (S 1 = 0; texel_operators.cpp says why). No diagonal entry: no change.
void zeroColumnSum(std::span<const int> rows, int column, std::span<double> values);

}  // namespace detail

struct TexelOperators::Impl {
  /// Piece that is a whole cell with bilinear basis.
  struct FullPiece {
    int32_t face, cellX, cellY;
  };
  /// Bilinear piece that is part of a cell.
  struct PartialPiece {
    int32_t face, cellX, cellY;
    detail::Moments moments;
  };
  /// Piece touching a seam: local texels and its four symmetric k x k integrals (mass, kxx, kxy,
  /// kyy), each stored as its upper triangle (k (k + 1) / 2 values).
  struct SeamPiece {
    int32_t face, cellX, cellY;
    int32_t texelBegin, texelEnd;
    int64_t valueBegin;
  };
  /// Metric factors of a face: sqrt|g| and sqrt|g| g^-1 (xx, xy, yy).
  struct FaceFactors {
    double mass = 0.0, xx = 0.0, xy = 0.0, yy = 0.0;
  };
  /// Plain pieces of the bands [firstBand, firstBand + bands), sorted by band; within a band in
  /// face order (and a face's clip order), which fixes the order of the sums into each entry.
  struct PlainPieces {
    int firstBand = 0;
    std::vector<FullPiece> full;
    std::vector<PartialPiece> partial;
    std::vector<int64_t> fullBandBegin, partialBandBegin;  ///< bands + 1 starts per list
  };
  /// Pieces of a run of faces as one task clips them, in face order; texelBegin and valueBegin
  /// of its seam pieces index its own texels and values.
  struct Chunk {
    std::vector<FullPiece> full;
    std::vector<PartialPiece> partial;
    std::vector<SeamPiece> seam;
    std::vector<int32_t> texels;
    std::vector<double> values;
    int unexpected = 0;
  };

  Impl(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& grid,
       const OperatorOptions& opts)
      : options(opts), basis(mesh, atlas, grid, {opts.basis}) {}

  /// Clips each face faceAt(i), i in [first, last), in turn and calls visit(face, piece,
  /// polygon) for each of its pieces; returns the clipping's unexpected crossings.
  template <typename FaceAt, typename Visit>
  int forEachPiece(int first, int last, FaceAt faceAt, Visit&& visit) const {
    FaceClip clip;
    int unexpected = 0;
    for (int i = first; i < last; ++i) {
      const int f = faceAt(i);
      basis.clipFace(f, clip);
      unexpected += clip.unexpectedCrossings;
      for (const FacePiece& piece : clip.pieces) visit(f, piece, clip.polygon(piece));
    }
    return unexpected;
  }
  /// Clips and integrates every piece, kept in `plain` (all bands) and `seam`.
  void integratePieces(const ProgressCallback& progress);
  /// Buffers of a seam piece's integration, reused from piece to piece by one task.
  struct SeamScratch {
    fem::PieceBasis basis;
    detail::LocalIntegrals integrals;
  };
  /// Appends a plain piece (polygon `poly` of face f) to the chunk: a full one, or a partial
  /// one with its moments.
  static void addPlainPiece(int face, const FacePiece& piece, std::span<const PieceVertex> poly,
                            Chunk& chunk);
  /// Integrates a piece that is not plain and appends it to the chunk's seam pieces; with
  /// `integrate` false only its texels (valueBegin 0, no values).
  void addSeamPiece(int face, const FacePiece& piece, std::span<const PieceVertex> poly,
                    Chunk& chunk, SeamScratch& scratch, bool integrate = true) const;
  /// Moves the chunks' seam pieces into `seam`, `seamTexels`, `seamValues` in chunk order.
  void gatherSeamPieces(std::vector<Chunk>& chunks);
  /// The chunks' plain pieces of the bands [firstBand, endBand) sorted by band (stable), each
  /// chunk's lists freed once copied.
  PlainPieces bucketByBand(std::vector<Chunk>& chunks, int firstBand, int endBand) const;
  /// Per cell (TexelGrid::cellIndex): 1 if a kept piece lies in it.
  std::vector<uint8_t> coveredCells() const;
  /// M's pattern: column u holds the texels of the covered cells around texel u and u's seam
  /// pairs (from `seam`).
  void buildPattern(const std::vector<uint8_t>& cellCovered);
  /// Builds the pattern and assembles M and S for `metric` band by band without keeping the
  /// plain pieces (prepareStreamed, then every window and the seam faces into M and S whole;
  /// band_streaming.cpp). The same sums in the same order as assemble(): bit-identical.
  void assembleStreamed(std::vector<Eigen::Matrix2d> metric, const ProgressCallback& progress);
  /// assembleStreamed's first part, all a deferred assembly does in the constructor: a first
  /// pass over the faces finds the covered cells, the seam pieces and each face's bands; then
  /// the pattern, the faces of every window of bands (`stream`) and the metric factors.
  void prepareStreamed(std::vector<Eigen::Matrix2d> metric, const ProgressCallback& progress);
  /// The deferred assembly (OperatorOptions::deferAssembly): windows in turn, each column of S
  /// held only until complete; `visit` sees every column of M and S, which then becomes
  /// alpha M + S in M's values, or with `out` (on M's pattern) in `out`, with its row sums:
  /// then M's values too are held only until their column is complete, and M's value array is
  /// never touched (band_streaming.cpp).
  void assembleScreened(double alpha, const ColumnVisitor& visit, const ProgressCallback& progress,
                        FloatSystem* out = nullptr);
  /// Per unknown: 1 for those whose entries a FloatSystem keeps exact, the texels whose footprint
  /// is not inside one chart (TexelClass::Boundary) and those whose column reaches beyond their
  /// 3 x 3 lattice neighbours (seam entries); the multigrid solves their rows directly.
  std::vector<uint8_t> exactUnknowns() const;
  /// Bands each face's plain pieces meet, first[f] to last[f] (none if last[f] < 0).
  struct FaceBands {
    std::vector<int32_t> first, last;
  };
  /// assembleStreamed's first pass: clips every face, marks the covered cells in `covered`,
  /// gathers the seam pieces (with their texels, not their integrals) and returns the bands.
  FaceBands scanFaces(std::vector<uint8_t>& covered);
  /// What prepareStreamed leaves for the windows: window k holds bands [windowBand[k],
  /// windowBand[k + 1]) and faces[faceBegin[k]] to faces[faceBegin[k + 1] - 1]; the faces with
  /// seam pieces (ascending), clipped again after the windows; and, for a deferred assembly, the
  /// columns those seam pieces add to (ascending).
  struct StreamPlan {
    std::vector<int32_t> windowBand;
    std::vector<int64_t> faceBegin;
    std::vector<int32_t> faces;
    std::vector<int32_t> seamFaces;
    std::vector<int32_t> seamColumns;
    int windows() const { return static_cast<int>(faceBegin.size()) - 1; }
  };
  /// S's values of some columns of the pattern (those of StreamPlan::seamColumns), in column
  /// order, while a deferred assembly completes them.
  struct ColumnValues {
    std::vector<int32_t> columns;  ///< ascending
    std::vector<int64_t> start;    ///< offset of each column's values, and the total
    std::vector<double> values;
    /// The values of `column` (one of `columns`), in the order of M's pattern.
    double* of(int column);
  };
  /// Fills the plan's windows of bands for the bands first[f] to last[f] of each face f (none
  /// if last[f] < 0): their bands, and their faces, ascending (a face is in every window its
  /// plain pieces meet).
  static void planWindows(std::span<const int32_t> first, std::span<const int32_t> last,
                          int bandCount, StreamPlan& plan);
  /// Room for S's values of `columns` (ascending) on `pattern`, all zero.
  static ColumnValues columnValuesOf(const SparseMatrixd& pattern, std::vector<int32_t> columns);
  /// Clips window k's faces again and adds their plain pieces into M's values (`massOut`,
  /// positions from `massFirst` on) and S's (`stiffnessOut`, positions from `stiffnessFirst` on).
  void assembleWindow(int k, double* massOut, int64_t massFirst, double* stiffnessOut,
                      int64_t stiffnessFirst);
  /// Clips the plan's seam faces again, integrates their seam pieces and adds them into M and S
  /// (M into `massColumns`, S into `stiffnessColumns` instead, where given) in face order, a few
  /// chunks of faces in flight (band_streaming.cpp).
  void assembleSeamFaces(double* massOut, double* stiffnessOut, ColumnValues* stiffnessColumns,
                         ColumnValues* massColumns = nullptr);
  /// C of the soft seam-continuity energy for the bilinear basis (none for the seam-continuous
  /// basis).
  void buildSeamContinuity();
  /// C: seamContinuity for the bilinear basis; for the seam-continuous basis an all-zero matrix,
  /// formed on the first call.
  const SparseMatrixd& continuityMatrix() const;
  /// Metric factors of every face for a per-face metric; throws InvalidInputError, naming
  /// `caller`, unless there is one SPD matrix per face.
  std::vector<FaceFactors> factorsOf(const std::vector<Eigen::Matrix2d>& faceMetric,
                                     const char* caller) const;
  /// Sums the pieces into the values of M and S_beta (beta per cell, or 1 where null) for the
  /// per-face `faceFactors` on the shared pattern (`mass`'s index arrays); either output may be
  /// null. Changes no member, so the matrices of another metric can be assembled alongside.
  void assemble(const std::vector<FaceFactors>& faceFactors, const double* beta, double* massValues,
                double* stiffnessValues) const;
  /// Adds the plain pieces into M's and S_beta's values: bands of one colour (parity) at a time,
  /// even first, in parallel (two bands of a colour share no column).
  /// M's and S's values start at positions `massFirst` and `stiffnessFirst` of the pattern (0:
  /// all of them).
  void assembleBands(const PlainPieces& pieces, const std::vector<FaceFactors>& faceFactors,
                     const double* beta, double* massValues, double* stiffnessValues,
                     int64_t stiffnessFirst = 0, int64_t massFirst = 0) const;
  /// Adds seam pieces (in order; their texels and integrals at texelBegin and valueBegin of
  /// `texels` and `values`) into M's and S_beta's values (M's into `massColumns`, S's into
  /// `stiffnessColumns` instead, where given).
  void assembleSeams(std::span<const SeamPiece> pieces, const int32_t* texels, const double* values,
                     const std::vector<FaceFactors>& faceFactors, const double* beta,
                     double* massValues, double* stiffnessValues,
                     ColumnValues* stiffnessColumns = nullptr,
                     ColumnValues* massColumns = nullptr) const;
  /// Sets S's diagonal to minus the sum of the rest of its column (S 1 = 0; zeroColumnSums).
  void finishStiffness(double* stiffnessValues) const;
  /// Frees the piece integrals (OperatorOptions::keepPieceIntegrals = false).
  void releasePieces();
  /// Throws InvalidInputError naming `caller` if the piece integrals were freed.
  void requirePieces(const char* caller) const;
  int band(int cellY) const;
  /// First cell row of band b (cell rows start at -1).
  static int firstCellRow(int b);
  /// Throws InvalidInputError naming `caller` while a deferred assembly has not run.
  void requireAssembled(const char* caller) const;

  OperatorOptions options;
  fem::TexelBasis basis;
  OperatorReport report;
  std::vector<Eigen::Matrix2d> metric;
  std::vector<FaceFactors> factors;
  PlainPieces plain;  ///< all bands' plain pieces while kept (keepPieceIntegrals)
  std::vector<SeamPiece> seam;
  std::vector<int32_t> seamTexels;
  std::vector<double> seamValues;
  int bandCount = 0;
  bool piecesReleased = false;       ///< releasePieces() ran: no re-assembly possible
  bool deferred = false;             ///< a deferred assembly has not run yet
  StreamPlan stream;                 ///< kept from prepareStreamed to the windows' assembly
  SparseMatrixd mass;  ///< M; its index arrays are the pattern of every assembled matrix
  std::vector<double> stiffnessValues;  ///< S on mass's pattern (TexelOperators::stiffness())
  SparseMatrixd seamContinuity;         ///< E_C(x) = x^T C x (paper Sec. 4.2); bilinear basis only
  mutable std::once_flag zeroContinuityFormed;
  mutable SparseMatrixd zeroContinuity;  ///< C = 0 of the seam-continuous basis, once asked for
};

}  // namespace texgrad
