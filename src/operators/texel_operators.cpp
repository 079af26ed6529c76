// Operator assembly: (A) per-face clipping and metric-independent integrals in fixed face chunks
// (parallel), (B) metric/beta-dependent accumulation into a precomputed pattern, cell-row bands in
// two colours (parallel, disjoint columns), seam pieces last: bit-identical for any thread count.
// Operators assembled once run A and B window by window instead (band_streaming.cpp).
#include "texgrad/operators/texel_operators.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "texel_operators_impl.h"
#include "texgrad/core/error.h"
#include "texgrad/core/page_allocator.h"
#include "texgrad/core/storage_bytes.h"

namespace texgrad {
namespace {

constexpr int kBandRows = 8;  ///< cell rows per assembly band (two bands apart never share a row)

/// Frees a vector's storage (`v = {}` would keep its capacity).
template <typename T>
void freeStorage(std::vector<T>& v) {
  std::vector<T>().swap(v);
}

/// Appends the upper triangle of a symmetric k x k matrix, column by column (k (k + 1) / 2 values).
void appendUpperTriangle(const Eigen::MatrixXd& m, std::vector<double>& out) {
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r <= c; ++r) out.push_back(m(r, c));
}

/// Read access (r, c) to a symmetric matrix stored by appendUpperTriangle.
struct PackedSymmetric {
  const double* values;
  double operator()(int r, int c) const {
    return r <= c ? values[c * (c + 1) / 2 + r] : values[r * (r + 1) / 2 + c];
  }
};

/// Throws UnsupportedError if the n columns' entry counts (counts[1..n]) sum past what M's int
/// positions index (Eigen's default StorageIndex): about 2^31 entries, some 230M texels at ~9.4
/// per column, which a 16384² atlas of high coverage reaches.
void requireIndexableNonZeros(const int* counts, int n) {
  int64_t total = 0;
  for (int u = 1; u <= n; ++u) total += counts[u];
  if (total > std::numeric_limits<int>::max())
    throw UnsupportedError("the texel operators would have " + std::to_string(total) +
                           " non-zeros (" + std::to_string(n) +
                           " active texels), more than 32-bit positions index; process the "
                           "atlas at a lower resolution");
}

}  // namespace

void OperatorOptions::validate() const {
  if (facesPerTask < 1) throw InvalidInputError("OperatorOptions.facesPerTask must be >= 1");
  if (!(seamContinuityWeight >= 0.0) || !std::isfinite(seamContinuityWeight))
    throw InvalidInputError("OperatorOptions.seamContinuityWeight must be finite and >= 0");
  if (deferAssembly && keepPieceIntegrals)
    throw InvalidInputError(
        "OperatorOptions.deferAssembly needs keepPieceIntegrals = false (a deferred assembly "
        "never holds the piece integrals)");
  if (seamContinuityWeight != 0.0 && basis != fem::BasisKind::Bilinear)
    throw InvalidInputError(
        "OperatorOptions.seamContinuityWeight applies to the Bilinear basis only (the "
        "seam-continuous basis has no seam jumps to penalise); set it to 0 or choose Bilinear");
}

double meanDiagonal(const SparseRefd& a) {
  if (a.rows() == 0) return 0.0;
  double sum = 0.0;
  for (Eigen::Index j = 0; j < a.outerSize(); ++j)
    for (SparseRefd::InnerIterator it(a, j); it; ++it)
      if (it.row() == j) sum += it.value();
  return sum / static_cast<double>(a.rows());
}

int64_t sparseStorageBytes(const SparseMatrixd& a) {
  constexpr int64_t kEntryBytes = sizeof(double) + sizeof(int);
  const int64_t outer = a.outerIndexPtr() ? (a.outerSize() + 1) * int64_t(sizeof(int)) : 0;
  const int64_t counts = a.isCompressed() ? 0 : a.outerSize() * int64_t(sizeof(int));
  return static_cast<int64_t>(a.data().allocatedSize()) * kEntryBytes + outer + counts;
}

OperatorOptions OperatorOptions::assembledOnce() {
  OperatorOptions options;
  options.keepPieceIntegrals = false;
  return options;
}

int TexelOperators::Impl::band(int cellY) const { return (cellY + 1) / kBandRows; }

int TexelOperators::Impl::firstCellRow(int b) { return b * kBandRows - 1; }

void TexelOperators::Impl::requireAssembled(const char* caller) const {
  if (deferred)
    throw InvalidInputError(std::string(caller) +
                            ": these operators were built with OperatorOptions::deferAssembly "
                            "and not assembled yet; assemble them with the visiting "
                            "TexelOperators::screenedSystem, or build them without deferAssembly");
}

void TexelOperators::Impl::addPlainPiece(int face, const FacePiece& piece,
                                         std::span<const PieceVertex> poly, Chunk& chunk) {
  if (piece.full)
    chunk.full.push_back({face, piece.cellX, piece.cellY});
  else
    chunk.partial.push_back(
        {face, piece.cellX, piece.cellY, detail::polygonMoments(poly, piece.cellX, piece.cellY)});
}

