// Solver module (private): one hierarchy level's operator split into regular interior stencils and
// an irregular boundary block (paper §6.2, Fig. 7), plus its CHOLMOD factorisation.
#pragma once

#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "texgrad/solver/cholmod_solver.h"
#include "texgrad/solver/grid_hierarchy.h"

namespace texgrad::detail {

/// A run of slots in one box row that contains every interior slot of that row.
struct SlotRow {
  int64_t begin = 0, end = 0;  ///< slot range [begin, end)
  int width = 0;               ///< width of the box (row stride in slots)
  int xParity = 0;             ///< parity of the lattice x coordinate of slot `begin`
};

/// Compressed rows with slot-indexed columns (rows of A for the boundary unknowns).
struct SlotCsr {
  std::vector<int64_t> ptr;  ///< row starts, size rows + 1
  std::vector<int64_t> col;  ///< slot index of each entry
  std::vector<double> val;   ///< entry values
};

/// Interior/boundary split and the double-precision boundary data of one level.
struct LevelSystem {
  std::vector<SlotKind> kind;              ///< per slot
  std::vector<SlotRow> rows[2];            ///< rows with interior slots, by lattice y parity
  std::vector<int64_t> boundarySlots;      ///< compact boundary index -> slot
  std::vector<int32_t> boundaryOfUnknown;  ///< per unknown: compact boundary index or -1
  std::vector<int32_t> interiorUnknowns;   ///< unknowns relaxed by Gauss–Seidel
  int64_t nonZeros = 0;                    ///< non-zeros of A^l
  int64_t boundaryNonZeros = 0;            ///< non-zeros of A_bb^l
  SlotCsr offBlock;                        ///< A_bi^l: boundary rows, non-boundary columns
  SlotCsr fullRows;                        ///< [A_bi^l A_bb^l]: complete boundary rows
  CholmodSolver boundarySolver;            ///< factorisation of A_bb^l
  int interiorCount() const { return static_cast<int>(interiorUnknowns.size()); }
  int boundaryCount() const { return static_cast<int>(boundarySlots.size()); }
};

/// Symbolic phase: a texel is interior when its footprint is interior (§6.1) and its row of
/// `pattern` only touches the 3 x 3 lattice neighbours in its own chart; A_bb^l is analysed.
void classifyLevel(const GridLevel& level, const Eigen::SparseMatrix<double>& pattern,
                   LevelSystem& system);

/// Numeric phase for the boundary: fills offBlock / fullRows and factorises A_bb^l.
void assignBoundary(const GridLevel& level, const Eigen::SparseMatrix<double>& a,
                    LevelSystem& system);

/// Numeric phase for the interior: 9 coefficients per slot, index (dy + 1) * 3 + (dx + 1), of
/// the rows of `a` at interior unknowns (other slots are left untouched).
template <typename T>
void assignStencils(const GridLevel& level, const Eigen::SparseMatrix<double>& a,
                    const LevelSystem& system, std::vector<T>& stencils);

/// Same sparsity with all values 1 (so Galerkin products of patterns cannot cancel).
Eigen::SparseMatrix<double> onesLike(const Eigen::SparseMatrix<double>& a);

}  // namespace texgrad::detail
