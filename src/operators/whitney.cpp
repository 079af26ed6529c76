// Quadrature-based operators that need basis values at points: the Whitney Hodge star *1
// (degree 6, paper Sec. 5.2) and the right-hand sides mass_h(psi), div_h(omega) (paper Sec. 5.3).
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>

#include "texel_operators_impl.h"

namespace texgrad {
namespace {

constexpr int kHodgeStarDegree = 6;  // omega_a . omega_b: cubic x cubic

/// Calls visit(buffer, face, point, weight, texels, values, gradients) at every quadrature point
/// of M on faces [first, last).
template <typename Buffer, typename Visit>
void sampleFaces(const fem::TexelBasis& basis, int first, int last, int degree, Buffer& buffer,
                 Visit& visit) {
  FaceClip clip;
  fem::PieceBasis pb;
  for (int f = first; f < last; ++f) {
    basis.clipFace(f, clip);
    for (const auto& piece : clip.pieces) {
      const auto poly = clip.polygon(piece);
      if (basis.isPlain(f, poly)) {
        const auto cell = basis.cellTexels(piece.cellX, piece.cellY);
        const std::vector<int32_t> texels(cell.begin(), cell.end());
        detail::PieceSampler::plain(
            poly, piece.cellX, piece.cellY, degree,
            [&](const Eigen::Vector2d& p, double w, const auto& v, const auto& g) {
              visit(buffer, f, p, w, texels, Eigen::VectorXd(v), Eigen::MatrixXd(g));
            });
      } else {
        basis.buildPieceBasis(f, poly, pb);
        detail::PieceSampler::quadratic(
            pb, degree,
            [&](const Eigen::Vector2d& p, double w, const Eigen::VectorXd& v,
                const Eigen::MatrixXd& g) { visit(buffer, f, p, w, pb.texels, v, g); });
      }
    }
  }
}

/// Calls visit(buffer, face, point, weight, texels, values, gradients) at every quadrature point
/// of M, face chunks in parallel; each chunk's results go to its own buffer (kept, in chunk
/// order).
template <typename Buffer, typename Visit>
std::vector<Buffer> sampleSurface(const fem::TexelBasis& basis, int grain, int degree,
                                  Visit&& visit) {
  const int faces = basis.faceCount();
  const int chunks = (faces + grain - 1) / grain;
  std::vector<Buffer> buffers(chunks);
  tbb::parallel_for(0, chunks, [&](int c) {
    sampleFaces(basis, c * grain, std::min(faces, (c + 1) * grain), degree, buffers[c], visit);
  });
  return buffers;
}

using Contributions = std::vector<std::pair<int32_t, double>>;

/// Sum of the (unknown, value) contributions visit emits at every quadrature point of M, over n
/// unknowns. Face chunks are sampled in parallel and added in chunk order, each chunk's buffer
/// freed once added: the same sums, in the same order, as keeping every buffer and adding them
/// afterwards, but only a few chunks' buffers are alive at once (all of them took ~1.4 kB per
/// active texel at degree 4, spot 2048²: docs/memory.md, Reaction-diffusion).
template <typename Visit>
Eigen::VectorXd sumOverSurface(const fem::TexelBasis& basis, int grain, int degree, int n,
                               Visit&& visit) {
  const int faces = basis.faceCount();
  const int chunks = (faces + grain - 1) / grain;
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
  int next = 0;
  const auto inFlight = static_cast<size_t>(2 * tbb::this_task_arena::max_concurrency());
  const auto chunkIndices = tbb::make_filter<void, int>(tbb::filter_mode::serial_in_order,
                                                        [&](tbb::flow_control& control) {
                                                          if (next == chunks) control.stop();
                                                          return next++;
                                                        });
  const auto sampleChunk =
      tbb::make_filter<int, Contributions>(tbb::filter_mode::parallel, [&](int c) {
        Contributions buffer;
        sampleFaces(basis, c * grain, std::min(faces, (c + 1) * grain), degree, buffer, visit);
        return buffer;
      });
  const auto addInOrder = tbb::make_filter<Contributions, void>(tbb::filter_mode::serial_in_order,
                                                                [&](const Contributions& buffer) {
                                                                  for (const auto& [u, v] : buffer)
                                                                    out[u] += v;
                                                                });
  tbb::parallel_pipeline(inFlight, chunkIndices & sampleChunk & addInOrder);
  return out;
}

/// Entries of *1 summed over the quadrature points of one piece at a time (its texels, hence its
/// forms, are the same at every point), so each piece adds (forms)^2 triplets, not that many per
/// point.
struct StarSums {
  /// One Whitney form omega_(s,t) of the piece: local texel indices i, j and its pair index.
  struct Form {
    int i, j, pair;
  };
  std::vector<Eigen::Triplet<double>> triplets;
  std::vector<int32_t> texels;  ///< of the piece being summed
  std::vector<Form> forms;
  std::vector<Eigen::Vector2d> values;  ///< omega_a at the current point
  Eigen::MatrixXd sums;                 ///< forms x forms

