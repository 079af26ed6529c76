// Operator invariants (DESIGN.md Sec. 4) on every mesh of ../shared/data at 256^2 and 1024^2:
// S 1 = 0, 1^T M 1 = 1 (unit-area surface), positive diagonals, clean clipping.
#include <gtest/gtest.h>

#include <tuple>

#include "shared_meshes.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/operators/texel_operators.h"

namespace texgrad {
namespace {

using Param = std::tuple<test::SharedMesh, int>;

class SharedMeshOperators : public ::testing::TestWithParam<Param> {};

TEST_P(SharedMeshOperators, KernelAreaAndDiagonals) {
  const auto& [shared, resolution] = GetParam();
  const TexturedMesh mesh = readMesh(test::sharedData() / shared.obj);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, resolution, resolution);
  const TexelOperators ops(mesh, atlas, grid);
  const SparseMatrixd& m = ops.mass();
  const SparseMatrixd& s = ops.stiffness();
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(m.rows());
  EXPECT_EQ(ops.report().unexpectedCrossings, 0);
  EXPECT_LE((s * one).norm(), 1e-10 * s.diagonal().norm());
  EXPECT_NEAR(one.dot(m * one), 1.0, 1e-9);
  Eigen::Index row = 0;
  EXPECT_GT(m.diagonal().minCoeff(&row), 0.0) << "zero mass row " << row;
  EXPECT_GT(s.diagonal().minCoeff(&row), 0.0) << "zero stiffness row " << row;
}

std::string paramName(const ::testing::TestParamInfo<Param>& info) {
  return std::get<0>(info.param).name + "_" + std::to_string(std::get<1>(info.param));
}

// 1024^2 over all meshes takes tens of seconds (more under ASan): Release pass only.
INSTANTIATE_TEST_SUITE_P(AllMeshes256, SharedMeshOperators,
                         ::testing::Combine(::testing::ValuesIn(test::sharedMeshes()),
                                            ::testing::Values(256)),
                         paramName);
INSTANTIATE_TEST_SUITE_P(AllMeshes1024Slow, SharedMeshOperators,
                         ::testing::Combine(::testing::ValuesIn(test::sharedMeshes()),
                                            ::testing::Values(1024)),
                         paramName);

}  // namespace
}  // namespace texgrad
