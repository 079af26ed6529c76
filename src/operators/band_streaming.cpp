// Operators assembled once (OperatorOptions::keepPieceIntegrals = false): the plain pieces are
// clipped, integrated and assembled one window of cell-row bands at a time, so that only that
// window's pieces are ever held (docs/memory.md, plan item 6); the same sums as assemble(). A
// deferred assembly (OperatorOptions::deferAssembly) also holds S's values of a column only until
// the column is complete: a visitor sees the column of M and S, which becomes alpha M + S in M's
// values, so S is never held whole; or, in float (screenedSystemInFloat), a FloatSystem's entries,
// M's values then held by window too.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "texel_operators_impl.h"
#include "texgrad/core/error.h"
#include "texgrad/core/page_allocator.h"

namespace texgrad {
namespace {

/// Windows per build: about 1/kWindows of the plain pieces are held at a time, and a face is
/// clipped once more for every window border it crosses (faces scale with the texture, so the
/// share of such faces does not grow with it).
constexpr int kWindows = 64;

/// Bands per window: even (see windowOf), about bandCount / kWindows, at least 2.
int windowBands(int bandCount) {
  const int w = (bandCount + kWindows - 1) / kWindows;
  return std::max(2, w + (w & 1));
}

/// Window of band b for w bands per window: window 0 holds bands [0, w], window k >= 1 the
/// bands [k w + 1, (k + 1) w]. Every window ends at an even band and the next starts at an odd
/// one, so the even band of two neighbours is assembled first, as assembleBands orders them.
int windowOf(int b, int w) {
  return std::max(b - 1, 0) / w;
}

/// First band of window k.
int windowStart(int k, int w) {
  return k == 0 ? 0 : k * w + 1;
}

}  // namespace

void TexelOperators::Impl::planWindows(std::span<const int32_t> first,
                                       std::span<const int32_t> last, int bandCount,
                                       StreamPlan& plan) {
  const int w = windowBands(bandCount);
  const int windows = windowOf(bandCount - 1, w) + 1;
  plan.windowBand.resize(static_cast<size_t>(windows) + 1);
  for (int k = 0; k <= windows; ++k) plan.windowBand[k] = std::min(bandCount, windowStart(k, w));
  const auto faces = static_cast<int>(first.size());
  auto forEachFaceWindow = [&](const auto& use) {
    for (int f = 0; f < faces; ++f)
      if (last[f] >= 0)
        for (int k = windowOf(first[f], w); k <= windowOf(last[f], w); ++k) use(f, k);
  };
  plan.faceBegin.assign(static_cast<size_t>(windows) + 1, 0);
  forEachFaceWindow([&](int, int k) { ++plan.faceBegin[static_cast<size_t>(k) + 1]; });
  for (int k = 0; k < windows; ++k) plan.faceBegin[k + 1] += plan.faceBegin[k];
  plan.faces.resize(static_cast<size_t>(plan.faceBegin.back()));
  std::vector<int64_t> cursor(plan.faceBegin.begin(), plan.faceBegin.end() - 1);
  forEachFaceWindow([&](int f, int k) { plan.faces[cursor[k]++] = f; });
}

TexelOperators::Impl::ColumnValues TexelOperators::Impl::columnValuesOf(
    const SparseMatrixd& pattern, std::vector<int32_t> columns) {
  ColumnValues out;
  out.start.assign(columns.size() + 1, 0);
  for (size_t i = 0; i < columns.size(); ++i)
    out.start[i + 1] = out.start[i] + pattern.outerIndexPtr()[columns[i] + 1] -
                       pattern.outerIndexPtr()[columns[i]];
  out.values.assign(static_cast<size_t>(out.start.back()), 0.0);
  out.columns = std::move(columns);
  return out;
}

double* TexelOperators::Impl::ColumnValues::of(int column) {
  const auto i = std::lower_bound(columns.begin(), columns.end(), column) - columns.begin();
  return values.data() + start[static_cast<size_t>(i)];
}

void TexelOperators::Impl::prepareStreamed(std::vector<Eigen::Matrix2d> faceMetric,
                                           const ProgressCallback& progress) {
  const TexelGrid& grid = basis.grid();
  bandCount = band(grid.ny - 1) + 1;
  std::vector<uint8_t> covered(grid.cellCount(), 0);
  FaceBands bands = scanFaces(covered);
  report.seamPieces = static_cast<int>(seam.size());
  reportProgress(progress, "integrate pieces", 0.6);
  buildPattern(covered);
  std::vector<uint8_t>().swap(covered);
  // The faces with seam pieces, ascending (`seam` is in face order); their pieces are clipped
  // and integrated again after the plain ones, rather than held (13 B/t at spot 4096²).
  stream = StreamPlan();
  for (const SeamPiece& sp : seam)
    if (stream.seamFaces.empty() || stream.seamFaces.back() != sp.face)
      stream.seamFaces.push_back(sp.face);
  if (deferred) {
    stream.seamColumns = seamTexels;
    std::sort(stream.seamColumns.begin(), stream.seamColumns.end());
    stream.seamColumns.erase(std::unique(stream.seamColumns.begin(), stream.seamColumns.end()),
                             stream.seamColumns.end());
  }
  releasePieces();
  factors = factorsOf(faceMetric, "TexelOperators");
  metric = std::move(faceMetric);
  planWindows(bands.first, bands.last, bandCount, stream);
}

void TexelOperators::Impl::assembleStreamed(std::vector<Eigen::Matrix2d> faceMetric,
                                            const ProgressCallback& progress) {
  prepareStreamed(std::move(faceMetric), progress);
  reportProgress(progress, "assemble", 0.8);
  stiffnessValues.assign(static_cast<size_t>(mass.nonZeros()), 0.0);  // M's: zeros already
  const int windows = stream.windows();
  for (int k = 0; k < windows; ++k) {
    assembleWindow(k, mass.valuePtr(), 0, stiffnessValues.data(), 0);
    reportProgress(progress, "assemble", 0.8 + 0.2 * (k + 1) / windows);
  }
  assembleSeamFaces(mass.valuePtr(), stiffnessValues.data(), nullptr);
  stream = StreamPlan();
  finishStiffness(stiffnessValues.data());
  buildSeamContinuity();
}

void TexelOperators::Impl::assembleScreened(double alpha, const ColumnVisitor& visit,
                                            const ProgressCallback& progress,
                                            FloatSystem* out) {
  const TexelGrid& grid = basis.grid();
  if (grid.unknownOfTexel.empty())
    throw InvalidInputError(
        "screenedSystem: the grid's per-texel maps were freed (TexelDomain::releaseImageMaps) "
        "before these operators' deferred assembly, which reads them; free them after it");
  const int n = grid.unknownCount();
  const int* outer = mass.outerIndexPtr();
  const int* inner = mass.innerIndexPtr();
  const auto nonZeros = static_cast<size_t>(mass.nonZeros());
  // In float, M's values are held by window as S's are, and M's own value array, never touched
  // (buildPattern leaves it to the assembly), is dropped whatever pages the heap gave it.
  double* massValues = out ? nullptr : mass.valuePtr();
  if (out) {
    detail::discardWholePages(mass.valuePtr(), nonZeros * sizeof(double));
    *out = FloatSystem(n, mass.outerIndexPtr(), mass.innerIndexPtr(), exactUnknowns());
  } else {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nonZeros, size_t{1} << 16),
                      [&](const tbb::blocked_range<size_t>& r) {
                        std::fill(massValues + r.begin(), massValues + r.end(), 0.0);
                      });
  }
  // Unknowns are numbered row by row: the first unknown in texel row y or above.
  auto firstUnknownOfRow = [&](int y) {
    const int32_t t = std::clamp(y, 0, grid.ny) * grid.nx;
    return static_cast<int>(
        std::lower_bound(grid.texelOfUnknown.begin(), grid.texelOfUnknown.end(), t) -
        grid.texelOfUnknown.begin());
  };
  // Column u of M and S complete in `m` and `s`: S's diagonal formed, shown, then alpha M + S,
  // in place (M's values, or in float the window's copy) and then into `out` with its sum.
  auto finishColumn = [&](int u, double* m, double* s) {
    const int length = outer[u + 1] - outer[u];
    const std::span<const int> rows(inner + outer[u], static_cast<size_t>(length));
    detail::zeroColumnSum(rows, u, std::span(s, static_cast<size_t>(length)));
    if (visit)
      visit(OperatorColumn{u, rows, std::span<const double>(m, static_cast<size_t>(length)),
                           std::span<const double>(s, static_cast<size_t>(length))});
    for (int k = 0; k < length; ++k) m[k] = alpha * m[k] + s[k];
    if (out) out->setColumn(u, std::span<const double>(m, static_cast<size_t>(length)));
  };
  const std::vector<int32_t>& seamColumns = stream.seamColumns;
  ColumnValues seamStiffness = columnValuesOf(mass, seamColumns);
  ColumnValues seamMass = out ? columnValuesOf(mass, seamColumns) : ColumnValues();
  // S's (and in float M's) values of the columns [first, ...) that window k reaches, from
  // position outer[first].
  std::vector<double> held, heldMass;
  int first = 0;
  const int windows = stream.windows();
  for (int k = 0; k < windows; ++k) {
    // After window k the cell rows below `cellEnd` are in: they reach the texel rows up to
    // cellEnd, and the columns of the texel rows below it are complete but for seam pieces.
    const int cellEnd = firstCellRow(stream.windowBand[k + 1]);
    const int complete = k + 1 == windows ? n : firstUnknownOfRow(cellEnd);
    const int reached = k + 1 == windows ? n : firstUnknownOfRow(cellEnd + 1);
    const auto span = static_cast<size_t>(outer[reached] - outer[first]);
    held.resize(span, 0.0);
    if (out) heldMass.resize(span, 0.0);
    assembleWindow(k, out ? heldMass.data() : massValues, out ? outer[first] : 0, held.data(),
                   outer[first]);
    tbb::parallel_for(tbb::blocked_range<int>(first, complete, 1024),
                      [&](const tbb::blocked_range<int>& columns) {
                        for (int u = columns.begin(); u != columns.end(); ++u) {
                          const int64_t at = outer[u] - outer[first];
                          double* s = held.data() + at;
                          double* m = out ? heldMass.data() + at : massValues + outer[u];
                          if (!std::binary_search(seamColumns.begin(), seamColumns.end(), u)) {
                            finishColumn(u, m, s);
                            continue;
                          }
                          const int length = outer[u + 1] - outer[u];
                          std::copy(s, s + length, seamStiffness.of(u));
                          if (out) std::copy(m, m + length, seamMass.of(u));
                        }
                      });
    const auto done = static_cast<std::ptrdiff_t>(outer[complete] - outer[first]);
    held.erase(held.begin(), held.begin() + done);
    if (out) heldMass.erase(heldMass.begin(), heldMass.begin() + done);
    first = complete;
    reportProgress(progress, "assemble", 0.95 * (k + 1) / windows);
  }
  std::vector<double>().swap(held);
  std::vector<double>().swap(heldMass);
  assembleSeamFaces(massValues, nullptr, &seamStiffness, out ? &seamMass : nullptr);
  tbb::parallel_for(size_t(0), seamColumns.size(), [&](size_t i) {
    const int u = seamColumns[i];
    double* m = out ? seamMass.values.data() + seamMass.start[i] : massValues + outer[u];
    finishColumn(u, m, seamStiffness.values.data() + seamStiffness.start[i]);
  });
  stream = StreamPlan();
  deferred = false;
  buildSeamContinuity();
  reportProgress(progress, "assemble", 1.0);
}