void TexelOperators::Impl::addSeamPiece(int face, const FacePiece& piece,
                                        std::span<const PieceVertex> poly, Chunk& chunk,
                                        SeamScratch& scratch, bool integrate) const {
  basis.buildPieceBasis(face, poly, scratch.basis);
  const std::vector<int32_t>& texels = scratch.basis.texels;
  SeamPiece sp{face, piece.cellX, piece.cellY, 0, 0, 0};
  sp.texelBegin = static_cast<int32_t>(chunk.texels.size());
  sp.valueBegin = static_cast<int64_t>(chunk.values.size());
  chunk.texels.insert(chunk.texels.end(), texels.begin(), texels.end());
  sp.texelEnd = static_cast<int32_t>(chunk.texels.size());
  if (!integrate) {
    chunk.seam.push_back(sp);
    return;
  }
  detail::quadraticIntegrals(scratch.basis, scratch.integrals);
  const detail::LocalIntegrals& li = scratch.integrals;
  for (const Eigen::MatrixXd* m : {&li.mass, &li.kxx, &li.kxy, &li.kyy})
    appendUpperTriangle(*m, chunk.values);
  chunk.seam.push_back(sp);
}

void TexelOperators::Impl::integratePieces(const ProgressCallback& progress) {
  const int faces = basis.faceCount();
  const int grain = options.facesPerTask;
  const int chunks = (faces + grain - 1) / grain;
  std::vector<Chunk> out(chunks);
  tbb::parallel_for(0, chunks, [&](int c) {
    Chunk& chunk = out[c];
    SeamScratch scratch;
    chunk.unexpected += forEachPiece(
        c * grain, std::min(faces, (c + 1) * grain), [](int f) { return f; },
        [&](int f, const FacePiece& piece, std::span<const PieceVertex> poly) {
          if (basis.isPlain(f, poly))
            addPlainPiece(f, piece, poly, chunk);
          else
            addSeamPiece(f, piece, poly, chunk, scratch);
        });
  });
  reportProgress(progress, "integrate pieces", 0.6);
  for (const Chunk& chunk : out) report.unexpectedCrossings += chunk.unexpected;
  gatherSeamPieces(out);
  bandCount = band(basis.grid().ny - 1) + 1;
  plain = bucketByBand(out, 0, bandCount);
  report.plainFullPieces = static_cast<int>(plain.full.size());
  report.plainPartialPieces = static_cast<int>(plain.partial.size());
  report.seamPieces = static_cast<int>(seam.size());
}

void TexelOperators::Impl::gatherSeamPieces(std::vector<Chunk>& chunks) {
  // Concatenated in chunk order, every chunk copied on its own task.
  struct Offsets {
    size_t seam = 0, texels = 0, values = 0;
  };
  std::vector<Offsets> at(chunks.size() + 1);
  for (size_t c = 0; c < chunks.size(); ++c)
    at[c + 1] = {at[c].seam + chunks[c].seam.size(), at[c].texels + chunks[c].texels.size(),
                 at[c].values + chunks[c].values.size()};
  seam.resize(at.back().seam);
  seamTexels.resize(at.back().texels);
  seamValues.resize(at.back().values);
  tbb::parallel_for(size_t(0), chunks.size(), [&](size_t c) {
    Chunk& chunk = chunks[c];
    std::copy(chunk.texels.begin(), chunk.texels.end(), seamTexels.begin() + at[c].texels);
    std::copy(chunk.values.begin(), chunk.values.end(), seamValues.begin() + at[c].values);
    for (size_t k = 0; k < chunk.seam.size(); ++k) {
      SeamPiece sp = chunk.seam[k];
      sp.texelBegin += static_cast<int32_t>(at[c].texels);
      sp.texelEnd += static_cast<int32_t>(at[c].texels);
      sp.valueBegin += static_cast<int64_t>(at[c].values);
      seam[at[c].seam + k] = sp;
    }
    freeStorage(chunk.seam);
    freeStorage(chunk.texels);
    freeStorage(chunk.values);
  });
}

TexelOperators::Impl::PlainPieces TexelOperators::Impl::bucketByBand(std::vector<Chunk>& chunks,
                                                                     int firstBand,
                                                                     int endBand) const {
  // Bucketed straight from the chunks (a stable sort of their concatenation), each chunk freed
  // once copied, so no second full copy is ever held.
  PlainPieces out;
  out.firstBand = firstBand;
  const auto bands = static_cast<size_t>(endBand - firstBand);
  auto bucket = [&](auto member, auto& sorted, std::vector<int64_t>& begin) {
    begin.assign(bands + 1, 0);
    for (const Chunk& chunk : chunks)
      for (const auto& p : chunk.*member)
        ++begin[static_cast<size_t>(band(p.cellY) - firstBand) + 1];
    for (size_t b = 0; b < bands; ++b) begin[b + 1] += begin[b];
    std::vector<int64_t> cursor(begin.begin(), begin.end() - 1);
    sorted.resize(static_cast<size_t>(begin.back()));
    for (Chunk& chunk : chunks) {
      for (const auto& p : chunk.*member) sorted[cursor[band(p.cellY) - firstBand]++] = p;
      freeStorage(chunk.*member);
    }
  };
  bucket(&Chunk::full, out.full, out.fullBandBegin);
  bucket(&Chunk::partial, out.partial, out.partialBandBegin);
  return out;
}

