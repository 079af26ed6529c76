// Operator properties (paper Sec. 5): S 1 = 0, unit area, SPD/PSD, flat stencils, conformal
// invariance, d^T *1 d = S, convergence, per-cell modulation and thread-count determinism.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <cstdio>

#include "../fem/fem_fixtures.h"
#include "texgrad/core/error.h"
#include "texgrad/operators/texel_operators.h"

namespace texgrad {
namespace {

struct Case {
  const char* name;
  TexturedMesh mesh;
  int resolution;
  int components;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  out.push_back({"square", test::gridSquare(3, 0.9, 0.8, 0.031, 0.077), 32, 1});
  out.push_back({"aligned", test::gridSquare(4), 32, 1});
  out.push_back({"twoChart", test::twoChartSquare(5), 64, 1});
  out.push_back({"twoChartDense", test::twoChartSquare(3, 0.05), 256, 1});
  out.push_back({"sphere", test::cubeSphere(4), 48, 1});
  return out;
}

struct Built {
  Atlas atlas;
  TexelGrid grid;
  std::unique_ptr<TexelOperators> ops;
};

Built build(const TexturedMesh& mesh, int resolution, const OperatorOptions& options = {}) {
  Built b;
  b.atlas = buildAtlas(mesh);
  b.grid = buildTexelGrid(mesh, b.atlas, resolution, resolution);
  b.ops = std::make_unique<TexelOperators>(mesh, b.atlas, b.grid, options);
  return b;
}

double relativeAsymmetry(const SparseMatrixd& m) {
  return (m - SparseMatrixd(m.transpose())).norm() / m.norm();
}

TEST(TexelOperators, BasicInvariants) {
  for (const auto& c : cases()) {
    const Built b = build(c.mesh, c.resolution);
    const SparseMatrixd& m = b.ops->mass();
    const SparseMatrixd s(b.ops->stiffness());  // a copy: the test uses its diagonal()
    const Eigen::VectorXd one = Eigen::VectorXd::Ones(m.rows());
    EXPECT_EQ(b.ops->report().unexpectedCrossings, 0) << c.name;
    EXPECT_NEAR(one.dot(m * one), 1.0, 1e-9) << c.name;
    EXPECT_LE((s * one).norm(), 1e-10 * s.diagonal().norm()) << c.name;
    EXPECT_LE(relativeAsymmetry(m), 1e-15) << c.name;
    EXPECT_LE(relativeAsymmetry(s), 1e-15) << c.name;
    EXPECT_GT(m.diagonal().minCoeff(), 0.0) << c.name << " zero mass row";
    EXPECT_GT(s.diagonal().minCoeff(), 0.0) << c.name << " zero stiffness row";
    Eigen::SimplicialLLT<SparseMatrixd> llt(m);
    EXPECT_EQ(llt.info(), Eigen::Success) << c.name << ": M not positive definite";
  }
}

TEST(TexelOperators, StiffnessKernelIsTheConstantsPerComponentSlow) {
  for (const auto& c : cases()) {
    if (c.resolution > 64) continue;
    const Built b = build(c.mesh, c.resolution);
    const Eigen::MatrixXd s = Eigen::MatrixXd(b.ops->stiffness());
    const Eigen::MatrixXd m = Eigen::MatrixXd(b.ops->mass());
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(s, m);
    const Eigen::VectorXd lambda = eig.eigenvalues();
    EXPECT_GT(lambda.minCoeff(), -1e-9 * lambda.maxCoeff()) << c.name << " S not PSD";
    int kernel = 0;
    for (double l : lambda) kernel += std::abs(l) < 1e-9 * lambda.maxCoeff();
    EXPECT_EQ(kernel, c.components) << c.name;
  }
}

TEST(TexelOperators, FlatInteriorRowsAreBilinearStencils) {
  const int r = 16;
  const TexturedMesh mesh = test::gridSquare(4);
  const Built b = build(mesh, r);
  const TexelGrid& g = b.grid;
  const double cellArea = 1.0 / (r * r);  // unit-area square, identity UV map
  int rows = 0;
  for (int u = 0; u < g.unknownCount(); ++u) {
    const int t = g.texelOfUnknown[u];
    if (g.texelClass[t] != TexelClass::Interior) continue;
    const int x = t % g.nx, y = t / g.nx;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int v = g.unknownOfTexel[g.texelIndex(x + dx, y + dy)];
        ASSERT_GE(v, 0);
        const int ring = std::abs(dx) + std::abs(dy);
        const double sExpected = ring == 0 ? 8.0 / 3.0 : -1.0 / 3.0;
        const double mExpected = (ring == 0 ? 4.0 / 9.0 : ring == 1 ? 1.0 / 9.0 : 1.0 / 36.0) * cellArea;
        EXPECT_NEAR(b.ops->stiffness().coeff(u, v), sExpected, 1e-13);
        EXPECT_NEAR(b.ops->mass().coeff(u, v), mExpected, 1e-13 * cellArea);
      }
    EXPECT_EQ(b.ops->stiffness().col(u).nonZeros(), 9);
    ++rows;
  }
  EXPECT_GT(rows, 50);
}

TEST(TexelOperators, ScaledMetricScalesMassOnly) {
  const Built b = build(test::cubeSphere(4), 48);
  const SparseMatrixd m = b.ops->mass(), s = b.ops->stiffness();
  std::vector<Eigen::Matrix2d> metric = b.ops->metric();
  for (auto& g : metric) g *= 3.5;
  b.ops->setMetric(metric);
  EXPECT_LE((b.ops->mass() - 3.5 * m).norm(), 1e-14 * m.norm() * 3.5);
  EXPECT_LE((b.ops->stiffness() - s).norm(), 1e-14 * s.norm());
}

TEST(TexelOperators, WhitneyFactorisationOfStiffness) {
  for (const auto& c : cases()) {
    if (c.resolution > 64) continue;
    const Built b = build(c.mesh, c.resolution);
    const SparseMatrixd d = b.ops->differential();
    EXPECT_EQ(d.rows(), static_cast<Eigen::Index>(b.ops->texelPairs().size()));
    const SparseMatrixd star = b.ops->hodgeStar1();
    const SparseMatrixd s = SparseMatrixd(d.transpose()) * star * d;
    EXPECT_LE((s - b.ops->stiffness()).norm(), 1e-10 * b.ops->stiffness().norm()) << c.name;
    const Eigen::VectorXd div =
        b.ops->divergenceOf([](const fem::SurfacePoint&) { return Eigen::Vector2d(0.3, -0.7); });
    EXPECT_NEAR(div.sum(), 0.0, 1e-12) << c.name << ": div_h of a 1-form sums to 0 (PoU)";
  }
}

TEST(TexelOperators, ModulatedStiffnessAndDeterminism) {
  const TexturedMesh mesh = test::twoChartSquare(5);
  OperatorOptions options;
  options.facesPerTask = 3;
  Built two = build(mesh, 128, options);
  Built one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = build(mesh, 128, options);
  }
  const auto& a = one.ops->stiffness();
  const auto& c = two.ops->stiffness();
  ASSERT_EQ(a.nonZeros(), c.nonZeros());
  EXPECT_TRUE(std::equal(a.valuePtr(), a.valuePtr() + a.nonZeros(), c.valuePtr()));
  EXPECT_TRUE(std::equal(one.ops->mass().valuePtr(), one.ops->mass().valuePtr() + a.nonZeros(),
                         two.ops->mass().valuePtr()));
  const size_t cells = size_t(two.grid.nx + 1) * (two.grid.ny + 1);
  std::vector<double> beta(cells, 1.0);
  const SparseMatrixd same = two.ops->modulatedStiffness(beta);
  EXPECT_TRUE(std::equal(same.valuePtr(), same.valuePtr() + same.nonZeros(), c.valuePtr()));
  std::vector<double> zero(cells, 0.0), split(cells, 0.0);
  for (int b = -1; b < two.grid.ny; ++b)
    for (int x = -1; x < two.grid.nx / 2; ++x) split[two.grid.cellIndex(x, b)] = 1.0;
  std::vector<double> rest(cells);
  for (size_t k = 0; k < cells; ++k) rest[k] = 1.0 - split[k];
  EXPECT_EQ(two.ops->modulatedStiffness(zero).norm(), 0.0);
  const SparseMatrixd sum = two.ops->modulatedStiffness(split) + two.ops->modulatedStiffness(rest);
  EXPECT_LE((sum - c).norm(), 1e-14 * c.norm());
}