TexelOperators::Impl::FaceBands TexelOperators::Impl::scanFaces(std::vector<uint8_t>& covered) {
  const TexelGrid& grid = basis.grid();
  const int faces = basis.faceCount();
  const int grain = options.facesPerTask;
  FaceBands bands;
  bands.first.assign(static_cast<size_t>(faces), std::numeric_limits<int32_t>::max());
  bands.last.assign(static_cast<size_t>(faces), -1);
  std::vector<Chunk> chunks(static_cast<size_t>((faces + grain - 1) / grain));
  tbb::parallel_for(0, static_cast<int>(chunks.size()), [&](int c) {
    Chunk& chunk = chunks[c];
    SeamScratch scratch;
    chunk.unexpected += forEachPiece(
        c * grain, std::min(faces, (c + 1) * grain), [](int f) { return f; },
        [&](int f, const FacePiece& piece, std::span<const PieceVertex> poly) {
          // Faces of other tasks may share the cell: a relaxed atomic store of the same value.
          std::atomic_ref<uint8_t>(covered[grid.cellIndex(piece.cellX, piece.cellY)])
              .store(1, std::memory_order_relaxed);
          if (basis.isPlain(f, poly)) {
            bands.first[f] = std::min(bands.first[f], band(piece.cellY));
            bands.last[f] = std::max(bands.last[f], band(piece.cellY));
          } else {
            addSeamPiece(f, piece, poly, chunk, scratch, false);
          }
        });
  });
  for (const Chunk& chunk : chunks) report.unexpectedCrossings += chunk.unexpected;
  gatherSeamPieces(chunks);
  return bands;
}

