// The bound on barely covered texels: a texel whose footprint a chart only grazes has almost no
// mass, so the surface signal hardly determines its solved value, which can then lie far outside
// the input's range (spot's texture in [0, 1] smoothed: -9.66). After the solve such values are
// clamped into the range the surface shows around them.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "texgrad/apps/texel_domain.h"

namespace texgrad {

/// Kernel coverage (barelyCoveredTexels: the part of a texel's bilinear kernel that the charts
/// cover, 1 for a texel inside a chart) below which a solved value is bounded. Filtering the ten
/// shared meshes' textures at 512² (direct solver, beta 0), the texels below 1e-3 held every
/// value more than 0.074 ranges outside the input's (up to 1.6 ranges on spot, 7.2 on
/// ycb_scissors, 10 on Lantern). Bounding moves the RMS seam jump of bilinear lookups by at most
/// 0.002 8-bit steps at 1024²; replacing the texels below 1e-2 or 0.1 by their neighbours'
/// average moved it by up to 0.21 and 1.3 (docs/architecture.md, Bounded results).
inline constexpr double kBarelyCoveredKernel = 1e-3;

/// Unknowns of `domain` (ascending) whose kernel coverage is below kBarelyCoveredKernel.
std::vector<int32_t> barelyCoveredUnknowns(const TexelDomain& domain);

/// What bounding the barely covered unknowns needs from the mass matrix, kept so that the bound
/// can be applied after the operators are freed (a one-shot filter).
struct BarelyCoveredNeighbours {
  std::vector<int32_t> unknowns;  ///< the unknowns to bound
  /// Neighbours of unknowns[i] (off-diagonal positive entries of M in its column) are
  /// neighbours[start[i] .. start[i + 1]); start has unknowns.size() + 1 entries.
  std::vector<int64_t> start;
  std::vector<int32_t> neighbours;  ///< see start
};

/// The neighbours of `barely` under `mass` (the domain's mass matrix M, |T| x |T|).
BarelyCoveredNeighbours barelyCoveredNeighbours(const SparseMatrixd& mass,
                                                std::vector<int32_t> barely);

/// Clamps each row `barely` of `x` (unknowns x channels), per channel, into the range of its
/// own row of `input` and of its neighbours under the mass matrix (positive entries) that are
/// not in `barely`: the values the surface shows around the texel, which the texel itself barely
/// changes. A value already within that range is kept, so an exact solution that reproduces
/// the input stays as it is. Rows next to no such neighbour are bounded in later passes by the
/// rows bounded before; rows that no pass reaches take `input`'s row.
void boundBarelyCovered(const TexelDomain& domain, std::span<const int32_t> barely,
                        const Eigen::MatrixXd& input, Eigen::MatrixXd& x);

/// boundBarelyCovered with the neighbours gathered beforehand; `input` holds only the rows of
/// the bounded unknowns (row i for bound.unknowns[i]), so the whole input need not be kept.
void boundBarelyCovered(const BarelyCoveredNeighbours& bound, const Eigen::MatrixXd& input,
                        Eigen::MatrixXd& x);

}  // namespace texgrad