TEST(TexelOperators, AssembledForAnotherMetricMatchesSetMetricAndChangesNothing) {
  const Built b = build(test::twoChartSquare(3, 0.05), 64);
  const SparseMatrixd m = b.ops->mass(), s = b.ops->stiffness();
  // An anisotropic metric, different on every face.
  std::vector<Eigen::Matrix2d> metric = b.ops->metric();
  for (size_t f = 0; f < metric.size(); ++f) {
    const double shear = 0.1 * std::sin(static_cast<double>(f));
    metric[f] = (Eigen::Matrix2d() << 2.0 + shear, shear, shear, 0.5).finished() *
                (1.0 + 0.01 * static_cast<double>(f % 7));
  }
  const MassStiffness other = b.ops->assembledFor(metric);
  auto identical = [](const SparseRefd& x, const SparseRefd& y) {
    return x.nonZeros() == y.nonZeros() &&
           std::equal(x.valuePtr(), x.valuePtr() + x.nonZeros(), y.valuePtr()) &&
           std::equal(x.innerIndexPtr(), x.innerIndexPtr() + x.nonZeros(), y.innerIndexPtr());
  };
  // This object keeps its metric and matrices.
  EXPECT_TRUE(identical(b.ops->mass(), m));
  EXPECT_TRUE(identical(b.ops->stiffness(), s));
  EXPECT_FALSE(identical(other.mass, m));
  // Bit for bit what setMetric assembles for the same metric.
  b.ops->setMetric(metric);
  EXPECT_TRUE(identical(other.mass, b.ops->mass()));
  EXPECT_TRUE(identical(other.stiffness, b.ops->stiffness()));
  metric.pop_back();
  EXPECT_THROW(b.ops->assembledFor(metric), InvalidInputError);
}

