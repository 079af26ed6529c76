// Gutter padding: seam-aware first ring, then ring-by-ring averaging outward.
#include "texgrad/apps/dilate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "texgrad/core/error.h"
#include "texgrad/io/image_sampling.h"

namespace texgrad {
namespace {

/// Boundary edges are bucketed on a coarse grid of this many texels per bucket for nearest queries.
constexpr int kBucketTexels = 8;

struct BoundaryEdge {
  Eigen::Vector2d start, end, third;  // texel coordinates; `third` = opposite corner of the face
  int seam = -1;                      // index into atlas.seams or -1 (open boundary)
  bool isSideA = true;                // which side of the seam this edge is
};

Eigen::Vector2d toTexel(const Eigen::Vector2d& uv, const Image& image) {
  return {uv.x() * image.width - 0.5, uv.y() * image.height - 0.5};
}

BoundaryEdge makeEdge(const TexturedMesh& mesh, const FaceEdge& e, const Image& image) {
  const Triangle& uv = mesh.uvTriangles[static_cast<size_t>(e.face)];
  auto corner = [&](int k) {
    return toTexel(mesh.uvs[static_cast<size_t>(uv[static_cast<size_t>(k % 3)])], image);
  };
  return {corner(e.corner), corner(e.corner + 1), corner(e.corner + 2), -1, true};
}

class EdgeIndex {
 public:
  void add(const BoundaryEdge& e) {
    const Eigen::Vector2d lo = e.start.cwiseMin(e.end), hi = e.start.cwiseMax(e.end);
    for (int by = bucket(lo.y()); by <= bucket(hi.y()); ++by)
      for (int bx = bucket(lo.x()); bx <= bucket(hi.x()); ++bx)
        buckets_[key(bx, by)].push_back(static_cast<int>(edges_.size()));
    edges_.push_back(e);
  }
  /// Nearest edge to p among buckets within one ring; -1 if none.
  int nearest(const Eigen::Vector2d& p, double& param) const {
    int best = -1;
    double bestDist = std::numeric_limits<double>::infinity();
    for (int by = bucket(p.y()) - 1; by <= bucket(p.y()) + 1; ++by)
      for (int bx = bucket(p.x()) - 1; bx <= bucket(p.x()) + 1; ++bx) {
        auto it = buckets_.find(key(bx, by));
        if (it == buckets_.end()) continue;
        for (int id : it->second) {
          const BoundaryEdge& e = edges_[static_cast<size_t>(id)];
          const Eigen::Vector2d d = e.end - e.start;
          const double len2 = d.squaredNorm();
          const double s = len2 > 0 ? std::clamp((p - e.start).dot(d) / len2, 0.0, 1.0) : 0.0;
          const double dist = (e.start + s * d - p).squaredNorm();
          if (dist < bestDist) bestDist = dist, best = id, param = s;
        }
      }
    return best;
  }
  const BoundaryEdge& edge(int id) const { return edges_[static_cast<size_t>(id)]; }

