// Operators assembled once (keepPieceIntegrals = false: plain pieces integrated and assembled a
// window of bands at a time) against the kept pieces' assembly: the same pattern and the same
// bits in M, S and C, on procedural meshes at sizes that put window borders in many places, with
// one thread and with all, and on the shared meshes. Likewise a deferred assembly
// (deferAssembly: S held a column at a time until complete) against operators assembled first:
// the same columns of M and S shown to the visitor, each once, and the same alpha M + S.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>

#include "../fem/fem_fixtures.h"
#include "shared_meshes.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/operators/texel_operators.h"

namespace texgrad {
namespace {

/// True if n bytes at a and at b are the same (n may be 0: the pointers may then be null, as an
/// empty matrix's are, which memcmp must not be given).
bool sameBytes(const void* a, const void* b, size_t n) {
  return n == 0 || std::memcmp(a, b, n) == 0;
}

/// Same index arrays and bit-identical values (memcmp: -0.0 is not 0.0 here).
::testing::AssertionResult identical(const SparseRefd& a, const SparseRefd& b) {
  if (a.rows() != b.rows() || a.outerSize() != b.outerSize() || a.nonZeros() != b.nonZeros())
    return ::testing::AssertionFailure()
           << "sizes differ: " << a.nonZeros() << " / " << b.nonZeros();
  const size_t outerBytes = a.outerSize() > 0 ? sizeof(int) * size_t(a.outerSize() + 1) : 0;
  if (!sameBytes(a.outerIndexPtr(), b.outerIndexPtr(), outerBytes) ||
      !sameBytes(a.innerIndexPtr(), b.innerIndexPtr(), sizeof(int) * size_t(a.nonZeros())))
    return ::testing::AssertionFailure() << "patterns differ";
  Eigen::Index differing = 0;
  for (Eigen::Index k = 0; k < a.nonZeros(); ++k)
    differing += std::memcmp(a.valuePtr() + k, b.valuePtr() + k, sizeof(double)) != 0;
  if (differing > 0)
    return ::testing::AssertionFailure() << differing << " of " << a.nonZeros() << " values differ";
  return ::testing::AssertionSuccess();
}

/// Builds the operators of `mesh` at resolution x resolution with the pieces kept and once
/// without, and expects the same operators bit for bit.
void expectStreamedMatchesKept(const TexturedMesh& mesh, int resolution,
                               const OperatorOptions& options, const std::string& name) {
  SCOPED_TRACE(name + " at " + std::to_string(resolution));
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, resolution, resolution);
  OperatorOptions kept = options, once = options;
  kept.keepPieceIntegrals = true;
  once.keepPieceIntegrals = false;
  const TexelOperators a(mesh, atlas, grid, kept);
  const TexelOperators b(mesh, atlas, grid, once);
  EXPECT_TRUE(identical(a.mass(), b.mass()));
  EXPECT_TRUE(identical(a.stiffness(), b.stiffness()));
  EXPECT_TRUE(identical(a.seamContinuity(), b.seamContinuity()));
  EXPECT_EQ(a.report().plainFullPieces, b.report().plainFullPieces);
  EXPECT_EQ(a.report().plainPartialPieces, b.report().plainPartialPieces);
  EXPECT_EQ(a.report().seamPieces, b.report().seamPieces);
  EXPECT_EQ(a.report().unexpectedCrossings, b.report().unexpectedCrossings);
  EXPECT_EQ(a.metric(), b.metric());
}

/// The columns a visitor was shown, on M's pattern: M's and S's values at their positions, and
/// how many times each column was shown.
struct VisitedColumns {
  SparseMatrixd mass, stiffness;
  std::vector<std::atomic<int>> visits;
  explicit VisitedColumns(const SparseMatrixd& pattern)
      : mass(pattern), stiffness(pattern), visits(static_cast<size_t>(pattern.cols())) {
    mass.coeffs().setConstant(std::nan(""));
    stiffness.coeffs().setConstant(std::nan(""));
  }
  /// Records a column (called concurrently for different columns).
  ColumnVisitor visitor() {
    return [this](const OperatorColumn& c) {
      ++visits[static_cast<size_t>(c.column)];
      const int first = mass.outerIndexPtr()[c.column];
      const int count = mass.outerIndexPtr()[c.column + 1] - first;
      if (static_cast<size_t>(count) != c.rows.size() ||
          !std::equal(c.rows.begin(), c.rows.end(), mass.innerIndexPtr() + first))
        return;  // left NaN: fails the comparison
      std::copy(c.mass.begin(), c.mass.end(), mass.valuePtr() + first);
      std::copy(c.stiffness.begin(), c.stiffness.end(), stiffness.valuePtr() + first);
    };
  }
  /// Columns not shown exactly once.
  int wrongVisits() const {
    int wrong = 0;
    for (const std::atomic<int>& v : visits) wrong += v.load() != 1;
    return wrong;
  }
};

/// Assembles `mesh` at resolution x resolution first (assembledOnce), and deferred to the
/// visiting screenedSystem, and expects the visitor to see M and S bit for bit, each column once,
/// and the same alpha M + S (+ alpha lambda C); also for operators assembled first.
void expectDeferredMatchesAssembled(const TexturedMesh& mesh, int resolution,
                                    const OperatorOptions& options, const std::string& name) {
  SCOPED_TRACE(name + " at " + std::to_string(resolution));
  constexpr double kAlpha = 0.37;
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, resolution, resolution);
  OperatorOptions once = options, deferral = options;
  once.keepPieceIntegrals = deferral.keepPieceIntegrals = false;
  deferral.deferAssembly = true;
  const TexelOperators assembled(mesh, atlas, grid, once);
  for (const OperatorOptions& built : {deferral, once}) {
    auto operators = std::make_unique<TexelOperators>(mesh, atlas, grid, built);
    EXPECT_EQ(operators->assemblyDeferred(), built.deferAssembly);
    VisitedColumns seen(assembled.mass());
    const SparseMatrixd system =
        TexelOperators::screenedSystem(std::move(operators), kAlpha, seen.visitor());
    EXPECT_EQ(seen.wrongVisits(), 0) << "deferred " << built.deferAssembly;
    EXPECT_TRUE(identical(seen.mass, assembled.mass())) << "deferred " << built.deferAssembly;
    EXPECT_TRUE(identical(seen.stiffness, assembled.stiffness()))
        << "deferred " << built.deferAssembly;
    EXPECT_TRUE(identical(system, assembled.screenedSystem(kAlpha)))
        << "deferred " << built.deferAssembly;
  }
}