std::vector<uint8_t> TexelOperators::Impl::coveredCells() const {
  const TexelGrid& grid = basis.grid();
  std::vector<uint8_t> covered(grid.cellCount(), 0);
  auto mark = [&](const auto& pieces) {
    for (const auto& p : pieces) covered[grid.cellIndex(p.cellX, p.cellY)] = 1;
  };
  mark(plain.full);
  mark(plain.partial);
  mark(seam);
  return covered;
}

void TexelOperators::Impl::buildPattern(const std::vector<uint8_t>& cellCovered) {
  const TexelGrid& grid = basis.grid();
  // Extra (column, row) pairs created by seam pieces.
  std::vector<std::pair<int32_t, int32_t>> extra;
  for (const SeamPiece& sp : seam)
    for (int32_t i = sp.texelBegin; i < sp.texelEnd; ++i)
      for (int32_t j = sp.texelBegin; j < sp.texelEnd; ++j)
        extra.emplace_back(seamTexels[i], seamTexels[j]);
  tbb::parallel_sort(extra.begin(), extra.end());
  extra.erase(std::unique(extra.begin(), extra.end()), extra.end());
  const int n = grid.unknownCount();
  // Column u: the texels of the covered cells around texel u and u's seam pairs, ascending.
  // Texel (x + dx, y + dy) shares with u the cells (x - 1 + i, y - 1 + j) with i in I(dx),
  // j in I(dy): I(-1) = {0}, I(0) = {0, 1}, I(1) = {1}. Unknowns are numbered in row-major
  // order, so the 3 x 3 neighbours come ascending; seam pairs are merged in.
  using Extra = std::vector<std::pair<int32_t, int32_t>>::const_iterator;
  auto columnOf = [&](int u, Extra& e, std::vector<int32_t>& column) {
    column.clear();
    const int t = grid.texelOfUnknown[u];
    const int x = t % grid.nx, y = t / grid.nx;
    bool covered[2][2];  // [j][i]: cell (x - 1 + i, y - 1 + j)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) covered[j][i] = cellCovered[grid.cellIndex(x - 1 + i, y - 1 + j)];
    for (int dy = -1; dy <= 1; ++dy) {
      if (y + dy < 0 || y + dy >= grid.ny) continue;
      for (int dx = -1; dx <= 1; ++dx) {
        if (x + dx < 0 || x + dx >= grid.nx) continue;
        bool shared = false;
        for (int j = std::max(0, dy); j <= std::min(1, dy + 1); ++j)
          for (int i = std::max(0, dx); i <= std::min(1, dx + 1); ++i) shared |= covered[j][i];
        const int32_t v = grid.unknownOfTexel[grid.texelIndex(x + dx, y + dy)];
        if (shared && v >= 0) column.push_back(v);
      }
    }
    const auto neighbours = static_cast<std::ptrdiff_t>(column.size());
    for (; e != extra.cend() && e->first == u; ++e) column.push_back(e->second);
    if (static_cast<std::ptrdiff_t>(column.size()) == neighbours) return;
    std::inplace_merge(column.begin(), column.begin() + neighbours, column.end());
    column.erase(std::unique(column.begin(), column.end()), column.end());
  };
  // Blocks of unknowns on all cores, twice: count each column into M's column starts, then
  // write it straight into M's index array (no per-block copies: docs/memory.md).
  constexpr int kBlock = 1 << 14;
  const int blocks = (n + kBlock - 1) / kBlock;
  auto forEachColumn = [&](const auto& use) {
    tbb::parallel_for(0, blocks, [&](int block) {
      const int first = block * kBlock, last = std::min(n, first + kBlock);
      Extra e =
          std::lower_bound(extra.cbegin(), extra.cend(),
                           std::pair<int32_t, int32_t>(first, std::numeric_limits<int32_t>::min()));
      std::vector<int32_t> column;
      for (int u = first; u < last; ++u) {
        columnOf(u, e, column);
        use(u, column);
      }
    });
  };
  // The mass matrix holds the shared pattern (no separate copy: it is the largest structure).
  mass.resize(n, n);
  int* outer = mass.outerIndexPtr();
  forEachColumn([&](int u, const std::vector<int32_t>& column) {
    outer[u + 1] = static_cast<int>(column.size());
  });
  outer[0] = 0;
  requireIndexableNonZeros(outer, n);
  for (int u = 0; u < n; ++u) outer[u + 1] += outer[u];
  mass.resizeNonZeros(outer[n]);
  forEachColumn([&](int u, const std::vector<int32_t>& column) {
    std::copy(column.begin(), column.end(), mass.innerIndexPtr() + outer[u]);
    // A deferred assembly zeroes them when it runs, if it uses them (assembleScreened).
    if (!deferred) std::fill_n(mass.valuePtr() + outer[u], column.size(), 0.0);
  });
}