 private:
  static int bucket(double x) { return static_cast<int>(std::floor(x / kBucketTexels)); }
  static int64_t key(int bx, int by) { return (static_cast<int64_t>(bx) << 32) ^ (by & 0xffffffffLL); }
  std::vector<BoundaryEdge> edges_;
  std::unordered_map<int64_t, std::vector<int>> buckets_;
};

/// Unit inward normal of an edge (towards its face's third corner).
Eigen::Vector2d inwardNormal(const BoundaryEdge& e) {
  const Eigen::Vector2d d = (e.end - e.start).normalized();
  Eigen::Vector2d n(-d.y(), d.x());
  if (n.dot(e.third - e.start) < 0) n = -n;
  return n;
}

/// Maps texel centre p, outside the chart of edge `self`, across the seam into the partner chart.
Eigen::Vector2d acrossSeam(const Eigen::Vector2d& p, const BoundaryEdge& self, double s,
                           const BoundaryEdge& partner, bool sameDirection) {
  const Eigen::Vector2d q = self.start + s * (self.end - self.start);
  const Eigen::Vector2d along = (self.end - self.start).normalized();
  const Eigen::Vector2d offset = p - q;
  const double a = offset.dot(along), outward = -offset.dot(inwardNormal(self));
  const double scale = (partner.end - partner.start).norm() / (self.end - self.start).norm();
  const double sp = sameDirection ? s : 1.0 - s;
  Eigen::Vector2d alongP = (partner.end - partner.start).normalized();
  if (!sameDirection) alongP = -alongP;
  const Eigen::Vector2d qp = partner.start + sp * (partner.end - partner.start);
  // A texel diagonal to a chart corner (nearest point = an edge end) would be carried past the
  // partner chart's corner; the corner itself is on the partner chart, so look up there.
  if (s <= 0.0 || s >= 1.0) return qp;
  return qp + scale * (a * alongP + outward * inwardNormal(partner));
}

}  // namespace

void DilateOptions::validate() const {
  if (!infinite && radius < 0) throw InvalidInputError("dilate radius must be >= 0");
}

namespace {

EdgeIndex buildEdgeIndex(const TexturedMesh& mesh, const Atlas& atlas, const Image& image,
                         std::vector<BoundaryEdge>& partnerOf) {
  EdgeIndex index;
  for (size_t s = 0; s < atlas.seams.size(); ++s) {
    BoundaryEdge a = makeEdge(mesh, atlas.seams[s].a, image);
    BoundaryEdge b = makeEdge(mesh, atlas.seams[s].b, image);
    a.seam = b.seam = static_cast<int>(s);
    b.isSideA = false;
    partnerOf.push_back(b);
    partnerOf.push_back(a);
    index.add(a);
    index.add(b);
  }
  for (const FaceEdge& e : atlas.openBoundary) index.add(makeEdge(mesh, e, image));
  return index;
}

/// Texel flags while dilating.
enum Fill : uint8_t { kEmpty = 0, kFilled = 1 };

/// Fills the texels of the first ring whose nearest chart edge is a seam with the value found across
/// the seam, marks them filled and returns the rest of the ring.
std::vector<size_t> fillAcrossSeams(const TexturedMesh& mesh, const Atlas& atlas,
                                    const Image& source, const std::vector<size_t>& ring,
                                    Image& out, std::vector<uint8_t>& state) {
  std::vector<BoundaryEdge> partnerOf;
  const EdgeIndex index = buildEdgeIndex(mesh, atlas, source, partnerOf);
  std::vector<size_t> rest;
  const size_t w = static_cast<size_t>(out.width);
  for (size_t t : ring) {
    const Eigen::Vector2d p(static_cast<double>(t % w), static_cast<double>(t / w));
    double s = 0.0;
    const int id = index.nearest(p, s);
    if (id < 0 || index.edge(id).seam < 0) {
      rest.push_back(t);
      continue;
    }
    const BoundaryEdge& self = index.edge(id);
    const size_t slot = 2 * static_cast<size_t>(self.seam) + (self.isSideA ? 0 : 1);
    const SeamPair& pair = atlas.seams[static_cast<size_t>(self.seam)];
    const Eigen::Vector2d target = acrossSeam(p, self, s, partnerOf[slot], pair.sameDirection);
    const int i = static_cast<int>(t % w), j = static_cast<int>(t / w);
    for (int c = 0; c < out.channels; ++c) out.at(i, j, c) = sampleBilinearTexel(source, target, c);
    state[t] = kFilled;
  }
  return rest;
}

/// Empty texels that touch (8-neighbourhood) a texel of `frontier`.
std::vector<size_t> nextRing(const Image& out, const std::vector<uint8_t>& state,
                             const std::vector<size_t>& frontier) {
  const int w = out.width, h = out.height;
  std::vector<uint8_t> queued(state.size(), 0);
  std::vector<size_t> ring;
  for (size_t t : frontier) {
    const int i = static_cast<int>(t % static_cast<size_t>(w));
    const int j = static_cast<int>(t / static_cast<size_t>(w));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = i + dx, y = j + dy;
        if (x < 0 || y < 0 || x >= w || y >= h) continue;
        const size_t n = static_cast<size_t>(y) * static_cast<size_t>(w) + x;
        if (state[n] == kEmpty && !queued[n]) queued[n] = 1, ring.push_back(n);
      }
  }
  std::sort(ring.begin(), ring.end());
  return ring;
}

/// Fills `ring` with the mean of filled 8-neighbours, then marks it filled.
void fillRing(Image& out, std::vector<uint8_t>& state, const std::vector<size_t>& ring) {
  const int w = out.width, h = out.height;
  for (size_t t : ring) {
    const int i = static_cast<int>(t % static_cast<size_t>(w));
    const int j = static_cast<int>(t / static_cast<size_t>(w));
    for (int c = 0; c < out.channels; ++c) {
      double sum = 0;
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = i + dx, y = j + dy;
          if (x < 0 || y < 0 || x >= w || y >= h) continue;
          if (state[static_cast<size_t>(y) * static_cast<size_t>(w) + x] != kFilled) continue;
          sum += out.at(x, y, c);
          ++n;
        }
      out.at(i, j, c) = static_cast<float>(sum / n);
    }
  }
  for (size_t t : ring) state[t] = kFilled;
}

}  // namespace

Image dilateGutters(const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& grid,
                    const Image& texture, const DilateOptions& options) {
  options.validate();
  if (grid.imageWidth != texture.width || grid.imageHeight != texture.height)
    throw InvalidInputError("dilate: texel grid is " + std::to_string(grid.imageWidth) + "x" +
                            std::to_string(grid.imageHeight) + " but the texture is " +
                            std::to_string(texture.width) + "x" + std::to_string(texture.height));
  Image out = texture;
  const size_t w = static_cast<size_t>(texture.width);
  std::vector<uint8_t> state(w * static_cast<size_t>(texture.height), kEmpty);
  std::vector<size_t> frontier;
  for (int y = 0; y < grid.ny; ++y)
    for (int x = 0; x < grid.nx; ++x)
      if (grid.inImage(x, y) &&
          grid.texelClass[static_cast<size_t>(grid.texelIndex(x, y))] != TexelClass::Inactive) {
        const size_t t = static_cast<size_t>(y + grid.y0) * w + static_cast<size_t>(x + grid.x0);
        state[t] = kFilled;
        frontier.push_back(t);
      }
  if (frontier.empty() || (!options.infinite && options.radius == 0)) return out;
  // Ring 1 takes values from across the seams where it can; every ring then averages.
  std::vector<size_t> ring = nextRing(out, state, frontier);
  const std::vector<size_t> rest = fillAcrossSeams(mesh, atlas, texture, ring, out, state);
  fillRing(out, state, rest);
  const int rings = options.infinite ? std::numeric_limits<int>::max() : options.radius;
  for (int r = 1; r < rings && !ring.empty(); ++r) {
    std::vector<size_t> next = nextRing(out, state, ring);
    fillRing(out, state, next);
    ring = std::move(next);
  }
  return out;
}

}  // namespace texgrad