  /// Emits the current piece's sums and starts summing the piece with these texels.
  template <typename PairIndex>
  void start(const std::vector<int32_t>& pieceTexels, PairIndex&& pairIndex) {
    flush();
    texels = pieceTexels;
    for (size_t i = 0; i < texels.size(); ++i)
      for (size_t j = 0; j < texels.size(); ++j)
        if (texels[i] >= 0 && texels[j] >= 0 && texels[i] < texels[j])
          forms.push_back(
              {static_cast<int>(i), static_cast<int>(j), pairIndex(texels[i], texels[j])});
    values.resize(forms.size());
    const auto count = static_cast<Eigen::Index>(forms.size());
    sums = Eigen::MatrixXd::Zero(count, count);
  }

  /// Emits the current piece's sums.
  void flush() {
    for (size_t a = 0; a < forms.size(); ++a)
      for (size_t b = 0; b < forms.size(); ++b)
        triplets.emplace_back(forms[a].pair, forms[b].pair,
                              sums(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)));
    forms.clear();
  }
};

}  // namespace

Eigen::VectorXd TexelOperators::massOf(const SurfaceScalar& psi, int degree) const {
  const auto& factors = impl_->factors;
  return sumOverSurface(impl_->basis, impl_->options.facesPerTask, degree,
                        impl_->basis.grid().unknownCount(),
                        [&](Contributions& out, int f, const Eigen::Vector2d& p, double w,
                            const std::vector<int32_t>& texels, const Eigen::VectorXd& values,
                            const Eigen::MatrixXd&) {
                          const double value = w * factors[f].mass * psi({f, p});
                          for (size_t k = 0; k < texels.size(); ++k)
                            if (texels[k] >= 0 && values[k] != 0.0)
                              out.emplace_back(texels[k], value * values[k]);
                        });
}

Eigen::VectorXd TexelOperators::divergenceOf(const SurfaceOneForm& omega, int degree) const {
  const auto& factors = impl_->factors;
  return sumOverSurface(
      impl_->basis, impl_->options.facesPerTask, degree, impl_->basis.grid().unknownCount(),
      [&](Contributions& out, int f, const Eigen::Vector2d& p, double w,
          const std::vector<int32_t>& texels, const Eigen::VectorXd&, const Eigen::MatrixXd& g) {
        const auto& m = factors[f];
        const Eigen::Vector2d o = omega({f, p});
        const Eigen::Vector2d raised(m.xx * o.x() + m.xy * o.y(), m.xy * o.x() + m.yy * o.y());
        for (size_t k = 0; k < texels.size(); ++k)
          if (texels[k] >= 0) out.emplace_back(texels[k], w * g.row(k).dot(raised));
      });
}

SparseMatrixd TexelOperators::hodgeStar1() const {
  const auto pairs = texelPairs();
  auto pairIndex = [&](int32_t s, int32_t t) {
    const auto it = std::lower_bound(pairs.begin(), pairs.end(), std::make_pair(s, t));
    return static_cast<int>(it - pairs.begin());
  };
  const auto& factors = impl_->factors;
  auto buffers = sampleSurface<StarSums>(
      impl_->basis, impl_->options.facesPerTask, kHodgeStarDegree,
      [&](StarSums& out, int f, const Eigen::Vector2d&, double w,
          const std::vector<int32_t>& texels, const Eigen::VectorXd& v, const Eigen::MatrixXd& g) {
        if (texels != out.texels) out.start(texels, pairIndex);
        const auto& m = factors[f];
        const size_t count = out.forms.size();
        for (size_t a = 0; a < count; ++a) {  // omega_a at the point
          const auto [i, j, pair] = out.forms[a];
          out.values[a] = v[i] * g.row(j).transpose() - v[j] * g.row(i).transpose();
        }
        for (size_t a = 0; a < count; ++a) {
          const Eigen::Vector2d& wa = out.values[a];
          const Eigen::Vector2d raised(m.xx * wa.x() + m.xy * wa.y(),
                                       m.xy * wa.x() + m.yy * wa.y());
          for (size_t b = 0; b < count; ++b)
            out.sums(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) +=
                w * raised.dot(out.values[b]);
        }
      });
  std::vector<Eigen::Triplet<double>> all;
  for (auto& b : buffers) {
    b.flush();
    all.insert(all.end(), b.triplets.begin(), b.triplets.end());
  }
  const auto n = static_cast<Eigen::Index>(pairs.size());
  SparseMatrixd star(n, n);
  star.setFromTriplets(all.begin(), all.end());
  return star;
}

}  // namespace texgrad