TEST(StreamedAssembly, MatchesTheKeptPiecesBitForBit) {
  OperatorOptions bilinear;
  bilinear.basis = fem::BasisKind::Bilinear;
  bilinear.seamContinuityWeight = 0.5;
  // Sizes from one window (a few bands) to dozens, the borders falling on various rows.
  for (int resolution : {24, 61, 203})
    expectStreamedMatchesKept(test::cubeSphere(4), resolution, {}, "sphere");
  for (int resolution : {96, 333})
    expectStreamedMatchesKept(test::twoChartSquare(3, 0.05), resolution, {}, "twoChartDense");
  expectStreamedMatchesKept(test::gridSquare(3, 0.9, 0.8, 0.031, 0.077), 160, {}, "square");
  expectStreamedMatchesKept(test::twoChartSquare(5), 150, bilinear, "twoChart bilinear");
  // Small tasks: many face chunks per window and among the seam faces.
  OperatorOptions small;
  small.facesPerTask = 2;
  expectStreamedMatchesKept(test::cubeSphere(4), 128, small, "sphere, 2 faces per task");
}

TEST(DeferredAssembly, ShowsEveryColumnOfMAndSOnceAndGivesTheSameSystem) {
  OperatorOptions bilinear;
  bilinear.basis = fem::BasisKind::Bilinear;
  bilinear.seamContinuityWeight = 0.5;
  for (int resolution : {12, 24, 61, 203})  // 12: a single window
    expectDeferredMatchesAssembled(test::cubeSphere(4), resolution, {}, "sphere");
  for (int resolution : {96, 333})
    expectDeferredMatchesAssembled(test::twoChartSquare(3, 0.05), resolution, {}, "twoChartDense");
  for (int resolution : {10, 160})  // one chart: no seam pieces
    expectDeferredMatchesAssembled(test::gridSquare(3, 0.9, 0.8, 0.031, 0.077), resolution, {},
                                   "square");
  expectDeferredMatchesAssembled(test::twoChartSquare(5), 150, bilinear, "twoChart bilinear");
  OperatorOptions small;
  small.facesPerTask = 2;
  expectDeferredMatchesAssembled(test::cubeSphere(4), 128, small, "sphere, 2 faces per task");
}

TEST(DeferredAssembly, HasNoMatricesUntilAssembledAndNeedsThePiecesFreed) {
  const TexturedMesh mesh = test::cubeSphere(4);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, 64, 64);
  OperatorOptions options = OperatorOptions::assembledOnce();
  options.deferAssembly = true;
  const TexelOperators deferred(mesh, atlas, grid, options);
  EXPECT_TRUE(deferred.assemblyDeferred());
  EXPECT_THROW(static_cast<void>(deferred.mass()), InvalidInputError);
  EXPECT_THROW(static_cast<void>(deferred.stiffness()), InvalidInputError);
  EXPECT_THROW(static_cast<void>(deferred.seamContinuity()), InvalidInputError);
  EXPECT_THROW(static_cast<void>(deferred.screenedSystem(1.0)), InvalidInputError);
  const TexelOperators assembled(mesh, atlas, grid, OperatorOptions::assembledOnce());
  EXPECT_EQ(deferred.texelPairs(), assembled.texelPairs()) << "the pattern is there";
  // The assembly reads the grid's per-texel maps: freed before it, it refuses.
  TexelGrid freed = grid;
  auto reading = std::make_unique<TexelOperators>(mesh, atlas, freed, options);
  freed.unknownOfTexel.clear();
  EXPECT_THROW(static_cast<void>(TexelOperators::screenedSystem(std::move(reading), 1.0, {})),
               InvalidInputError);
  options.keepPieceIntegrals = true;
  EXPECT_THROW(options.validate(), InvalidInputError);
}

TEST(StreamedAssembly, DoesNotDependOnTheThreadCount) {
  const TexturedMesh mesh = test::cubeSphere(4);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, 160, 160);
  OperatorOptions options = OperatorOptions::assembledOnce();
  options.facesPerTask = 3;
  const TexelOperators all(mesh, atlas, grid, options);
  std::unique_ptr<TexelOperators> one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = std::make_unique<TexelOperators>(mesh, atlas, grid, options);
  }
  EXPECT_TRUE(identical(all.mass(), one->mass()));
  EXPECT_TRUE(identical(all.stiffness(), one->stiffness()));
}

// A real atlas: seams, slivers, charts of every shape (~1 s per mesh in Release).
TEST(StreamedAssembly, MatchesTheKeptPiecesOnTheSharedMeshesSlow) {
  for (const test::SharedMesh& shared : test::sharedMeshes()) {
    const TexturedMesh mesh = readMesh(test::sharedData() / shared.obj);
    expectStreamedMatchesKept(mesh, 512, {}, shared.name);
    expectDeferredMatchesAssembled(mesh, 512, {}, shared.name);
  }
}

}  // namespace
}  // namespace texgrad
