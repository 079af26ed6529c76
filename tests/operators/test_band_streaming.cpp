// Operators assembled once (keepPieceIntegrals = false: plain pieces integrated and assembled a
// window of bands at a time) against the kept pieces' assembly: the same pattern and the same
// bits in M, S and C, on procedural meshes at sizes that put window borders in many places, with
// one thread and with all, and on the shared meshes. Likewise a deferred assembly
// (deferAssembly: S held a column at a time until complete) against operators assembled first:
// the same columns of M and S shown to the visitor, each once, and the same alpha M + S; and
// alpha M + S in float (screenedSystemInFloat, roundedSystem): the double one rounded, with the
// irregular rows exact and every row's sum.
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

/// A mesh's atlas and grid at resolution x resolution, options that assemble once and that defer
/// the assembly, and operators assembled once.
struct AssembledAndDeferred {
  AssembledAndDeferred(const TexturedMesh& mesh, int resolution, const OperatorOptions& options)
      : atlas(buildAtlas(mesh)),
        grid(buildTexelGrid(mesh, atlas, resolution, resolution)),
        once(withPiecesFreed(options, false)),
        deferral(withPiecesFreed(options, true)),
        assembled(mesh, atlas, grid, once) {}
  /// `options` with the piece integrals freed, the assembly deferred or not.
  static OperatorOptions withPiecesFreed(OperatorOptions options, bool deferred) {
    options.keepPieceIntegrals = false;
    options.deferAssembly = deferred;
    return options;
  }
  Atlas atlas;
  TexelGrid grid;
  OperatorOptions once, deferral;
  TexelOperators assembled;
};

/// Expects the visitor to have seen each column once and `assembled`'s M and S bit for bit.
void expectVisitedAsAssembled(const VisitedColumns& seen, const TexelOperators& assembled,
                              bool deferred) {
  EXPECT_EQ(seen.wrongVisits(), 0) << "deferred " << deferred;
  EXPECT_TRUE(identical(seen.mass, assembled.mass())) << "deferred " << deferred;
  EXPECT_TRUE(identical(seen.stiffness, assembled.stiffness())) << "deferred " << deferred;
}

/// Assembles `mesh` at resolution x resolution first (assembledOnce), and deferred to the
/// visiting screenedSystem, and expects the visitor to see M and S bit for bit, each column once,
/// and the same alpha M + S (+ alpha lambda C); also for operators assembled first.
void expectDeferredMatchesAssembled(const TexturedMesh& mesh, int resolution,
                                    const OperatorOptions& options, const std::string& name) {
  SCOPED_TRACE(name + " at " + std::to_string(resolution));
  constexpr double kAlpha = 0.37;
  const AssembledAndDeferred both(mesh, resolution, options);
  for (const OperatorOptions& built : {both.deferral, both.once}) {
    auto operators = std::make_unique<TexelOperators>(mesh, both.atlas, both.grid, built);
    EXPECT_EQ(operators->assemblyDeferred(), built.deferAssembly);
    VisitedColumns seen(both.assembled.mass());
    const SparseMatrixd system =
        TexelOperators::screenedSystem(std::move(operators), kAlpha, seen.visitor());
    expectVisitedAsAssembled(seen, both.assembled, built.deferAssembly);
    EXPECT_TRUE(identical(system, both.assembled.screenedSystem(kAlpha)))
        << "deferred " << built.deferAssembly;
  }
}

/// Expects `f` to be `a` (symmetric, compressed) rounded: the same pattern, every entry in the
/// row or column of an exact unknown exactly a's and the others a's rounded to float, each row's
/// sum a's entries summed in column order in double and rounded.
void expectRounded(const FloatSystem& f, const SparseMatrixd& a, const std::vector<uint8_t>& exact,
                   const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_EQ(f.rows(), a.rows());
  ASSERT_EQ(f.nonZeros(), a.nonZeros());
  ASSERT_TRUE(std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1, f.outer()));
  ASSERT_TRUE(std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), f.inner()));
  int64_t wrongValues = 0, wrongMarks = 0, wrongSums = 0;
  for (int u = 0; u < a.outerSize(); ++u) {
    double sum = 0.0;
    for (int e = a.outerIndexPtr()[u]; e < a.outerIndexPtr()[u + 1]; ++e) {
      const double v = a.valuePtr()[e];
      const bool marked = exact[static_cast<size_t>(u)] || exact[a.innerIndexPtr()[e]];
      wrongMarks += f.exact(e) != marked;
      const double expected = marked ? v : static_cast<double>(static_cast<float>(v));
      const double got = f.value(e);
      wrongValues += std::memcmp(&got, &expected, sizeof(double)) != 0;
      sum += v;
    }
    wrongSums += f.rowSums()[static_cast<size_t>(u)] != static_cast<float>(sum);
  }
  EXPECT_EQ(wrongMarks, 0);
  EXPECT_EQ(wrongValues, 0);
  EXPECT_EQ(wrongSums, 0);
}

