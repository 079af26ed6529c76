// Operator invariants (paper Sec. 5) on every mesh of ../shared/data at 256^2 and 1024^2:
// S 1 = 0 up to the rounding of each row's own sum, 1^T M 1 = 1 (unit-area surface), positive
// diagonals, clean clipping; at 256^2 also M positive definite and S positive semi-definite with
// one null vector per connected component.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <tuple>
#include <vector>

#include "shared_meshes.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/operators/texel_operators.h"

namespace texgrad {
namespace {

using Param = std::tuple<test::SharedMesh, int>;

/// The largest |(S 1)_t| over rows t, and that row's excess over the rounding of summing it:
/// |(S 1)_t| / (n_t eps sum_s |S_st|) with n_t its non-zeros (a sum of n_t terms in floating point
/// is off from the exact one by less than (n_t - 1) eps / 2 sum_s |S_st|; one more term rounds
/// S_tt itself). S 1 = 0 holds in exact arithmetic (partition of unity), so an excess above 1
/// is rounding the assembly left in S. S is symmetric: columns are rows.
struct RowSums {
  double largest = 0.0, excess = 0.0;
  Eigen::Index row = -1;
};
RowSums constantRowSums(const SparseMatrixd& s) {
  RowSums out;
  for (Eigen::Index t = 0; t < s.outerSize(); ++t) {
    double sum = 0.0, magnitude = 0.0;
    int terms = 0;
    for (SparseMatrixd::InnerIterator it(s, t); it; ++it) {
      sum += it.value();
      magnitude += std::abs(it.value());
      terms += it.value() != 0.0;
    }
    if (sum == 0.0) continue;
    out.largest = std::max(out.largest, std::abs(sum));
    const double excess =
        std::abs(sum) / (terms * std::numeric_limits<double>::epsilon() * magnitude);
    if (excess > out.excess) {
      out.excess = excess;
      out.row = t;
    }
  }
  return out;
}

class SharedMeshOperators : public ::testing::TestWithParam<Param> {};

TEST_P(SharedMeshOperators, KernelAreaAndDiagonals) {
  const auto& [shared, resolution] = GetParam();
  const TexturedMesh mesh = readMesh(test::sharedData() / shared.obj);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, resolution, resolution);
  const TexelOperators ops(mesh, atlas, grid);
  const SparseMatrixd& m = ops.mass();
  const SparseMatrixd s(ops.stiffness());  // a copy: the test uses its diagonal()
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(m.rows());
  EXPECT_EQ(ops.report().unexpectedCrossings, 0);
  const RowSums sums = constantRowSums(s);
  EXPECT_LE(sums.excess, 1.0) << "S 1 at row " << sums.row << " exceeds its rounding";
  std::printf("%s at %d: max |S 1| %.2e, max |S_st| %.3g\n", shared.name.c_str(), resolution,
              sums.largest, s.coeffs().abs().maxCoeff());
  EXPECT_NEAR(one.dot(m * one), 1.0, 1e-9);
  Eigen::Index row = 0;
  EXPECT_GT(m.diagonal().minCoeff(&row), 0.0) << "zero mass row " << row;
  EXPECT_GT(s.diagonal().minCoeff(&row), 0.0) << "zero stiffness row " << row;
}

/// Connected components of the graph of a symmetric sparse matrix (union-find over non-zeros).
int graphComponents(const SparseMatrixd& a) {
  std::vector<Eigen::Index> parent(static_cast<size_t>(a.rows()));
  std::iota(parent.begin(), parent.end(), Eigen::Index{0});
  const auto root = [&](Eigen::Index v) {
    while (parent[static_cast<size_t>(v)] != v)
      v = parent[static_cast<size_t>(v)] =
          parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
    return v;
  };
  for (Eigen::Index k = 0; k < a.outerSize(); ++k)
    for (SparseMatrixd::InnerIterator it(a, k); it; ++it)
      parent[static_cast<size_t>(root(it.row()))] = root(it.col());
  int count = 0;
  for (Eigen::Index v = 0; v < a.rows(); ++v) count += root(v) == v;
  return count;
}

/// The factorisation checks, instantiated at 256^2 only (a simplicial LDL^T at 1024^2 is slow).
class SharedMeshFactorisations : public ::testing::TestWithParam<Param> {};

TEST_P(SharedMeshFactorisations, MassDefiniteStiffnessSemiDefiniteWithConstantKernel) {
  const auto& [shared, resolution] = GetParam();
  const TexturedMesh mesh = readMesh(test::sharedData() / shared.obj);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, resolution, resolution);
  const TexelOperators ops(mesh, atlas, grid);
  const Eigen::SimplicialLLT<SparseMatrixd> mass(ops.mass());
  EXPECT_EQ(mass.info(), Eigen::Success) << "M is not positive definite";
  // LDL^T of S: one vanishing pivot per null vector, none negative (PSD). A pivot is compared
  // with its own diagonal entry: diagonals span many orders of magnitude (grazing footprints).
  const SparseMatrixd s(ops.stiffness());
  const Eigen::SimplicialLDLT<SparseMatrixd> ldlt(s);
  ASSERT_EQ(ldlt.info(), Eigen::Success);
  const Eigen::ArrayXd d = ldlt.vectorD().array();
  const Eigen::ArrayXd diagonal = (ldlt.permutationP() * s.diagonal()).array();
  const Eigen::ArrayXd relative = d / diagonal;
  EXPECT_GE(relative.minCoeff(), -1e-8) << "S has a negative pivot";
  const auto nullPivots = (relative.abs() <= 1e-8).count();
  std::printf("%s: %ld null pivot(s), smallest other relative pivot %.2e\n", shared.name.c_str(),
              static_cast<long>(nullPivots),
              (relative.abs() > 1e-8).select(relative.abs(), 1.0).minCoeff());
  EXPECT_EQ(nullPivots, graphComponents(s)) << shared.name;
}

std::string paramName(const ::testing::TestParamInfo<Param>& info) {
  return std::get<0>(info.param).name + "_" + std::to_string(std::get<1>(info.param));
}

// 1024^2 over all meshes takes tens of seconds (more under ASan): Release pass only.
INSTANTIATE_TEST_SUITE_P(AllMeshes256, SharedMeshOperators,
                         ::testing::Combine(::testing::ValuesIn(test::sharedMeshes()),
                                            ::testing::Values(256)),
                         paramName);
INSTANTIATE_TEST_SUITE_P(AllMeshes256, SharedMeshFactorisations,
                         ::testing::Combine(::testing::ValuesIn(test::sharedMeshes()),
                                            ::testing::Values(256)),
                         paramName);
INSTANTIATE_TEST_SUITE_P(AllMeshes1024Slow, SharedMeshOperators,
                         ::testing::Combine(::testing::ValuesIn(test::sharedMeshes()),
                                            ::testing::Values(1024)),
                         paramName);

}  // namespace
}  // namespace texgrad
