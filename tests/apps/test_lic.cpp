// Line integral convolution: streaks follow the field (autocorrelation along vs across), CG with
// a multigrid preconditioner matches the direct solve, field files and curvature directions.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <type_traits>
#include <vector>

#include "test_paths.h"
#include "texgrad/apps/lic.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/apps/vector_field.h"
#include "texgrad/atlas/seam_jump.h"
#include "texgrad/core/error.h"
#include "texgrad/fem/metric.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

/// The same 3-D vector on every face.
FaceVectorField constantField(const TexturedMesh& mesh, const Eigen::Vector3d& vector) {
  FaceVectorField field;
  field.basis = FieldBasis::Extrinsic;
  field.vectors.assign(mesh.faceCount(), vector);
  return field;
}

/// Normalised autocorrelation of channel 0 at grid offset (dx, dy), over pairs of active texels.
double autocorrelation(const TexelGrid& grid, const Eigen::MatrixXd& values, int dx, int dy) {
  const double mean = values.col(0).mean();
  double cross = 0.0, varA = 0.0, varB = 0.0;
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const int t = grid.texelOfUnknown[u];
    const int x = t % grid.nx + dx, y = t / grid.nx + dy;
    if (x < 0 || y < 0 || x >= grid.nx || y >= grid.ny) continue;
    const int w = grid.unknownOfTexel[grid.texelIndex(x, y)];
    if (w < 0) continue;
    const double a = values(u, 0) - mean, b = values(w, 0) - mean;
    cross += a * b;
    varA += a * a;
    varB += b * b;
  }
  return cross / std::sqrt(varA * varB);
}

struct Correlations {
  double alongX = 0.0, alongY = 0.0;
};

Correlations licCorrelations(const Eigen::Vector3d& direction, const LicOptions& options, int lag) {
  TexelDomain domain(procedural::square(), 64, 64);
  const auto field = fieldInTexelCoordinates(domain.mesh(), domain.grid(),
                                             constantField(domain.mesh(), direction));
  const LicResult result = lineIntegralConvolution(domain, field, options);
  return {autocorrelation(domain.grid(), result.values, lag, 0),
          autocorrelation(domain.grid(), result.values, 0, lag)};
}

TEST(Lic, StreaksFollowTheFieldAndRotateWithIt) {
  // Default pipeline (diffusion + sharpening). The sharpening boosts texel-scale detail across
  // the streaks, which makes neighbours across them anti-correlated at lag 1; from lag 2 on the
  // across correlation is ~0 while the along correlation stays high.
  const LicOptions options;
  for (int lag : {1, 2, 3}) {
    const Correlations x = licCorrelations({1, 0, 0}, options, lag);
    const Correlations y = licCorrelations({0, 1, 0}, options, lag);
    std::printf("lag %d  field x: rho_x %.3f rho_y %.3f  | field y: rho_x %.3f rho_y %.3f\n", lag,
                x.alongX, x.alongY, y.alongX, y.alongY);
    EXPECT_GT(x.alongX, 0.85) << "lag " << lag;
    if (lag >= 2) {
      EXPECT_LT(std::abs(x.alongY), 0.15) << "lag " << lag;
      EXPECT_GT(x.alongX, 5.0 * std::abs(x.alongY)) << "lag " << lag;
    }
    // Rotating the field by 90 degrees swaps the two directions (the square is symmetric).
    EXPECT_NEAR(y.alongY, x.alongX, 0.1) << "lag " << lag;
    EXPECT_NEAR(y.alongX, x.alongY, 0.1) << "lag " << lag;
  }
}

TEST(Lic, DiffusionAloneIsSmoothAlongAndRoughAcross) {
  LicOptions options;
  options.sharpenBeta = 1.0;  // no sharpening: the raw anisotropic diffusion
  const Correlations x = licCorrelations({1, 0, 0}, options, 1);
  std::printf("diffusion only: rho_x %.3f rho_y %.3f ratio %.1f\n", x.alongX, x.alongY,
              x.alongX / std::abs(x.alongY));
  EXPECT_GT(x.alongX, 0.9);
  EXPECT_GT(x.alongX, 5.0 * std::abs(x.alongY));
}