TEST(TexelOperators, AssembledOnceKeepsMAndSButRefusesToReassemble) {
  const TexturedMesh mesh = test::twoChartSquare(5);
  const Built kept = build(mesh, 64);
  const Built once = build(mesh, 64, OperatorOptions::assembledOnce());
  // Freeing the piece integrals after the assembly leaves M and S bit for bit as they were.
  auto expectIdentical = [](const SparseRefd& a, const SparseRefd& b) {
    ASSERT_EQ(a.nonZeros(), b.nonZeros());
    EXPECT_TRUE(std::equal(a.valuePtr(), a.valuePtr() + a.nonZeros(), b.valuePtr()));
    EXPECT_TRUE(std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr()));
  };
  expectIdentical(kept.ops->mass(), once.ops->mass());
  expectIdentical(kept.ops->stiffness(), once.ops->stiffness());
  // Re-assembly would need them: a clear error instead of operators summed over nothing.
  const std::vector<double> beta(size_t(once.grid.nx + 1) * (once.grid.ny + 1), 1.0);
  EXPECT_THROW(once.ops->modulatedStiffness(beta), InvalidInputError);
  EXPECT_THROW(once.ops->setMetric(once.ops->metric()), InvalidInputError);
  EXPECT_EQ(once.ops->mass().nonZeros(), kept.ops->mass().nonZeros());  // left as they were
  EXPECT_NO_THROW(kept.ops->modulatedStiffness(beta));
}

TEST(TexelOperators, PieceIntegralsReleasedLaterKeepMAndSButRefuseToReassemble) {
  const TexturedMesh mesh = test::twoChartSquare(5);
  const Built b = build(mesh, 64);
  const SparseMatrixd m = b.ops->mass(), s = b.ops->stiffness();
  const int64_t before = b.ops->storageBytes();
  b.ops->releasePieceIntegrals();
  EXPECT_LT(b.ops->storageBytes(), before);
  EXPECT_EQ((b.ops->mass() - m).norm(), 0.0);
  EXPECT_EQ((SparseMatrixd(b.ops->stiffness()) - s).norm(), 0.0);
  EXPECT_THROW(b.ops->assembledFor(b.ops->metric()), InvalidInputError);
  EXPECT_THROW(b.ops->setMetric(b.ops->metric()), InvalidInputError);
}