namespace {

/// Where one column's values of a matrix with M's pattern are: position p at values[p - first].
struct ColumnSlice {
  double* values;
  int64_t first;
};

/// Adds local (k x k) values into the entries (row texels[j], column texels[i]) of a matrix with
/// the pattern of `m` (column-major CSC); columnOf(column) is the ColumnSlice they go to.
template <typename Local, typename ColumnOf>
void scatter(const SparseMatrixd& m, const int32_t* texels, int k, const Local& local, double scale,
             const ColumnOf& columnOf) {
  const int* outer = m.outerIndexPtr();
  const int* inner = m.innerIndexPtr();
  for (int i = 0; i < k; ++i) {
    if (texels[i] < 0) continue;
    const int* begin = inner + outer[texels[i]];
    const int* end = inner + outer[texels[i] + 1];
    const ColumnSlice column = columnOf(texels[i]);
    for (int j = 0; j < k; ++j) {
      if (texels[j] < 0) continue;
      const int* pos = std::lower_bound(begin, end, texels[j]);
      column.values[pos - inner - column.first] += scale * local(j, i);
    }
  }
}

/// Positions in the values of a matrix with the pattern of `m` of the entries (row texels[j],
/// column texels[i]) of a cell's four texels, at [4 i + j]; -1 where a texel is missing. The
/// present texels of a cell ascend (unknowns are row-major), so each search starts at the last.
std::array<int, 16> cellEntries(const SparseMatrixd& m, const std::array<int32_t, 4>& texels) {
  const int* outer = m.outerIndexPtr();
  const int* inner = m.innerIndexPtr();
  std::array<int, 16> at;
  at.fill(-1);
  for (int i = 0; i < 4; ++i) {
    if (texels[i] < 0) continue;
    const int* begin = inner + outer[texels[i]];
    const int* end = inner + outer[texels[i] + 1];
    for (int j = 0; j < 4; ++j) {
      if (texels[j] < 0) continue;
      begin = std::lower_bound(begin, end, texels[j]);
      at[4 * i + j] = static_cast<int>(begin - inner);
    }
  }
  return at;
}

/// values[at[4 i + j] - first] += scale * local(j, i) at the entries cellEntries found (as
/// scatter adds), for values that start at position `first` of the pattern.
void addCell(const std::array<int, 16>& at, const Eigen::Matrix4d& local, double scale,
             double* values, int64_t first = 0) {
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (at[4 * i + j] >= 0) values[at[4 * i + j] - first] += scale * local(j, i);
}

/// Neumaier's compensated sum of values[begin, end) without values[skip]: within an ulp of the
/// exact sum, whatever the cancellation (a column of S mixes entries from 1e-15 to 1e3).
double sumExcept(const double* values, int begin, int end, int skip) {
  double sum = 0.0, compensation = 0.0;
  for (int k = begin; k < end; ++k) {
    if (k == skip) continue;
    const double next = sum + values[k];
    compensation +=
        std::abs(sum) >= std::abs(values[k]) ? (sum - next) + values[k] : (values[k] - next) + sum;
    sum = next;
  }
  return sum + compensation;
}

/// Sets every diagonal entry of a symmetric matrix with the pattern of `m` to minus the sum of
/// the other entries of its column (detail::zeroColumnSum).
void zeroColumnSums(const SparseMatrixd& m, double* values) {
  const int* outer = m.outerIndexPtr();
  const int* inner = m.innerIndexPtr();
  tbb::parallel_for(tbb::blocked_range<int>(0, static_cast<int>(m.outerSize()), 1 << 12),
                    [&](const tbb::blocked_range<int>& columns) {
                      for (int t = columns.begin(); t != columns.end(); ++t) {
                        const auto length = static_cast<size_t>(outer[t + 1] - outer[t]);
                        detail::zeroColumnSum(std::span(inner + outer[t], length), t,
                                              std::span(values + outer[t], length));
                      }
                    });
}

}  // namespace

/// The stiffness is S_h = d^T *1 d (paper Sec. 5.3) with d 1 = 0 because the texel functions are
/// a partition of unity (Claim 3): S_tt = -sum_{s != t} S_st holds exactly. Summed piece by piece
/// as integrated, S 1 is off by the rounding of the parts: on a seam piece of a UV sliver with a
/// stretched metric (spot at 256^2, face 3968: 10 x 0.04 texels in UV, metric anisotropy 268) the
/// metric factors combine stiffness parts of up to 1e4 into entries of about 1, whose rows vanish
/// only to 5e-12. Formed here, a row's sum is zero up to one rounding of its diagonal. Every
/// column with an entry holds its diagonal: a piece adds (t, t) with every (s, t).
void detail::zeroColumnSum(std::span<const int> rows, int column, std::span<double> values) {
  const auto diagonal = std::lower_bound(rows.begin(), rows.end(), column);
  if (diagonal == rows.end() || *diagonal != column) return;
  const auto at = static_cast<int>(diagonal - rows.begin());
  values[static_cast<size_t>(at)] =
      -sumExcept(values.data(), 0, static_cast<int>(values.size()), at);
}

void TexelOperators::Impl::assemble(const std::vector<FaceFactors>& faceFactors, const double* beta,
                                    double* massOut, double* stiffnessOut) const {
  for (double* out : {massOut, stiffnessOut})
    if (out) std::fill_n(out, mass.nonZeros(), 0.0);
  assembleBands(plain, faceFactors, beta, massOut, stiffnessOut);
  assembleSeams(seam, seamTexels.data(), seamValues.data(), faceFactors, beta, massOut,
                stiffnessOut);
  if (stiffnessOut) finishStiffness(stiffnessOut);
}

void TexelOperators::Impl::finishStiffness(double* stiffnessOut) const {
  zeroColumnSums(mass, stiffnessOut);
}