/// Autocorrelation length of channel 0 along the grid step (dx, dy), in steps: the first lag at
/// which the autocorrelation falls to 1/e, interpolated linearly between lags; maxLag if it never
/// does (a lower bound).
double correlationLength(const TexelGrid& grid, const Eigen::MatrixXd& values, int dx, int dy,
                         int maxLag) {
  const double threshold = std::exp(-1.0);
  double previous = 1.0;  // rho(0)
  for (int lag = 1; lag <= maxLag; ++lag) {
    const double rho = autocorrelation(grid, values, lag * dx, lag * dy);
    if (rho <= threshold) return lag - 1 + (previous - threshold) / (previous - rho);
    previous = rho;
  }
  return maxLag;
}

/// Largest relative deviation of the per-face metrics from one common multiple of the identity:
/// 0 when texel units are surface units up to a single scale (an isometric chart).
double isometryDefect(const std::vector<Eigen::Matrix2d>& g) {
  double scale = 0.0;
  for (const Eigen::Matrix2d& m : g) scale += 0.5 * m.trace();
  scale /= static_cast<double>(g.size());
  double worst = 0.0;
  for (const Eigen::Matrix2d& m : g)
    worst = std::max(worst, (m - scale * Eigen::Matrix2d::Identity()).norm() / scale);
  return worst;
}

TEST(Lic, CylinderStreaksAlongTheAxisSameFromMultigridCgAndDirect) {
  // The cylinder's chart is isometric up to scale, so texel lags are surface lengths: the
  // output's correlation length along the axis field must be >= 5x the one around the cylinder.
  TexelDomain domain(procedural::cylinder(48, 24), 128, 128);
  const TexelGrid& grid = domain.grid();
  ASSERT_LT(isometryDefect(domain.operators().metric()), 0.01);
  const auto field =
      fieldInTexelCoordinates(domain.mesh(), grid, constantField(domain.mesh(), {0, 0, 1}));
  for (const Eigen::Vector2d& v : field) ASSERT_LT(std::abs(v.x()), 1e-9 * v.norm());
  constexpr int kMaxLag = 40;
  LicOptions direct;
  direct.solver.kind = SolverKind::Direct;
  const LicResult cg = lineIntegralConvolution(domain, field, {});
  const LicResult exact = lineIntegralConvolution(domain, field, direct);
  for (const LicResult* r : {&cg, &exact}) {
    const char* name = r == &cg ? "MG-PCG" : "direct";
    const Eigen::MatrixXd output = gatherTexels(grid, r->image);  // what the user gets
    const double along = correlationLength(grid, output, 0, 1, kMaxLag);
    const double across = correlationLength(grid, output, 1, 0, kMaxLag);
    std::printf(
        "cylinder LIC (%s): correlation length along the axis %.2f texels, around %.2f, "
        "ratio %.1f\n",
        name, along, across, along / across);
    EXPECT_GE(along, 5.0 * across) << name;
  }
  EXPECT_TRUE(cg.report.diffusion.converged);
  EXPECT_TRUE(cg.report.sharpening.converged);
  const double rms =
      std::sqrt((gatherTexels(grid, cg.image) - gatherTexels(grid, exact.image)).squaredNorm() /
                static_cast<double>(domain.unknowns()));
  std::printf(
      "cylinder LIC: MG-PCG %d + %d iterations; output RMS difference to direct %.2e "
      "(%.3f / 255)\n",
      cg.report.diffusion.iterations, cg.report.sharpening.iterations, rms, 255.0 * rms);
  EXPECT_LE(rms, 1.0 / 255.0);
}

double relativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

TEST(Lic, MultigridCgMatchesDirect) {
  struct Case {
    const char* name;
    TexturedMesh mesh;
    int width, height;
  };
  const Case cases[] = {{"square", procedural::square(), 64, 64},
                        {"cylinder", procedural::cylinder(32, 16), 96, 96}};
  for (const Case& c : cases) {
    TexelDomain domain(c.mesh, c.width, c.height);
    const auto field = fieldInTexelCoordinates(
        domain.mesh(), domain.grid(),
        c.name == std::string("square") ? constantField(domain.mesh(), {1, 1, 0})
                                        : curvatureField(domain.mesh(), CurvatureDirection::Major));
    LicOptions cg;
    LicOptions direct;
    direct.solver.kind = SolverKind::Direct;
    const LicResult a = lineIntegralConvolution(domain, field, cg);
    const LicResult b = lineIntegralConvolution(domain, field, direct);
    const double difference = relativeDifference(a.values, b.values);
    std::printf(
        "%s: %d unknowns, CG %d + %d iterations (residual %.2e), relative difference to "
        "direct %.2e\n",
        c.name, domain.unknowns(), a.report.diffusion.iterations, a.report.sharpening.iterations,
        a.report.diffusion.residuals.back(), difference);
    EXPECT_TRUE(a.report.diffusion.converged) << c.name;
    EXPECT_TRUE(a.report.sharpening.converged) << c.name;
    EXPECT_LE(difference, 1e-4) << c.name;
  }
}