TEST(TexelOperators, ScreenedSystemOfMassAndStiffnessIsFormedInTheMassStorage) {
  const TexturedMesh mesh = test::twoChartSquare(3, 0.05);
  const Built b = build(mesh, 64);
  std::vector<Eigen::Matrix2d> metric = b.ops->metric();
  for (size_t f = 0; f < metric.size(); ++f) metric[f](0, 0) *= 3.0;
  const double alpha = 37.5;
  MassStiffness h = b.ops->assembledFor(metric);
  const SparseMatrixd expected = alpha * h.mass + h.stiffness;
  const double* massValues = h.mass.valuePtr();
  const SparseMatrixd system = screenedSystem(std::move(h), alpha);
  // Entry for entry the expression's values, in M's own array; M and S are left empty.
  ASSERT_EQ(system.nonZeros(), expected.nonZeros());
  EXPECT_TRUE(
      std::equal(system.valuePtr(), system.valuePtr() + system.nonZeros(), expected.valuePtr()));
  EXPECT_TRUE(std::equal(system.innerIndexPtr(), system.innerIndexPtr() + system.nonZeros(),
                         expected.innerIndexPtr()));
  EXPECT_EQ(system.valuePtr(), massValues);
  EXPECT_EQ(h.mass.nonZeros(), 0);
  EXPECT_EQ(h.stiffness.nonZeros(), 0);
  // Matrices on different patterns are refused.
  MassStiffness mismatched = b.ops->assembledFor(metric);
  mismatched.stiffness.prune([](Eigen::Index r, Eigen::Index c, double) { return r == c; });
  EXPECT_THROW(static_cast<void>(screenedSystem(std::move(mismatched), alpha)), InvalidInputError);
}

TEST(TexelOperators, StiffnessSharesTheMassPatternAndMatchesItsOwnAssembly) {
  const Built b = build(test::cubeSphere(4), 48);
  const SparseMatrixd& m = b.ops->mass();
  const SparseViewd s = b.ops->stiffness();
  // One index array for both matrices (the memory this layout exists for).
  EXPECT_EQ(s.innerIndexPtr(), m.innerIndexPtr());
  EXPECT_EQ(s.outerIndexPtr(), m.outerIndexPtr());
  EXPECT_NE(s.valuePtr(), m.valuePtr());
  // The view reads the same matrix as S assembled on its own (beta = 1 everywhere), and
  // screenedSystem is alpha M + S entry by entry.
  const std::vector<double> ones(size_t(b.grid.nx + 1) * (b.grid.ny + 1), 1.0);
  const SparseMatrixd own = b.ops->modulatedStiffness(ones);
  EXPECT_EQ((own - SparseMatrixd(s)).norm(), 0.0);
  const SparseMatrixd a = b.ops->screenedSystem(7.0);
  EXPECT_LE((a - (7.0 * m + own)).norm(), 1e-15 * a.norm());
}

TEST(TexelOperators, ProjectionConverges) {
  // f = sin(3x) cos(2y) on the flat two-chart square (unit area, smooth across the seam).
  auto f = [](const Eigen::Vector3d& p) { return std::sin(3 * p.x()) * std::cos(2 * p.y()); };
  const double s6 = std::sin(6.0), s4 = std::sin(4.0);
  const double l2 = (0.5 - s6 / 12) * (0.5 + s4 / 8);
  const double h1 = 9 * (0.5 + s6 / 12) * (0.5 + s4 / 8) + 4 * (0.5 - s6 / 12) * (0.5 - s4 / 8);
  const TexturedMesh mesh = test::twoChartSquare(3);
  std::vector<double> errMass, errStiff;
  for (int r : {32, 64, 128, 256}) {
    const Built b = build(mesh, r);
    const auto& basis = b.ops->basis();
    const Eigen::VectorXd rhs =
        b.ops->massOf([&](const fem::SurfacePoint& p) { return f(basis.position(p)); }, 6);
    Eigen::SimplicialLDLT<SparseMatrixd> solver(b.ops->mass());
    const Eigen::VectorXd x = solver.solve(rhs);
    errMass.push_back(std::abs(x.dot(b.ops->mass() * x) - l2));
    errStiff.push_back(std::abs(x.dot(b.ops->stiffness() * x) - h1));
  }
  for (size_t k = 1; k < errMass.size(); ++k) {
    const double om = std::log2(errMass[k - 1] / errMass[k]);
    const double os = std::log2(errStiff[k - 1] / errStiff[k]);
    std::printf("resolution x%d: |x'Mx - int f^2| = %.3e (order %.2f), |x'Sx - int |df|^2| = %.3e "
                "(order %.2f)\n", 1 << k, errMass[k], om, errStiff[k], os);
    EXPECT_GE(om, 1.0);
    EXPECT_GE(os, 1.0);
  }
}

}  // namespace
}  // namespace texgrad