void TexelOperators::Impl::assembleBands(const PlainPieces& pieces,
                                         const std::vector<FaceFactors>& faceFactors,
                                         const double* beta, double* massOut,
                                         double* stiffnessOut, int64_t stiffnessFirst,
                                         int64_t massFirst) const {
  const TexelGrid& grid = basis.grid();
  static const detail::BilinearIntegrals unit = detail::bilinearIntegrals(detail::unitCellMoments());
  auto cellBeta = [&](int a, int b) { return beta ? beta[grid.cellIndex(a, b)] : 1.0; };
  auto add = [&](int face, int a, int b, const detail::BilinearIntegrals& in) {
    const FaceFactors& f = faceFactors[face];
    const std::array<int, 16> at = cellEntries(mass, basis.cellTexels(a, b));
    if (massOut) addCell(at, in.mass, f.mass, massOut, massFirst);
    if (stiffnessOut) {
      const Eigen::Matrix4d s = f.xx * in.kxx + f.xy * in.kxy + f.yy * in.kyy;
      addCell(at, s, cellBeta(a, b), stiffnessOut, stiffnessFirst);
    }
  };
  const int first = pieces.firstBand;
  const int end = first + static_cast<int>(pieces.fullBandBegin.size()) - 1;
  for (int colour = 0; colour < 2; ++colour) {
    const int start = first + ((first & 1) != colour ? 1 : 0);  // first band of this colour
    tbb::parallel_for(0, std::max(0, (end - start + 1) / 2), [&](int half) {
      const int b = start + 2 * half - first;
      for (int64_t i = pieces.fullBandBegin[b]; i < pieces.fullBandBegin[b + 1]; ++i) {
        const FullPiece& p = pieces.full[i];
        add(p.face, p.cellX, p.cellY, unit);
      }
      for (int64_t i = pieces.partialBandBegin[b]; i < pieces.partialBandBegin[b + 1]; ++i) {
        const PartialPiece& p = pieces.partial[i];
        add(p.face, p.cellX, p.cellY, detail::bilinearIntegrals(p.moments));
      }
    });
  }
}

void TexelOperators::Impl::assembleSeams(std::span<const SeamPiece> pieces, const int32_t* texels,
                                         const double* values,
                                         const std::vector<FaceFactors>& faceFactors,
                                         const double* beta, double* massOut, double* stiffnessOut,
                                         ColumnValues* stiffnessColumns,
                                         ColumnValues* massColumns) const {
  const TexelGrid& grid = basis.grid();
  auto sliceOf = [&](ColumnValues* columns, double* whole, int column) {
    return columns ? ColumnSlice{columns->of(column), mass.outerIndexPtr()[column]}
                   : ColumnSlice{whole, 0};
  };
  auto massSlice = [&](int column) { return sliceOf(massColumns, massOut, column); };
  auto stiffnessSlice = [&](int column) { return sliceOf(stiffnessColumns, stiffnessOut, column); };
  std::vector<double> combined;
  for (const SeamPiece& sp : pieces) {
    const int k = sp.texelEnd - sp.texelBegin;
    const FaceFactors& f = faceFactors[sp.face];
    const double* v = values + sp.valueBegin;
    const int packed = k * (k + 1) / 2;
    if (massOut || massColumns)
      scatter(mass, texels + sp.texelBegin, k, PackedSymmetric{v}, f.mass, massSlice);
    if (stiffnessOut || stiffnessColumns) {
      combined.resize(static_cast<size_t>(packed));
      for (int i = 0; i < packed; ++i)
        combined[i] = f.xx * v[packed + i] + f.xy * v[2 * packed + i] + f.yy * v[3 * packed + i];
      scatter(mass, texels + sp.texelBegin, k, PackedSymmetric{combined.data()},
              beta ? beta[grid.cellIndex(sp.cellX, sp.cellY)] : 1.0, stiffnessSlice);
    }
  }
}

TexelOperators::TexelOperators(const TexturedMesh& mesh, const Atlas& atlas,
                               const TexelGrid& grid, const OperatorOptions& options,
                               const ProgressCallback& progress) {
  options.validate();
  impl_ = std::make_unique<Impl>(mesh, atlas, grid, options);
  reportProgress(progress, "integrate pieces", 0.0);
  std::vector<Eigen::Matrix2d> metric = fem::immersionMetric(mesh, grid, &impl_->report.metric);
  if (options.keepPieceIntegrals) {
    impl_->integratePieces(progress);
    impl_->buildPattern(impl_->coveredCells());
    reportProgress(progress, "assemble", 0.8);
    setMetric(std::move(metric));
  } else if (options.deferAssembly) {
    impl_->deferred = true;
    impl_->prepareStreamed(std::move(metric), progress);
    reportProgress(progress, "integrate pieces", 1.0);
    return;
  } else {
    impl_->assembleStreamed(std::move(metric), progress);
  }
  reportProgress(progress, "assemble", 1.0);
}

void TexelOperators::Impl::releasePieces() {
  plain = {};  // move-assigns empty vectors: frees the storage
  freeStorage(seam);
  freeStorage(seamTexels);
  freeStorage(seamValues);
  piecesReleased = true;
}

void TexelOperators::releasePieceIntegrals() {
  impl_->releasePieces();
}

void TexelOperators::Impl::requirePieces(const char* caller) const {
  if (piecesReleased)
    throw InvalidInputError(std::string(caller) +
                            ": these operators were built with "
                            "OperatorOptions::keepPieceIntegrals = false, so they cannot be "
                            "re-assembled; build them with keepPieceIntegrals = true");
}