TEST(Lic, LeavesTheSharedDomainUntouchedAndIsDeterministic) {
  // LIC reads a const domain, so other apps (a viewer frame, another LIC) may share it.
  EXPECT_TRUE((std::is_constructible_v<LineIntegralConvolution, const TexelDomain&,
                                       const std::vector<Eigen::Vector2d>&, const LicOptions&>));
  const TexelDomain domain(procedural::cylinder(16, 8), 48, 48);
  const TexelOperators& ops = domain.operators();
  const std::vector<Eigen::Matrix2d> metricBefore = ops.metric();
  const SparseMatrixd massBefore = ops.mass();
  const SparseMatrixd stiffnessBefore = ops.stiffness();
  // Storage a reader of the domain may hold across the LIC run: never replaced, not even by a
  // re-assembly that restores the same values.
  const Eigen::Matrix2d* metricStorage = ops.metric().data();
  const double* massStorage = ops.mass().valuePtr();
  const double* stiffnessStorage = ops.stiffness().valuePtr();
  const auto field = fieldInTexelCoordinates(
      domain.mesh(), domain.grid(), curvatureField(domain.mesh(), CurvatureDirection::Major));
  const LicResult first = lineIntegralConvolution(domain, field, {});
  const LicResult second = lineIntegralConvolution(domain, field, {});
  EXPECT_EQ(ops.metric().data(), metricStorage);
  EXPECT_EQ(ops.mass().valuePtr(), massStorage);
  EXPECT_EQ(ops.stiffness().valuePtr(), stiffnessStorage);
  ASSERT_EQ(ops.metric().size(), metricBefore.size());
  for (size_t f = 0; f < metricBefore.size(); ++f) EXPECT_EQ(ops.metric()[f], metricBefore[f]);
  // Bit for bit: the same pattern and the same values.
  EXPECT_EQ(ops.mass().nonZeros(), massBefore.nonZeros());
  EXPECT_TRUE(std::equal(massBefore.valuePtr(), massBefore.valuePtr() + massBefore.nonZeros(),
                         ops.mass().valuePtr()));
  EXPECT_TRUE(std::equal(stiffnessBefore.valuePtr(),
                         stiffnessBefore.valuePtr() + stiffnessBefore.nonZeros(),
                         ops.stiffness().valuePtr()));
  EXPECT_EQ(first.values, second.values);
  LicOptions otherSeed;
  otherSeed.seed = 2;
  EXPECT_NE(lineIntegralConvolution(domain, field, otherSeed).values, first.values);
}

TEST(Lic, OneShotRunsMatchTheStatefulConvolutionBitForBit) {
  // The one-shot paths (the domain's operators kept, or handed over and consumed) reorder the
  // work to hold one system at a time; the values must stay those of convolve, bit for bit.
  LicOptions grey, colourUnsharpened;
  colourUnsharpened.channels = 3;
  colourUnsharpened.sharpenBeta = 1.0;
  for (const LicOptions& options : {grey, colourUnsharpened}) {
    const TexelDomain domain(procedural::cylinder(16, 8), 48, 48);
    const auto field = fieldInTexelCoordinates(
        domain.mesh(), domain.grid(), curvatureField(domain.mesh(), CurvatureDirection::Major));
    LineIntegralConvolution lic(domain, field, options);
    const Eigen::MatrixXd stateful =
        lic.convolve(licNoise(domain.grid(), options.channels, options.seed));
    const LicResult kept = lineIntegralConvolution(domain, field, options);
    EXPECT_TRUE(kept.values == stateful) << options.channels << " channels";
    TexelDomain handing(procedural::cylinder(16, 8), 48, 48);
    const LicResult consumed =
        lineIntegralConvolution(handing, handing.releaseOperators(), field, options);
    EXPECT_FALSE(handing.hasOperators());
    EXPECT_TRUE(consumed.values == stateful) << options.channels << " channels";
    EXPECT_EQ(consumed.image.pixels, kept.image.pixels);
    EXPECT_EQ(consumed.report.diffusion.iterations, kept.report.diffusion.iterations);
  }
  TexelDomain domain(procedural::cylinder(16, 8), 48, 48);
  const std::vector<Eigen::Vector2d> field(domain.mesh().faceCount(), Eigen::Vector2d(1, 0));
  EXPECT_THROW(static_cast<void>(lineIntegralConvolution(domain, nullptr, field, {})),
               InvalidInputError);
}

