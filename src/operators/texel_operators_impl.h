// State of TexelOperators (private to operators/): per-piece metric-independent integrals grouped
// by cell-row band and the assembled matrices (which all share mass's sparsity pattern).
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "piece_integrals.h"
#include "texgrad/operators/texel_operators.h"

namespace texgrad {

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

  Impl(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& grid,
       const OperatorOptions& opts)
      : options(opts), basis(mesh, atlas, grid, {opts.basis}) {}

  void integratePieces(const ProgressCallback& progress);
  void buildPattern();
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
  /// Frees the piece integrals (OperatorOptions::keepPieceIntegrals = false).
  void releasePieces();
  /// Throws InvalidInputError naming `caller` if the piece integrals were freed.
  void requirePieces(const char* caller) const;
  int band(int cellY) const;

  OperatorOptions options;
  fem::TexelBasis basis;
  OperatorReport report;
  std::vector<Eigen::Matrix2d> metric;
  std::vector<FaceFactors> factors;
  // Pieces sorted by band (stable); bandBegin* index the first piece of each band.
  std::vector<FullPiece> full;
  std::vector<PartialPiece> partial;
  std::vector<SeamPiece> seam;
  std::vector<int32_t> seamTexels;
  std::vector<double> seamValues;
  std::vector<int64_t> fullBandBegin, partialBandBegin;
  int bandCount = 0;
  bool piecesReleased = false;       ///< releasePieces() ran: no re-assembly possible
  SparseMatrixd mass;  ///< M; its index arrays are the pattern of every assembled matrix
  std::vector<double> stiffnessValues;  ///< S on mass's pattern (TexelOperators::stiffness())
  SparseMatrixd seamContinuity;         ///< E_C(x) = x^T C x (paper Sec. 4.2); bilinear basis only
  mutable std::once_flag zeroContinuityFormed;
  mutable SparseMatrixd zeroContinuity;  ///< C = 0 of the seam-continuous basis, once asked for
};

}  // namespace texgrad