TexelOperators::~TexelOperators() = default;

std::vector<TexelOperators::Impl::FaceFactors> TexelOperators::Impl::factorsOf(
    const std::vector<Eigen::Matrix2d>& faceMetric, const char* caller) const {
  if (static_cast<int>(faceMetric.size()) != basis.faceCount())
    throw InvalidInputError(std::string(caller) + ": expected one 2x2 metric per face (" +
                            std::to_string(basis.faceCount()) + "), got " +
                            std::to_string(faceMetric.size()));
  std::vector<FaceFactors> out(faceMetric.size());
  for (size_t f = 0; f < faceMetric.size(); ++f) {
    if (!basis.faceValid(static_cast<int>(f))) continue;
    const Eigen::Matrix2d& g = faceMetric[f];
    const double det = g.determinant();
    if (!(det > 0.0) || !(g(0, 0) > 0.0) || !std::isfinite(det) || g(0, 1) != g(1, 0))
      throw InvalidInputError(std::string(caller) + ": the metric of face " + std::to_string(f) +
                              " is not symmetric positive definite");
    const double root = std::sqrt(det);
    out[f] = {root, root * g(1, 1) / det, -root * g(0, 1) / det, root * g(0, 0) / det};
  }
  return out;
}

void TexelOperators::setMetric(std::vector<Eigen::Matrix2d> metric) {
  impl_->requirePieces("setMetric");
  impl_->factors = impl_->factorsOf(metric, "setMetric");
  impl_->metric = std::move(metric);
  impl_->stiffnessValues.resize(static_cast<size_t>(impl_->mass.nonZeros()));
  impl_->assemble(impl_->factors, nullptr, impl_->mass.valuePtr(), impl_->stiffnessValues.data());
  impl_->buildSeamContinuity();
}

MassStiffness TexelOperators::assembledFor(const std::vector<Eigen::Matrix2d>& metric) const {
  impl_->requirePieces("assembledFor");
  const std::vector<Impl::FaceFactors> faceFactors = impl_->factorsOf(metric, "assembledFor");
  MassStiffness out{impl_->mass, impl_->mass};  // the shared pattern; assemble overwrites values
  impl_->assemble(faceFactors, nullptr, out.mass.valuePtr(), out.stiffness.valuePtr());
  return out;
}

const std::vector<Eigen::Matrix2d>& TexelOperators::metric() const { return impl_->metric; }
const SparseMatrixd& TexelOperators::mass() const {
  impl_->requireAssembled("mass");
  return impl_->mass;
}
SparseViewd TexelOperators::stiffness() const {
  impl_->requireAssembled("stiffness");
  const SparseMatrixd& m = impl_->mass;
  return SparseViewd(m.rows(), m.cols(), m.nonZeros(), m.outerIndexPtr(), m.innerIndexPtr(),
                     impl_->stiffnessValues.data());
}
const SparseMatrixd& TexelOperators::seamContinuity() const {
  impl_->requireAssembled("seamContinuity");
  return impl_->continuityMatrix();
}
bool TexelOperators::assemblyDeferred() const { return impl_->deferred; }
const OperatorOptions& TexelOperators::options() const { return impl_->options; }
const fem::TexelBasis& TexelOperators::basis() const { return impl_->basis; }
const OperatorReport& TexelOperators::report() const { return impl_->report; }

int64_t TexelOperators::storageBytes() const {
  const Impl& m = *impl_;
  return sparseStorageBytes(m.mass) + sparseStorageBytes(m.seamContinuity) +
         sparseStorageBytes(m.zeroContinuity) +
         capacityBytes(m.stiffnessValues, m.seamValues, m.plain.fullBandBegin,
                       m.plain.partialBandBegin, m.seamTexels, m.metric, m.factors, m.plain.full,
                       m.plain.partial, m.seam) +
         capacityBytes(m.stream.windowBand, m.stream.faces, m.stream.seamFaces,
                       m.stream.seamColumns, m.stream.faceBegin);
}

namespace {

/// values[k] = alpha values[k] + stiffness[k] over a pattern M and S share: alpha M + S formed
/// in M's values.
void screenValues(double alpha, const double* stiffness, double* values, Eigen::Index count) {
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, count, 1 << 16),
                    [&](const tbb::blocked_range<Eigen::Index>& r) {
                      for (Eigen::Index k = r.begin(); k != r.end(); ++k)
                        values[k] = alpha * values[k] + stiffness[k];
                    });
}

/// values[k] = combine(row, column, values[k], stiffness[k]) over `pattern`'s entries.
void combineValues(const SparseMatrixd& pattern, const double* stiffness,
                   const EntryCombination& combine, double* values) {
  const int* outer = pattern.outerIndexPtr();
  const int* inner = pattern.innerIndexPtr();
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, pattern.outerSize(), 4096),
                    [&](const tbb::blocked_range<Eigen::Index>& r) {
                      for (Eigen::Index c = r.begin(); c != r.end(); ++c)
                        for (int k = outer[c]; k < outer[c + 1]; ++k)
                          values[k] = combine(inner[k], c, values[k], stiffness[k]);
                    });
}

}  // namespace

