// Solver module: the Galerkin coarse operator Pᵀ A P of paper §6.1 (A^{l+1} = Pᵀ A^l P).
#pragma once

#include <Eigen/SparseCore>

#include "texgrad/solver/grid_hierarchy.h"
#include "texgrad/solver/sparse_sum.h"

namespace texgrad {

/// Pᵀ A P for A (n x n; a matrix or a SparseSum) and P (n x m), column by column without forming A
/// P. The pattern is structural (no entry is dropped for being zero), so it depends only on the
/// patterns of A and P; the result does not depend on the thread count. Throws
/// InvalidInputError unless A is square with P's row count (and, as a matrix, compressed).
Eigen::SparseMatrix<double> galerkinProduct(const SparseSum& a,
                                            const Eigen::SparseMatrix<double>& p);

/// Pᵀ A P for the bilinear prolongation P from `coarse` to `fine` (consecutive levels of one
/// GridHierarchy), computed from the lattice positions without storing P; equal, bit for bit, to
/// galerkinProduct(a, GridHierarchy::prolongation(l)). Throws InvalidInputError unless A is
/// square with fine's unknown count (and, as a matrix, compressed) and both levels have their
/// unknownOfSlot (GridHierarchy::restoreUnknownOfSlot).
Eigen::SparseMatrix<double> galerkinProduct(const SparseSum& a, const GridLevel& fine,
                                            const GridLevel& coarse);

}  // namespace texgrad
