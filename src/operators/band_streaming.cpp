// Operators assembled once (OperatorOptions::keepPieceIntegrals = false): the plain pieces are
// clipped, integrated and assembled one window of cell-row bands at a time, so that only that
// window's pieces are ever held (docs/memory.md, plan item 6); the same sums as assemble().
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

namespace texgrad {
namespace {

/// Windows per build: about 1/kWindows of the plain pieces are held at a time, and a face is
/// clipped once more for every window border it crosses (faces scale with the texture, so the
/// share of such faces does not grow with it).
constexpr int kWindows = 16;

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

/// The faces of each window, ascending (a face is in every window its plain pieces meet):
/// window k holds faces[begin[k]] to faces[begin[k + 1] - 1].
struct WindowFaces {
  std::vector<int64_t> begin;
  std::vector<int32_t> faces;
};

/// The windows' faces, for the bands first[f] to last[f] of each face f (none if last[f] < 0),
/// w bands per window.
WindowFaces windowFacesOf(std::span<const int32_t> first, std::span<const int32_t> last, int w,
                          int windows) {
  const auto faces = static_cast<int>(first.size());
  auto forEachFaceWindow = [&](const auto& use) {
    for (int f = 0; f < faces; ++f)
      if (last[f] >= 0)
        for (int k = windowOf(first[f], w); k <= windowOf(last[f], w); ++k) use(f, k);
  };
  WindowFaces out;
  out.begin.assign(static_cast<size_t>(windows) + 1, 0);
  forEachFaceWindow([&](int, int k) { ++out.begin[static_cast<size_t>(k) + 1]; });
  for (int k = 0; k < windows; ++k) out.begin[k + 1] += out.begin[k];
  out.faces.resize(static_cast<size_t>(out.begin.back()));
  std::vector<int64_t> cursor(out.begin.begin(), out.begin.end() - 1);
  forEachFaceWindow([&](int f, int k) { out.faces[cursor[k]++] = f; });
  return out;
}

}  // namespace

void TexelOperators::Impl::assembleStreamed(std::vector<Eigen::Matrix2d> faceMetric,
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
  std::vector<int32_t> seamFaces;
  for (const SeamPiece& sp : seam)
    if (seamFaces.empty() || seamFaces.back() != sp.face) seamFaces.push_back(sp.face);
  releasePieces();
  reportProgress(progress, "assemble", 0.8);
  factors = factorsOf(faceMetric, "TexelOperators");
  metric = std::move(faceMetric);
  stiffnessValues.assign(static_cast<size_t>(mass.nonZeros()), 0.0);  // M's: zeros already

  const int w = windowBands(bandCount);
  const int windows = windowOf(bandCount - 1, w) + 1;
  const WindowFaces windowFaces = windowFacesOf(bands.first, bands.last, w, windows);
  bands = FaceBands();
  for (int k = 0; k < windows; ++k) {
    const auto begin = static_cast<size_t>(windowFaces.begin[k]);
    const auto end = static_cast<size_t>(windowFaces.begin[k + 1]);
    assembleWindow(std::span(windowFaces.faces).subspan(begin, end - begin), windowStart(k, w),
                   std::min(bandCount, windowStart(k + 1, w)));
    reportProgress(progress, "assemble", 0.8 + 0.2 * (k + 1) / windows);
  }
  assembleSeamFaces(seamFaces);
  finishStiffness(stiffnessValues.data());
  buildSeamContinuity();
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

void TexelOperators::Impl::assembleWindow(std::span<const int32_t> faces, int lo, int hi) {
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
  assembleBands(pieces, factors, nullptr, mass.valuePtr(), stiffnessValues.data());
}

void TexelOperators::Impl::assembleSeamFaces(const std::vector<int32_t>& seamFaces) {
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
                      mass.valuePtr(), stiffnessValues.data());
      });
  tbb::parallel_pipeline(static_cast<size_t>(2 * tbb::this_task_arena::max_concurrency()),
                         chunkIndices & integrateChunk & addInOrder);
}

}  // namespace texgrad