SparseMatrixd TexelOperators::combined(const EntryCombination& combine) const {
  impl_->requireAssembled("combined");
  SparseMatrixd out = impl_->mass;
  combineValues(out, impl_->stiffnessValues.data(), combine, out.valuePtr());
  return out;
}

SparseMatrixd TexelOperators::combined(std::unique_ptr<TexelOperators> operators,
                                       const EntryCombination& combine) {
  if (!operators) throw InvalidInputError("combined: no operators were handed over");
  operators->impl_->requireAssembled("combined");
  SparseMatrixd out;
  out.swap(operators->impl_->mass);  // as in screenedSystem: M's arrays become the result's
  combineValues(out, operators->impl_->stiffnessValues.data(), combine, out.valuePtr());
  return out;
}

void TexelOperators::addSeamScreening(double alpha, SparseMatrixd& system) const {
  if (impl_->options.seamContinuityWeight != 0.0)
    system += (alpha * impl_->options.seamContinuityWeight) * impl_->seamContinuity;
}

SparseMatrixd TexelOperators::screenedSystem(double alpha) const {
  impl_->requireAssembled("screenedSystem");
  // M and S share one pattern: copy M's and combine the values (no sparse merge).
  SparseMatrixd system = impl_->mass;
  screenValues(alpha, impl_->stiffnessValues.data(), system.valuePtr(), system.nonZeros());
  addSeamScreening(alpha, system);
  return system;
}

SparseMatrixd TexelOperators::screenedSystem(std::unique_ptr<TexelOperators> operators,
                                             double alpha) {
  if (!operators) throw InvalidInputError("screenedSystem: no operators were handed over");
  operators->impl_->requireAssembled("screenedSystem");
  // M's own arrays become A's (a swap: Eigen 3.4's move assignment of a SparseMatrix copies).
  SparseMatrixd system;
  system.swap(operators->impl_->mass);
  screenValues(alpha, operators->impl_->stiffnessValues.data(), system.valuePtr(),
               system.nonZeros());
  operators->addSeamScreening(alpha, system);
  return system;
}

SparseMatrixd TexelOperators::screenedSystem(std::unique_ptr<TexelOperators> operators,
                                             double alpha, const ColumnVisitor& visit,
                                             const ProgressCallback& progress) {
  if (!operators) throw InvalidInputError("screenedSystem: no operators were handed over");
  Impl& impl = *operators->impl_;
  if (impl.deferred) {
    impl.assembleScreened(alpha, visit, progress);  // M's values become alpha M + S there
  } else {
    // Assembled already: each column shown as it is, then combined as screenedSystem does.
    const SparseMatrixd& m = impl.mass;
    const int* outer = m.outerIndexPtr();
    if (visit)
      tbb::parallel_for(tbb::blocked_range<int>(0, static_cast<int>(m.outerSize()), 1024),
                        [&](const tbb::blocked_range<int>& columns) {
                          for (int u = columns.begin(); u != columns.end(); ++u) {
                            const auto length = static_cast<size_t>(outer[u + 1] - outer[u]);
                            visit(OperatorColumn{
                                u, std::span<const int>(m.innerIndexPtr() + outer[u], length),
                                std::span<const double>(m.valuePtr() + outer[u], length),
                                std::span<const double>(impl.stiffnessValues.data() + outer[u],
                                                        length)});
                          }
                        });
    screenValues(alpha, impl.stiffnessValues.data(), impl.mass.valuePtr(), m.nonZeros());
  }
  SparseMatrixd system;
  system.swap(impl.mass);  // M's arrays, now alpha M + S, become A's
  operators->addSeamScreening(alpha, system);
  return system;
}

FloatSystem TexelOperators::screenedSystemInFloat(std::unique_ptr<TexelOperators> operators,
                                                  double alpha, const ColumnVisitor& visit,
                                                  const ProgressCallback& progress) {
  if (!operators) throw InvalidInputError("screenedSystemInFloat: no operators were handed over");
  Impl& impl = *operators->impl_;
  if (impl.options.seamContinuityWeight != 0.0)
    throw InvalidInputError(
        "screenedSystemInFloat: the operators have a seam-continuity weight, whose C may add "
        "entries to the pattern; use screenedSystem");
  if (!impl.deferred) {  // assembled already: A in double first (M's storage), then rounded
    std::vector<uint8_t> exact = impl.exactUnknowns();
    return roundedSystem(screenedSystem(std::move(operators), alpha, visit, progress), exact);
  }
  FloatSystem out;
  impl.assembleScreened(alpha, visit, progress, &out);
  // M's index arrays become the system's (a swap keeps them where they are); its values were
  // never used.
  auto pattern = std::make_shared<SparseMatrixd>();
  pattern->swap(impl.mass);
  out.keepPatternAlive(std::move(pattern));
  return out;
}

