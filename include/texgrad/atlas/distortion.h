// Parameterisation distortion of an atlas (paper §6.4): how far the UV map is from conformal and
// from area-preserving, the quantities that predict multigrid convergence.
#pragma once

#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// 99th percentiles (over faces, weighted by surface area) of the log-space distortion energies,
/// with surface and UV areas both normalised to 1. With sigma1 >= sigma2 the singular values of
/// the Jacobian of the 3-D position w.r.t. UV: conformal = log(sigma1 / sigma2), authalic =
/// |log(sigma1 sigma2)|. Both are 0 for an isometric (up to global scale) map.
struct Distortion {
  double conformal99 = 0.0;
  double authalic99 = 0.0;
};

/// Measures the distortion; faces degenerate in 3-D or in UV are skipped.
Distortion measureDistortion(const TexturedMesh& mesh);

}  // namespace texgrad
