// Heat-method geodesics against analytic distances (great circles, anisotropic flat square) and
// multigrid interactive updates against the direct solver on a real mesh.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <vector>

#include "shared_meshes.h"
#include "test_paths.h"
#include "texgrad/apps/dilate.h"
#include "texgrad/apps/distance_colour_map.h"
#include "texgrad/apps/geodesic.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/atlas/cell_clipping.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

/// Area-weighted mean and max relative error of the computed distance function, sampled at the
/// centroid of every piece T ∩ cell (quadratic elements on seam pieces), skipping points closer
/// to the source than `exclusion` (model units).
struct ErrorStats {
  double mean = 0.0, max = 0.0;
  Eigen::Vector3d worst = Eigen::Vector3d::Zero();  ///< where the max occurs
  int samples = 0;
};

/// Largest 3-D edge length of a texel over all faces (model units).
double texelSize(const TexelDomain& domain) {
  const double area = domain.operators().report().metric.surfaceArea;
  double largest = 0.0;
  for (const Eigen::Matrix2d& g : domain.operators().metric())
    if (g.determinant() > 0.0)
      largest =
          std::max(largest, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(g).eigenvalues()[1]);
  return std::sqrt(largest * area);
}

template <typename Truth>
ErrorStats compare(const TexelDomain& domain, const Eigen::VectorXd& distances, double exclusion,
                   const Truth& truth) {
  const fem::TexelBasis& basis = domain.operators().basis();
  const auto& metric = domain.operators().metric();
  ErrorStats stats;
  double weightSum = 0.0;
  auto sample = [&](int face, const Eigen::Vector2d& p, double uvArea, double value) {
    const double exact = truth(basis.position({face, p}));
    if (exact < exclusion) return;
    const double error = std::abs(value - exact) / exact;
    const double weight = uvArea * std::sqrt(metric[static_cast<size_t>(face)].determinant());
    stats.mean += weight * error;
    weightSum += weight;
    if (error > stats.max) {
      stats.max = error;
      stats.worst = basis.position({face, p});
    }
    ++stats.samples;
  };
  FaceClip clip;
  fem::PieceBasis pb;
  const Eigen::Vector3d centre = Eigen::Vector3d::Constant(1.0 / 3.0);
  const auto shape = fem::quadraticShape(centre);
  for (int f = 0; f < basis.faceCount(); ++f) {
    if (!basis.faceValid(f)) continue;
    basis.clipFace(f, clip);
    for (const auto& piece : clip.pieces) {
      const auto poly = clip.polygon(piece);
      if (basis.isPlain(f, poly)) {
        Eigen::Vector2d c = Eigen::Vector2d::Zero();
        for (const auto& v : poly) c += v.p;
        c /= static_cast<double>(poly.size());
        const double fx = c.x() - piece.cellX, fy = c.y() - piece.cellY;
        const std::array<double, 4> w{(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
        const auto texels = basis.cellTexels(piece.cellX, piece.cellY);
        double value = 0.0;
        for (int k = 0; k < 4; ++k)
          if (texels[k] >= 0) value += w[k] * distances[texels[k]];
        sample(f, c, polygonArea(poly), value);
        continue;
      }
      basis.buildPieceBasis(f, poly, pb);
      for (size_t e = 0; e < pb.elements.size(); ++e) {
        const auto& t = pb.elements[e];
        const double area =
            0.5 * ((t[1] - t[0]).x() * (t[2] - t[0]).y() - (t[1] - t[0]).y() * (t[2] - t[0]).x());
        double value = 0.0;
        for (size_t k = 0; k < pb.texels.size(); ++k)
          for (int n = 0; n < 6; ++n)
            value += shape[n] *
                     pb.coefficients(static_cast<Eigen::Index>(6 * e + n),
                                     static_cast<Eigen::Index>(k)) *
                     distances[pb.texels[k]];
        sample(f, (t[0] + t[1] + t[2]) / 3.0, area, value);
      }
    }
  }
  stats.mean /= std::max(weightSum, 1e-300);
  return stats;
}

GeodesicOptions directOptions() {
  GeodesicOptions options;
  options.solver.kind = SolverKind::Direct;
  return options;
}

/// Great-circle distance on the unit sphere that the cube-sphere approximates.
struct GreatCircle {
  Eigen::Vector3d source;
  double operator()(const Eigen::Vector3d& p) const {
    return std::acos(std::clamp(p.normalized().dot(source), -1.0, 1.0));
  }
};

/// Great-circle error of the cube-sphere distances at one resolution; `exclusionTexels` texels of
/// the given resolution (or of this one when 0) around the source are skipped.
ErrorStats sphereError(int resolution, double exclusionTexels, int exclusionResolution = 0) {
  const TexelDomain domain(procedural::cubeSphere(32), resolution, resolution);
  const Eigen::Vector3d target = Eigen::Vector3d(0.3, 0.5, 0.8).normalized();
  const GeodesicSource source = GeodesicSource::atPoint(target);
  const GeodesicResult result = geodesicDistance(domain, {&source, 1}, directOptions());
  const GreatCircle truth{result.sources[0].position.normalized()};
  const double texel =
      texelSize(domain) * resolution / (exclusionResolution > 0 ? exclusionResolution : resolution);
  return compare(domain, result.distances, exclusionTexels * texel, truth);
}

TEST(Geodesic, SphereAccuracySlow) {
  const ErrorStats stats = sphereError(1024, 3.0);
  std::cout << "sphere 1024^2: mean rel error " << stats.mean << ", max " << stats.max << " over "
            << stats.samples << " points; worst at " << stats.worst.transpose() << "\n";
  ASSERT_GT(stats.samples, 100000);
  EXPECT_LE(stats.mean, 0.02);
  EXPECT_LE(stats.max, 0.05);
}

TEST(Geodesic, SphereErrorFallsWithResolution) {
  // The same region (outside 3 texels at 64^2) at every resolution.
  std::vector<ErrorStats> errors;
  for (int resolution : {64, 128, 256}) {
    errors.push_back(sphereError(resolution, 3.0, 64));
    std::cout << "sphere " << resolution << "^2: mean rel error " << errors.back().mean << ", max "
              << errors.back().max << " at " << errors.back().worst.transpose() << "\n";
  }
  for (size_t k = 1; k < errors.size(); ++k) {
    EXPECT_LT(errors[k].mean, errors[k - 1].mean) << k;
    EXPECT_LT(errors[k].max, errors[k - 1].max) << k;
  }
}

TEST(Geodesic, AnisotropicFlatSquareIsEuclidean) {
  // UV squeezes y by 4: texels are 4x longer along y on the surface than along x.
  const TexelDomain domain(procedural::square(1.0, 0.25), 512, 512);
  const Eigen::Vector3d centre(0.5, 0.5, 0.0);
  const GeodesicSource source = GeodesicSource::atPoint(centre);
  const GeodesicResult result = geodesicDistance(domain, {&source, 1}, directOptions());
  EXPECT_NEAR(result.sources[0].uv.x(), 0.5, 1e-12);
  EXPECT_NEAR(result.sources[0].uv.y(), 0.125, 1e-12);
  const auto euclidean = [&](const Eigen::Vector3d& p) { return (p - centre).norm(); };
  const double texel = texelSize(domain);  // 4 / 512 (along y)
  const ErrorStats near = compare(domain, result.distances, 3.0 * texel, euclidean);
  const ErrorStats far = compare(domain, result.distances, 8.0 * texel, euclidean);
  std::cout << "anisotropic square: mean rel error " << near.mean << ", max " << near.max
            << " (outside 3 texels), " << far.max << " (outside 8 texels)\n";
  EXPECT_LE(near.mean, 0.02);
  EXPECT_LE(near.max, 0.05);
  EXPECT_LE(far.max, 0.02);
  // The farthest point is a corner, at distance sqrt(1/2).
  EXPECT_NEAR(result.maxDistance, std::sqrt(0.5), 0.02 * std::sqrt(0.5));
  EXPECT_GT(GeodesicSolver(domain).dirichletTexels(), 0);
  // Neumann only (the paper's boundary condition) bends the level sets at the boundary.
  GeodesicOptions neumann = directOptions();
  neumann.boundary = GeodesicBoundary::Neumann;
  const GeodesicResult bent = geodesicDistance(domain, {&source, 1}, neumann);
  const ErrorStats bentFar = compare(domain, bent.distances, 8.0 * texel, euclidean);
  std::cout << "anisotropic square, Neumann only: mean rel error " << bentFar.mean << ", max "
            << bentFar.max << " (outside 8 texels)\n";
  EXPECT_GT(bentFar.max, 2.0 * far.max);
}

TEST(Geodesic, UnconnectedPartsAreInfinitelyFar) {
  // Two unit squares, 3-D disjoint, side by side in UV.
  TexturedMesh mesh = procedural::square(0.45, 0.45, 0.02, 0.02);
  const TexturedMesh other = procedural::square(0.45, 0.45, 0.52, 0.02);
  const auto base = static_cast<int32_t>(mesh.positions.size());
  const auto uvBase = static_cast<int32_t>(mesh.uvs.size());
  for (const Eigen::Vector3d& p : other.positions)
    mesh.positions.push_back(p + Eigen::Vector3d(0, 0, 1));
  mesh.uvs.insert(mesh.uvs.end(), other.uvs.begin(), other.uvs.end());
  for (size_t f = 0; f < other.triangles.size(); ++f) {
    Triangle t = other.triangles[f], uv = other.uvTriangles[f];
    for (int c = 0; c < 3; ++c) {
      t[c] += base;
      uv[c] += uvBase;
    }
    mesh.triangles.push_back(t);
    mesh.uvTriangles.push_back(uv);
  }
  const TexelDomain domain(std::move(mesh), 128, 64);
  const GeodesicSource source = GeodesicSource::atPoint({0.5, 0.5, 0.0});
  const GeodesicResult result = geodesicDistance(domain, {&source, 1});
  int infinite = 0;
  for (Eigen::Index u = 0; u < result.distances.size(); ++u) {
    const int x = domain.grid().texelOfUnknown[static_cast<size_t>(u)] % domain.grid().nx;
    const bool second = domain.grid().toUv(Eigen::Vector2d(x, 0)).x() > 0.5;
    EXPECT_EQ(std::isinf(result.distances[u]), second) << u;
    infinite += std::isinf(result.distances[u]) ? 1 : 0;
  }
  EXPECT_EQ(result.unreachableTexels, infinite);
  EXPECT_GT(infinite, 0);
  EXPECT_NEAR(result.maxDistance, std::sqrt(0.5), 0.03);
  const Image picture = distanceColourMap(domain.grid(), result.distances, result.maxDistance, 5);
  EXPECT_EQ(picture.width, 128);
  EXPECT_EQ(picture.at(100, 16, 0), 0.5f);  // unreachable: grey
  EXPECT_EQ(picture.at(1, 62, 1), 0.0f);    // outside every chart: black
}

TEST(Geodesic, SourcesResolveAndBadInputIsRefused) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const TexturedMesh& mesh = domain.mesh();
  const ResolvedSource v = resolveSource(domain, GeodesicSource::atVertex(5));
  EXPECT_LT((v.position - mesh.positions[5]).norm(), 1e-12);
  EXPECT_EQ(v.snapDistance, 0.0);
  // A 3-D point off the surface snaps radially (nearly) onto it.
  const ResolvedSource p = resolveSource(domain, GeodesicSource::atPoint({0.0, 0.0, 2.0}));
  EXPECT_NEAR(p.snapDistance, 1.0, 1e-9);
  EXPECT_NEAR(p.position.z(), 1.0, 1e-9);
  // A UV point inside a chart maps to itself.
  const ResolvedSource u = resolveSource(domain, GeodesicSource::atUv(p.uv));
  EXPECT_LT((u.uv - p.uv).norm(), 1e-12);
  EXPECT_LT((u.position - p.position).norm(), 1e-12);
  EXPECT_THROW(resolveSource(domain, GeodesicSource::atVertex(-1)), InvalidInputError);
  EXPECT_THROW(
      resolveSource(domain, GeodesicSource::atVertex(static_cast<int64_t>(mesh.positions.size()))),
      InvalidInputError);
  GeodesicSolver solver(domain);
  EXPECT_THROW(solver.update(), InvalidInputError);
  EXPECT_THROW(solver.setSources({}), InvalidInputError);
  GeodesicOptions bad;
  bad.alpha = -1.0;
  EXPECT_THROW((GeodesicSolver{domain, bad}), InvalidInputError);
}

TEST(Geodesic, OffsetsAndAlphaUpdates) {
  const TexelDomain domain(procedural::cubeSphere(8), 128, 128);
  const fem::TexelBasis& basis = domain.operators().basis();
  const GeodesicSource source = GeodesicSource::atPoint({0.2, -0.4, 0.9});
  GeodesicOptions paper = directOptions();
  paper.offset = GeodesicOffset::Source;
  const GeodesicResult atSource = geodesicDistance(domain, {&source, 1}, paper);
  EXPECT_NEAR(basis.evaluate(atSource.sources[0].point, atSource.distances), 0.0, 1e-12);
  // NearField moves the constant by a fraction of a texel.
  const GeodesicResult nearField = geodesicDistance(domain, {&source, 1}, directOptions());
  const double shift = nearField.distances[0] - atSource.distances[0];
  EXPECT_GT(std::abs(shift), 0.0);
  EXPECT_LT(std::abs(shift), texelSize(domain));
  EXPECT_LT((nearField.distances - atSource.distances -
             Eigen::VectorXd::Constant(domain.unknowns(), shift))
                .cwiseAbs()
                .maxCoeff(),
            1e-9);
  // setAlpha only refactors; the result equals a fresh solver's at that alpha.
  GeodesicSolver solver(domain, directOptions());
  solver.setSource(source);
  solver.setAlpha(3e3);
  solver.solve();
  GeodesicOptions fresh = directOptions();
  fresh.alpha = 3e3;
  const GeodesicResult expected = geodesicDistance(domain, {&source, 1}, fresh);
  EXPECT_LT((solver.distances() - expected.distances).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT((solver.distances() - nearField.distances).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(Geodesic, OneShotMatchesTheSolver) {
  // geodesicDistance keeps one system's solver at a time (and forms A2 only after the heat
  // solve); the distances must be the stateful solver's, bit for bit: with Dirichlet averaging
  // (open square) and without (closed cube-sphere), with float cycles.
  const GeodesicSource source = GeodesicSource::atPoint({0.3, 0.5, 0.8});
  for (TexturedMesh mesh : {procedural::square(1.0, 0.25), procedural::cubeSphere(8)}) {
    const TexelDomain domain(std::move(mesh), 128, 128);
    GeodesicSolver solver(domain);
    solver.setSource(source);
    solver.solve();
    const GeodesicResult once = geodesicDistance(domain, {&source, 1});
    ASSERT_EQ(once.distances.size(), solver.distances().size());
    EXPECT_TRUE((once.distances.array() == solver.distances().array()).all());
    EXPECT_EQ(once.distanceReport.iterations, solver.distanceReport().iterations);
    EXPECT_GT(once.timings.setup, 0.0);
    // The stateful solver goes on after a solve: updates, residuals, and a new alpha whose
    // systems (heat and Dirichlet) replace the old ones in solvers that keep no copy of them.
    const Eigen::VectorXd solved = solver.distances();
    solver.update();
    EXPECT_TRUE(std::isfinite(solver.residual()));
    // Float updates stay near the solution (RMS about 1e-4 of the largest distance, see update();
    // the largest move here is 2.4e-4 of it in a Release build).
    EXPECT_LT((solver.distances() - solved).cwiseAbs().maxCoeff(), 5e-3 * solved.maxCoeff());
    GeodesicOptions other;
    other.alpha = 2e3;
    solver.setAlpha(other.alpha);
    solver.solve();
    const GeodesicResult atOther = geodesicDistance(domain, {&source, 1}, other);
    EXPECT_TRUE((atOther.distances.array() == solver.distances().array()).all());
    EXPECT_GT((atOther.distances - once.distances).cwiseAbs().maxCoeff(), 1e-6);
  }
}

TEST(Geodesic, ThreadCountDoesNotChangeTheResult) {
  // Divergence, transfers and relaxation add in a fixed order: 1 and 2 threads agree bit for bit.
  const TexelDomain domain(procedural::cubeSphere(8), 256, 256);
  const GeodesicSource source = GeodesicSource::atPoint({0.3, 0.5, 0.8});
  std::vector<Eigen::VectorXd> updated, solved;
  for (int threads : {1, 2}) {
    GeodesicOptions options;
    options.solver.multigrid.threads = threads;
    GeodesicSolver solver(domain, options);
    solver.setSource(source);
    for (int k = 0; k < 3; ++k) solver.update();
    updated.push_back(solver.distances());
    solver.solve();
    solved.push_back(solver.distances());
  }
  EXPECT_EQ((updated[0] - updated[1]).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((solved[0] - solved[1]).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Geodesic, UpdatesStopCyclingOnTheHeatOnceFloatRoundingIsReached) {
  const TexelDomain domain(procedural::cubeSphere(8), 256, 256);
  const GeodesicSource source = GeodesicSource::atPoint({0.3, 0.5, 0.8});
  GeodesicSolver exact(domain, directOptions());
  exact.setSource(source);
  exact.solve();
  GeodesicSolver solver(domain, GeodesicOptions::interactive());
  solver.setSource(source);
  int updates = 0;
  for (; updates < 60 && !solver.heatSettled(); ++updates) solver.update();
  ASSERT_TRUE(solver.heatSettled()) << "after " << updates << " updates";
  const double heatError = (solver.diffused() - exact.diffused()).norm() / exact.diffused().norm();
  std::cout << "heat settled after " << updates << " updates, relative error " << heatError << "\n";
  EXPECT_LE(heatError, 1e-5);
  // Later updates leave u as it is and go on refining the distances.
  const Eigen::MatrixXd heat = solver.diffused();
  const auto rms = [&] {
    return (solver.distances() - exact.distances()).norm() /
           std::sqrt(static_cast<double>(domain.unknowns())) / exact.distances().maxCoeff();
  };
  const double before = rms();
  for (int k = 0; k < 20; ++k) solver.update();
  EXPECT_EQ((solver.diffused() - heat).cwiseAbs().maxCoeff(), 0.0);
  std::cout << "distance RMS / max at settling " << before << ", 20 updates later " << rms()
            << "\n";
  EXPECT_LE(rms(), 5e-5);
  // A new source resets u to zero and starts the heat cycles again (a skipped cycle would
  // leave u at zero).
  solver.setSource(GeodesicSource::atPoint({-0.3, 0.5, 0.8}));
  EXPECT_FALSE(solver.heatSettled());
  solver.update();
  EXPECT_GT(solver.diffused().cwiseAbs().maxCoeff(), 0.0);
}

TEST(Geodesic, TwoSourcesGiveTheNearerDistance) {
  const TexelDomain domain(procedural::cubeSphere(16), 256, 256);
  const std::array<GeodesicSource, 2> sources{GeodesicSource::atPoint({0.0, 0.0, 1.0}),
                                              GeodesicSource::atPoint({0.0, 0.0, -1.0})};
  const GeodesicResult result = geodesicDistance(domain, sources, directOptions());
  const Eigen::Vector3d a = result.sources[0].position.normalized();
  const Eigen::Vector3d b = result.sources[1].position.normalized();
  const ErrorStats stats = compare(
      domain, result.distances, 3.0 * texelSize(domain),
      [&](const Eigen::Vector3d& p) { return std::min(GreatCircle{a}(p), GreatCircle{b}(p)); });
  std::cout << "two sources: mean rel error " << stats.mean << ", max " << stats.max << "\n";
  EXPECT_LE(stats.mean, 0.03);
  // The equator is the farthest set, at pi / 2.
  EXPECT_NEAR(result.maxDistance, std::acos(-1.0) / 2.0, 0.03);
}

/// Bounding-box diagonal of the mesh (model units): the scale "1e-3 of the diameter" refers to.
double diameter(const TexturedMesh& mesh) {
  Eigen::Vector3d lo = mesh.positions.front(), hi = lo;
  for (const Eigen::Vector3d& p : mesh.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

/// Lowest finite distance over the active texels (+infinity if there is none).
double lowestDistance(const Eigen::VectorXd& distances) {
  double lowest = std::numeric_limits<double>::infinity();
  for (double d : distances)
    if (std::isfinite(d)) lowest = std::min(lowest, d);
  return lowest;
}

TEST(Geodesic, TwoConesJoinedAtTheApexMatchTheSlantDistance) {
  // The cones touch only at the apex, a non-manifold vertex: a source there seeds both sheets,
  // each is its own component with its own constant, and the distance is the slant |p|.
  const TexelDomain domain(procedural::twoCones(), 256, 256);
  const fem::TexelBasis& basis = domain.operators().basis();
  const double texel = texelSize(domain);
  for (const GeodesicSource& source :
       {GeodesicSource::atVertex(0), GeodesicSource::atPoint(Eigen::Vector3d::Zero())}) {
    const GeodesicResult result = geodesicDistance(domain, {&source, 1}, directOptions());
    ASSERT_EQ(result.sources[0].sheets.size(), 2u);
    EXPECT_EQ(result.unreachableTexels, 0);
    for (const double side : {1.0, -1.0}) {
      // The other cone's points count as "near the source" and are skipped.
      const ErrorStats stats =
          compare(domain, result.distances, 3.0 * texel,
                  [side](const Eigen::Vector3d& p) { return p.z() * side > 0.0 ? p.norm() : 0.0; });
      std::cout << "cone " << side << ": mean rel error " << stats.mean << ", max " << stats.max
                << " over " << stats.samples << " points\n";
      EXPECT_GT(stats.samples, 1000);
      EXPECT_LE(stats.mean, 0.01);
      EXPECT_LE(stats.max, 0.05);
    }
    for (const fem::SurfacePoint& sheet : result.sources[0].sheets) {
      const double atApex = basis.evaluate(sheet, result.distances);
      std::cout << "distance at the apex on face " << sheet.face << ": " << atApex / texel
                << " texels\n";
      EXPECT_LE(std::abs(atApex), 0.5 * texel);
    }
  }
}

TEST(Geodesic, BarelyCoveredTexelsStayNearTheSurfaceDistances) {
  // The cones' arcs and the source at a chart corner leave cells that their chart barely covers.
  const TexelDomain domain(procedural::twoCones(), 256, 256);
  const GeodesicSource source = GeodesicSource::atVertex(0);
  for (SolverKind kind : {SolverKind::Direct, SolverKind::Multigrid}) {
    GeodesicOptions options;
    options.solver.kind = kind;
    const GeodesicResult result = geodesicDistance(domain, {&source, 1}, options);
    const double lowest = lowestDistance(result.distances);
    const double highest = result.distances.maxCoeff();
    std::cout << toString(kind) << ": distances " << lowest << " .. " << highest
              << " (largest on M " << result.maxDistance << ")\n";
    EXPECT_GE(lowest, -1e-3 * diameter(domain.mesh()));
    EXPECT_LE(highest, result.maxDistance + 2.0 * texelSize(domain));
  }
}

TEST(Geodesic, SharedMeshesHaveNoNanAndNoNegativeDistancesSlow) {
  // The output of `texgrad geodesic MESH --source-vertex 0` at 1024², gutters padded: before the
  // cut-cell penalty Lantern reached -1.44 (diameter 30.3) at a barely covered texel, and the
  // padding turned gutters next to unreachable charts into NaN.
  for (const test::SharedMesh& shared : test::sharedMeshes()) {
    const TexelDomain domain(readMesh(test::sharedData() / shared.obj), 1024, 1024,
                             OperatorOptions::assembledOnce());
    const GeodesicSource source = GeodesicSource::atVertex(0);
    const GeodesicResult result = geodesicDistance(domain, {&source, 1});
    const double lowest = lowestDistance(result.distances);
    std::cout << shared.name << ": lowest distance " << lowest / diameter(domain.mesh())
              << " of the diameter, largest " << result.maxDistance << "\n";
    EXPECT_GE(lowest, -1e-3 * diameter(domain.mesh())) << shared.name;
    Image image(1024, 1024, 1, PixelFormat::Float);
    scatterTexels(domain.grid(), result.distances, image);
    const Image padded = dilateGutters(domain.mesh(), domain.atlas(), domain.grid(), image);
    EXPECT_EQ(std::count_if(padded.pixels.begin(), padded.pixels.end(),
                            [](float v) { return std::isnan(v); }),
              0)
        << shared.name;
  }
}

TEST(Geodesic, MultigridUpdatesMatchDirectOnSpotSlow) {
  const test::SharedMesh& spot = test::sharedMeshes().front();
  ASSERT_EQ(spot.name, "spot");
  const TexelDomain domain(readMesh(test::sharedData() / spot.obj), 1024, 1024);
  const GeodesicSource source = GeodesicSource::atVertex(100);
  const GeodesicResult exact = geodesicDistance(domain, {&source, 1}, directOptions());
  GeodesicSolver interactive(domain, GeodesicOptions::interactive());
  interactive.setSource(source);
  std::vector<double> rms;
  for (int update = 0; update < 3; ++update) {
    interactive.update();
    rms.push_back((interactive.distances() - exact.distances).norm() /
                  std::sqrt(static_cast<double>(domain.unknowns())) / exact.maxDistance);
    std::cout << "spot update " << update + 1 << ": RMS / max distance " << rms.back() << "\n";
  }
  EXPECT_LE(rms.back(), 1e-3);
  EXPECT_LT(rms[2], rms[0]);
  const double residualAfter3 = interactive.residual();
  for (int update = 3; update < 20; ++update) {
    interactive.update();
    rms.push_back((interactive.distances() - exact.distances).norm() /
                  std::sqrt(static_cast<double>(domain.unknowns())) / exact.maxDistance);
    std::cout << "spot update " << update + 1 << ": RMS / max distance " << rms.back() << "\n";
  }
  // Float updates (y re-centred every update) settle near 1e-4 and do not drift away.
  EXPECT_LE(*std::max_element(rms.begin() + 9, rms.end()), 2.5e-4);
  const double residualAfter20 = interactive.residual();
  std::cout << "spot residual after 3 / 20 updates: " << residualAfter3 << " / " << residualAfter20
            << "\n";
  EXPECT_LT(residualAfter20, residualAfter3);
  // The one-shot multigrid solve (default cycles) is at least as close.
  const GeodesicResult multigrid = geodesicDistance(domain, {&source, 1});
  const double oneShot = (multigrid.distances - exact.distances).norm() /
                         std::sqrt(static_cast<double>(domain.unknowns())) / exact.maxDistance;
  std::cout << "spot one-shot multigrid: RMS / max distance " << oneShot << "\n";
  EXPECT_LE(oneShot, 1e-3);
}

}  // namespace
}  // namespace texgrad