void TexelOperators::Impl::assembleWindow(int k, double* massOut, int64_t massFirst,
                                          double* stiffnessOut, int64_t stiffnessFirst) {
  const auto begin = static_cast<size_t>(stream.faceBegin[k]);
  const auto end = static_cast<size_t>(stream.faceBegin[k + 1]);
  const std::span<const int32_t> faces = std::span(stream.faces).subspan(begin, end - begin);
  const int lo = stream.windowBand[k], hi = stream.windowBand[k + 1];
  const int grain = options.facesPerTask;
  const auto count = static_cast<int>(faces.size());
  std::vector<Chunk> chunks(static_cast<size_t>((count + grain - 1) / grain));
  tbb::parallel_for(0, static_cast<int>(chunks.size()), [&](int c) {
    // Unexpected crossings were counted in scanFaces.
    forEachPiece(
        c * grain, std::min(count, (c + 1) * grain), [&](int i) { return faces[i]; },
        [&](int f, const FacePiece& piece, std::span<const PieceVertex> poly) {
          const int b = band(piece.cellY);
          if (b >= lo && b < hi && basis.isPlain(f, poly)) addPlainPiece(f, piece, poly, chunks[c]);
        });
  });
  const PlainPieces pieces = bucketByBand(chunks, lo, hi);
  report.plainFullPieces += static_cast<int>(pieces.full.size());
  report.plainPartialPieces += static_cast<int>(pieces.partial.size());
  assembleBands(pieces, factors, nullptr, massOut, stiffnessOut, stiffnessFirst, massFirst);
}