/// Unknowns that are not exact are interior texels whose columns reach their 3 x 3 lattice
/// neighbours only: the regular stencils a float multigrid rounds anyway.
void expectInexactAreRegular(const TexelGrid& grid, const SparseMatrixd& pattern,
                             const std::vector<uint8_t>& exact) {
  ASSERT_EQ(exact.size(), static_cast<size_t>(grid.unknownCount()));
  int irregular = 0, boundary = 0;
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const int32_t t = grid.texelOfUnknown[static_cast<size_t>(u)];
    boundary += grid.texelClass[static_cast<size_t>(t)] != TexelClass::Interior;
    if (exact[static_cast<size_t>(u)]) continue;
    bool regular = grid.texelClass[static_cast<size_t>(t)] == TexelClass::Interior;
    for (int e = pattern.outerIndexPtr()[u]; e < pattern.outerIndexPtr()[u + 1]; ++e) {
      const int32_t o = grid.texelOfUnknown[static_cast<size_t>(pattern.innerIndexPtr()[e])];
      regular = regular && std::abs(o % grid.nx - t % grid.nx) <= 1 &&
                std::abs(o / grid.nx - t / grid.nx) <= 1;
    }
    irregular += !regular;
  }
  EXPECT_EQ(irregular, 0);
  EXPECT_GT(boundary, 0);
  EXPECT_GE(std::count(exact.begin(), exact.end(), uint8_t{1}), boundary);
}

/// screenedSystemInFloat on `mesh`, deferred and assembled first, against screenedSystem: the
/// visitor sees the same columns, and the system is the double one rounded (expectRounded), as
/// roundedSystem gives it.
void expectFloatSystemRoundsTheDoubleOne(const TexturedMesh& mesh, int resolution,
                                         const OperatorOptions& options, const std::string& name) {
  SCOPED_TRACE(name + " at " + std::to_string(resolution));
  constexpr double kAlpha = 0.37;
  const AssembledAndDeferred both(mesh, resolution, options);
  const std::vector<uint8_t> exact = both.assembled.exactUnknowns();
  expectInexactAreRegular(both.grid, both.assembled.mass(), exact);
  const SparseMatrixd reference = both.assembled.screenedSystem(kAlpha);
  expectRounded(roundedSystem(both.assembled.screenedSystem(kAlpha), exact), reference, exact,
                "roundedSystem");
  for (const OperatorOptions& built : {both.deferral, both.once}) {
    auto operators = std::make_unique<TexelOperators>(mesh, both.atlas, both.grid, built);
    VisitedColumns seen(both.assembled.mass());
    const FloatSystem f =
        TexelOperators::screenedSystemInFloat(std::move(operators), kAlpha, seen.visitor());
    expectVisitedAsAssembled(seen, both.assembled, built.deferAssembly);
    expectRounded(f, reference, exact, built.deferAssembly ? "deferred" : "assembled first");
  }
}

TEST(FloatAssembly, RoundsTheDoubleSystemKeepingIrregularRowsExactAndEveryRowSum) {
  for (int resolution : {12, 61, 203})
    expectFloatSystemRoundsTheDoubleOne(test::cubeSphere(4), resolution, {}, "sphere");
  expectFloatSystemRoundsTheDoubleOne(test::twoChartSquare(3, 0.05), 96, {}, "twoChartDense");
  expectFloatSystemRoundsTheDoubleOne(test::gridSquare(3, 0.9, 0.8, 0.031, 0.077), 160, {},
                                      "square");
  OperatorOptions small;
  small.facesPerTask = 2;
  expectFloatSystemRoundsTheDoubleOne(test::cubeSphere(4), 128, small, "sphere, 2 faces per task");
  // A seam-continuity weight's C may add entries: refused.
  OperatorOptions bilinear = OperatorOptions::assembledOnce();
  bilinear.basis = fem::BasisKind::Bilinear;
  bilinear.seamContinuityWeight = 0.5;
  const TexturedMesh mesh = test::twoChartSquare(5);
  const Atlas atlas = buildAtlas(mesh);
  const TexelGrid grid = buildTexelGrid(mesh, atlas, 40, 40);
  EXPECT_THROW(static_cast<void>(TexelOperators::screenedSystemInFloat(
                   std::make_unique<TexelOperators>(mesh, atlas, grid, bilinear), 1.0, {})),
               InvalidInputError);
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