TEST(Lic, SeamContinuousOnTheCubeSphere) {
  TexelDomain domain(procedural::cubeSphere(8), 192, 128);
  // A field along the z axis, projected onto each face (it vanishes at the poles).
  const auto field = fieldInTexelCoordinates(domain.mesh(), domain.grid(),
                                             constantField(domain.mesh(), {0, 0, 1}));
  const LicResult result = lineIntegralConvolution(domain, field, {});
  const SeamJump jump = measureSeamJump(domain.mesh(), domain.atlas(), result.image);
  const double contrast = LicOptions{}.contrast;  // standard deviation of the mapped output
  std::printf("cube sphere LIC: seam jump RMS %.4f (max %.3f), output std %.2f, ratio %.3f\n",
              jump.rms, jump.maxAbs, contrast, jump.rms / contrast);
  EXPECT_LT(jump.rms, 0.25 * contrast);
}

TEST(Lic, AnisotropicMetricShape) {
  TexelDomain domain(procedural::cylinder(16, 8), 64, 64);
  const TexturedMesh& mesh = domain.mesh();
  const TexelGrid& grid = domain.grid();
  const std::vector<Eigen::Matrix2d>& g = domain.operators().metric();
  const auto field = fieldInTexelCoordinates(mesh, grid, constantField(mesh, {0, 0, 1}));
  const double epsilon = 1e-3;
  const auto h = anisotropicMetric(mesh, grid, g, field, epsilon);
  double area = 0.0;
  for (size_t f = 0; f < h.size(); ++f) {
    const int face = static_cast<int>(f);
    area += std::sqrt(h[f].determinant()) * std::abs(fem::gridArea(mesh, grid, face));
    // Generalised eigenvalues of h relative to g: epsilon along u, |u|^2 + epsilon across.
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix2d> eig(h[f], g[f]);
    const double ratio = eig.eigenvalues()(1) / eig.eigenvalues()(0);
    const double along = field[f].dot(h[f] * field[f]) / field[f].dot(g[f] * field[f]);
    ASSERT_NEAR(along / eig.eigenvalues()(0), 1.0, 1e-9) << "u must be the short direction";
    ASSERT_GT(ratio, 10.0) << f;
  }
  EXPECT_NEAR(area, 1.0, 1e-9);
  const std::vector<Eigen::Vector2d> zero(mesh.faceCount(), Eigen::Vector2d::Zero());
  EXPECT_THROW(anisotropicMetric(mesh, grid, g, zero, epsilon), InvalidInputError);
}

TEST(VectorField, FileRoundTripAndErrors) {
  const TexturedMesh mesh = procedural::cube(2);
  const auto dir = test::tempDir("vector_field");
  FaceVectorField extrinsic;
  extrinsic.basis = FieldBasis::Extrinsic;
  FaceVectorField intrinsic;
  intrinsic.basis = FieldBasis::Intrinsic;
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const double s = static_cast<double>(f);
    extrinsic.vectors.emplace_back(std::sin(s), -1.0 / (s + 3.0), 1e-300 * s);
    intrinsic.vectors.emplace_back(std::cos(s) * 1e6, std::numbers::pi * s, 0.0);
  }
  writeFaceVectorField(dir / "e.vf", extrinsic);
  writeFaceVectorField(dir / "i.vf", intrinsic);
  EXPECT_EQ(std::filesystem::file_size(dir / "e.vf"), 4 + mesh.faceCount() * 3 * 8);
  EXPECT_EQ(std::filesystem::file_size(dir / "i.vf"), 4 + mesh.faceCount() * 2 * 8);
  const auto e = readFaceVectorField(dir / "e.vf", FieldBasis::Extrinsic, mesh.faceCount());
  const auto i = readFaceVectorField(dir / "i.vf", FieldBasis::Intrinsic, mesh.faceCount());
  EXPECT_EQ(e.vectors, extrinsic.vectors);
  EXPECT_EQ(i.vectors, intrinsic.vectors);

  const auto expectMessage = [](const auto& call, const std::string& part) {
    try {
      call();
      ADD_FAILURE() << "expected InvalidInputError containing '" << part << "'";
    } catch (const InvalidInputError& error) {
      std::printf("message: %s\n", error.what());
      EXPECT_NE(std::string(error.what()).find(part), std::string::npos) << error.what();
    }
  };
  expectMessage([&] { readFaceVectorField(dir / "e.vf", FieldBasis::Extrinsic, 7); },
                "but the mesh has 7 faces");
  expectMessage([&] { readFaceVectorField(dir / "i.vf", FieldBasis::Extrinsic, mesh.faceCount()); },
                "use --intrinsic");
  {
    std::ofstream out(dir / "short.vf", std::ios::binary);
    out.write("\x05\x00", 2);
  }
  expectMessage([&] { readFaceVectorField(dir / "short.vf", FieldBasis::Extrinsic, 5); },
                "too short");
  EXPECT_THROW(readFaceVectorField(dir / "missing.vf", FieldBasis::Extrinsic, 5), IoError);
}

