// Surface quantities sampled at texel centres: which face holds each centre, and the smooth
// surface normal there (used by stitching's illumination model).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "texgrad/apps/texel_domain.h"

namespace texgrad {

/// Per unknown: the face whose UV triangle holds the texel centre (first in index order where
/// UVs overlap), or -1 if the centre lies outside M.
std::vector<int32_t> texelCentreFaces(const TexelDomain& domain);

/// Per unknown (rows): the unit surface normal at the texel centre, interpolated from
/// area-weighted vertex normals of the welded mesh. Texels whose centre lies outside M take the
/// mean normal of the unknowns they are coupled to in the stiffness matrix; a texel with none
/// gets a zero row.
Eigen::MatrixX3d texelNormals(const TexelDomain& domain);

/// As above with the domain's operators given (e.g. handed over by releaseOperators).
Eigen::MatrixX3d texelNormals(const TexelDomain& domain, const TexelOperators& operators);

}  // namespace texgrad