FloatSystem roundedSystem(SparseMatrixd&& a, std::span<const uint8_t> exactUnknown) {
  if (!a.isCompressed() || a.rows() != a.cols())
    throw InvalidInputError("roundedSystem: the matrix must be square and compressed");
  if (exactUnknown.size() != static_cast<size_t>(a.rows()))  // before a is taken over
    throw InvalidInputError("roundedSystem: " + std::to_string(exactUnknown.size()) +
                            " exact-unknown flags for a matrix of " + std::to_string(a.rows()) +
                            " rows");
  auto pattern = std::make_shared<SparseMatrixd>();
  pattern->swap(a);
  const auto n = static_cast<int>(pattern->rows());
  const int* outer = pattern->outerIndexPtr();
  const double* values = pattern->valuePtr();
  FloatSystem out(n, pattern->outerIndexPtr(), pattern->innerIndexPtr(), exactUnknown);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int u = r.begin(); u != r.end(); ++u)
      out.setColumn(u, std::span<const double>(values + outer[u],
                                               static_cast<size_t>(outer[u + 1] - outer[u])));
  });
  detail::discardWholePages(pattern->valuePtr(),
                            static_cast<size_t>(pattern->nonZeros()) * sizeof(double));
  out.keepPatternAlive(std::move(pattern));
  return out;
}

std::vector<uint8_t> TexelOperators::Impl::exactUnknowns() const {
  const TexelGrid& grid = basis.grid();
  if (grid.texelClass.empty())
    throw InvalidInputError(
        "exactUnknowns: the grid's texel classes were freed (TexelDomain::releaseImageMaps); "
        "free them after it");
  const int* outer = mass.outerIndexPtr();
  const int* inner = mass.innerIndexPtr();
  std::vector<uint8_t> exact(static_cast<size_t>(grid.unknownCount()), 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.unknownCount(), 4096),
                    [&](const tbb::blocked_range<int>& r) {
    for (int u = r.begin(); u != r.end(); ++u) {
      const int32_t t = grid.texelOfUnknown[static_cast<size_t>(u)];
      bool irregular = grid.texelClass[static_cast<size_t>(t)] != TexelClass::Interior;
      // A seam piece's entries may reach beyond the 3 x 3 lattice neighbours.
      for (int e = outer[u]; e < outer[u + 1] && !irregular; ++e) {
        const int32_t other = grid.texelOfUnknown[static_cast<size_t>(inner[e])];
        irregular = std::abs(other % grid.nx - t % grid.nx) > 1 ||
                    std::abs(other / grid.nx - t / grid.nx) > 1;
      }
      exact[static_cast<size_t>(u)] = irregular ? 1 : 0;
    }
  });
  return exact;
}

std::vector<uint8_t> TexelOperators::exactUnknowns() const {
  return impl_->exactUnknowns();
}

SparseMatrixd screenedSystem(MassStiffness&& matrices, double alpha) {
  SparseMatrixd& m = matrices.mass;
  const SparseMatrixd& s = matrices.stiffness;
  const bool samePattern =
      m.isCompressed() && s.isCompressed() && m.rows() == s.rows() && m.cols() == s.cols() &&
      m.nonZeros() == s.nonZeros() &&
      std::equal(m.outerIndexPtr(), m.outerIndexPtr() + m.outerSize() + 1, s.outerIndexPtr()) &&
      std::equal(m.innerIndexPtr(), m.innerIndexPtr() + m.nonZeros(), s.innerIndexPtr());
  if (!samePattern)
    throw InvalidInputError("screenedSystem: M and S do not share one sparsity pattern");
  SparseMatrixd system;
  system.swap(m);  // M's arrays become A's (Eigen 3.4's move assignment copies)
  screenValues(alpha, s.valuePtr(), system.valuePtr(), system.nonZeros());
  SparseMatrixd().swap(matrices.stiffness);  // frees S's arrays now
  return system;
}

SparseMatrixd TexelOperators::modulatedStiffness(std::span<const double> betaPerCell) const {
  const TexelGrid& grid = impl_->basis.grid();
  if (betaPerCell.size() != static_cast<size_t>(grid.nx + 1) * (grid.ny + 1))
    throw InvalidInputError("modulatedStiffness: expected one beta per grid cell");
  impl_->requirePieces("modulatedStiffness");
  SparseMatrixd s = impl_->mass;  // the shared pattern; assemble overwrites the values
  impl_->assemble(impl_->factors, betaPerCell.data(), nullptr, s.valuePtr());
  return s;
}

std::vector<std::pair<int32_t, int32_t>> TexelOperators::texelPairs() const {
  std::vector<std::pair<int32_t, int32_t>> pairs;
  const SparseMatrixd& p = impl_->mass;
  for (int s = 0; s < p.outerSize(); ++s)
    for (int k = p.outerIndexPtr()[s]; k < p.outerIndexPtr()[s + 1]; ++k)
      if (p.innerIndexPtr()[k] > s) pairs.emplace_back(s, p.innerIndexPtr()[k]);
  return pairs;
}

SparseMatrixd TexelOperators::differential() const {
  const auto pairs = texelPairs();
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(2 * pairs.size());
  for (size_t a = 0; a < pairs.size(); ++a) {
    triplets.emplace_back(static_cast<int>(a), pairs[a].first, -1.0);
    triplets.emplace_back(static_cast<int>(a), pairs[a].second, 1.0);
  }
  SparseMatrixd d(static_cast<Eigen::Index>(pairs.size()), impl_->mass.rows());
  d.setFromTriplets(triplets.begin(), triplets.end());
  return d;
}

MassStiffness buildMassStiffness(const TexturedMesh& mesh, const Atlas& atlas,
                                 const TexelGrid& grid, const OperatorOptions& options) {
  TexelOperators ops(mesh, atlas, grid, options);
  return {ops.mass(), SparseMatrixd(ops.stiffness())};
}

}  // namespace texgrad