void TexelOperators::Impl::assembleSeamFaces(double* massOut, double* stiffnessOut,
                                             ColumnValues* stiffnessColumns,
                                             ColumnValues* massColumns) {
  const std::vector<int32_t>& seamFaces = stream.seamFaces;
  // Chunks of faces integrated in parallel and added in chunk order (the order of `seam`), a few
  // chunks in flight, as sumOverSurface does.
  const int grain = options.facesPerTask;
  const auto faces = static_cast<int>(seamFaces.size());
  const int chunks = (faces + grain - 1) / grain;
  int next = 0;
  const auto chunkIndices = tbb::make_filter<void, int>(tbb::filter_mode::serial_in_order,
                                                        [&](tbb::flow_control& control) {
                                                          if (next == chunks) control.stop();
                                                          return next++;
                                                        });
  const auto integrateChunk = tbb::make_filter<int, Chunk>(tbb::filter_mode::parallel, [&](int c) {
    Chunk chunk;
    SeamScratch scratch;
    forEachPiece(
        c * grain, std::min(faces, (c + 1) * grain), [&](int i) { return seamFaces[i]; },
        [&](int f, const FacePiece& piece, std::span<const PieceVertex> poly) {
          if (!basis.isPlain(f, poly)) addSeamPiece(f, piece, poly, chunk, scratch);
        });
    return chunk;
  });
  const auto addInOrder =
      tbb::make_filter<Chunk, void>(tbb::filter_mode::serial_in_order, [&](const Chunk& chunk) {
        assembleSeams(chunk.seam, chunk.texels.data(), chunk.values.data(), factors, nullptr,
                      massOut, stiffnessOut, stiffnessColumns, massColumns);
      });
  tbb::parallel_pipeline(static_cast<size_t>(2 * tbb::this_task_arena::max_concurrency()),
                         chunkIndices & integrateChunk & addInOrder);
}

}  // namespace texgrad
