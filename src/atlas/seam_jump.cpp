// Seam jump diagnostic: bilinear lookups on both sides of every seam pair, compared.
#include "texgrad/atlas/seam_jump.h"

#include <algorithm>
#include <cmath>

#include "texgrad/core/error.h"
#include "texgrad/io/image_sampling.h"

namespace texgrad {
namespace {

constexpr int kMinSamplesPerEdge = 2;

struct EdgeUv {
  Eigen::Vector2d start, end;
};

EdgeUv edgeUv(const TexturedMesh& mesh, const FaceEdge& e) {
  const Triangle& uv = mesh.uvTriangles[static_cast<size_t>(e.face)];
  return {mesh.uvs[static_cast<size_t>(uv[static_cast<size_t>(e.corner)])],
          mesh.uvs[static_cast<size_t>(uv[static_cast<size_t>((e.corner + 1) % 3)])]};
}

double edgeLength3d(const TexturedMesh& mesh, const FaceEdge& e) {
  const Triangle& t = mesh.triangles[static_cast<size_t>(e.face)];
  return (mesh.positions[static_cast<size_t>(t[static_cast<size_t>(e.corner)])] -
          mesh.positions[static_cast<size_t>(t[static_cast<size_t>((e.corner + 1) % 3)])])
      .norm();
}

double texelLength(const EdgeUv& e, const Image& image) {
  const Eigen::Vector2d d = e.end - e.start;
  return std::hypot(d.x() * image.width, d.y() * image.height);
}

}  // namespace

void SeamJumpOptions::validate() const {
  if (!(samplesPerTexel > 0.0) || !std::isfinite(samplesPerTexel))
    throw InvalidInputError("seam jump samplesPerTexel must be a positive number");
}

SeamJump measureSeamJump(const TexturedMesh& mesh, const Atlas& atlas, const Image& texture,
                         const SeamJumpOptions& options) {
  options.validate();
  if (texture.empty()) throw InvalidInputError("seam jump needs a non-empty texture");
  const auto channels = static_cast<size_t>(texture.channels);
  std::vector<double> sumSq(channels, 0.0);
  SeamJump result;
  double weightSum = 0.0;
  for (const SeamPair& seam : atlas.seams) {
    const EdgeUv a = edgeUv(mesh, seam.a), b = edgeUv(mesh, seam.b);
    const double length = edgeLength3d(mesh, seam.a);
    const double texels = std::max(texelLength(a, texture), texelLength(b, texture));
    const int n = std::max(kMinSamplesPerEdge,
                           static_cast<int>(std::ceil(texels * options.samplesPerTexel)));
    const double weight = length / n;
    for (int k = 0; k < n; ++k) {
      const double s = (k + 0.5) / n;
      const double sb = seam.sameDirection ? s : 1.0 - s;
      const Eigen::Vector2d pa = a.start + s * (a.end - a.start);
      const Eigen::Vector2d pb = b.start + sb * (b.end - b.start);
      for (size_t c = 0; c < channels; ++c) {
        const double diff = sampleBilinear(texture, pa, static_cast<int>(c)) -
                            sampleBilinear(texture, pb, static_cast<int>(c));
        sumSq[c] += weight * diff * diff;
        result.maxAbs = std::max(result.maxAbs, std::abs(diff));
      }
      weightSum += weight;
      ++result.samples;
    }
    result.seamLength3d += length;
  }
  result.rmsPerChannel.assign(channels, 0.0);
  if (weightSum <= 0.0) return result;
  double total = 0.0;
  for (size_t c = 0; c < channels; ++c) {
    result.rmsPerChannel[c] = std::sqrt(sumSq[c] / weightSum);
    total += sumSq[c];
  }
  result.rms = std::sqrt(total / (weightSum * static_cast<double>(channels)));
  return result;
}

}  // namespace texgrad