TEST(VectorField, IntrinsicAndExtrinsicAgreeInTexelCoordinates) {
  TexelDomain domain(procedural::cylinder(16, 8), 64, 64);
  const TexturedMesh& mesh = domain.mesh();
  FaceVectorField intrinsic;
  intrinsic.basis = FieldBasis::Intrinsic;
  FaceVectorField extrinsic;
  extrinsic.basis = FieldBasis::Extrinsic;
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const Eigen::Vector2d ab(0.3 + 0.01 * static_cast<double>(f), -0.7);
    const Triangle& t = mesh.triangles[f];
    intrinsic.vectors.emplace_back(ab.x(), ab.y(), 0.0);
    const Eigen::Vector3d tangent = ab.x() * (mesh.positions[t[1]] - mesh.positions[t[0]]) +
                                    ab.y() * (mesh.positions[t[2]] - mesh.positions[t[0]]);
    const Eigen::Vector3d normal = (mesh.positions[t[1]] - mesh.positions[t[0]])
                                       .cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    extrinsic.vectors.push_back(tangent + 5.0 * normal);  // the normal part must be dropped
  }
  const auto a = fieldInTexelCoordinates(mesh, domain.grid(), intrinsic);
  const auto b = fieldInTexelCoordinates(mesh, domain.grid(), extrinsic);
  for (size_t f = 0; f < a.size(); ++f) EXPECT_LT((a[f] - b[f]).norm(), 1e-9 * a[f].norm()) << f;
}

TEST(VectorField, PrincipalCurvaturesOfCylinderAndSphere) {
  const TexturedMesh cylinder = procedural::cylinder(64, 16);
  const PrincipalCurvatures k = principalCurvatures(cylinder);
  const double radius = 1.0 / (2.0 * std::numbers::pi);
  double worstMajor = 0.0, worstMinor = 0.0, worstAxis = 0.0;
  for (size_t f = 0; f < cylinder.faceCount(); ++f) {
    worstMajor = std::max(worstMajor, std::abs(std::abs(k.kMajor[f]) * radius - 1.0));
    worstMinor = std::max(worstMinor, std::abs(k.kMinor[f] * radius));
    worstAxis = std::max(worstAxis, std::abs(k.dirMajor[f].z()));  // around, not along the axis
  }
  std::printf(
      "cylinder: ||k_major| r - 1| <= %.3f, |k_minor r| <= %.3f, "
      "|dir_major . axis| <= %.3f\n",
      worstMajor, worstMinor, worstAxis);
  EXPECT_LT(worstMajor, 0.05);
  EXPECT_LT(worstMinor, 0.05);
  EXPECT_LT(worstAxis, 0.05);

  const TexturedMesh sphere = procedural::cubeSphere(16);
  const PrincipalCurvatures s = principalCurvatures(sphere);
  double meanMajor = 0.0, meanMinor = 0.0;
  for (size_t f = 0; f < sphere.faceCount(); ++f) {
    meanMajor += std::abs(s.kMajor[f]);
    meanMinor += std::abs(s.kMinor[f]);
  }
  meanMajor /= static_cast<double>(sphere.faceCount());
  meanMinor /= static_cast<double>(sphere.faceCount());
  std::printf("unit sphere: mean |k_major| %.3f, mean |k_minor| %.3f\n", meanMajor, meanMinor);
  EXPECT_NEAR(meanMajor, 1.0, 0.05);
  EXPECT_NEAR(meanMinor, 1.0, 0.05);
}

}  // namespace
}  // namespace texgrad
