// Viewer module: the geodesic app (paper §7.3) driven interactively: a click sets the source, a
// shift-click adds one, and GeodesicSolver::update() refines u and the distance once per frame.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <variant>

#include "app_views.h"
#include "texgrad/apps/geodesic.h"
#include "texgrad/io/image_io.h"

namespace texgrad::viewer {
namespace {

/// Largest R16 code for a value; kNoValue marks texels without one.
constexpr uint16_t kMaxCode = 65534;
constexpr uint16_t kNoValue = 65535;
/// RMS change of the distance per step, relative to the largest distance, below which the
/// field counts as settled: one step of the 16-bit frame encoding, so further steps would not
/// change the picture. (Float updates keep moving by about that much: GeodesicSolver::update.)
constexpr double kSettledRelativeChange = 1.0 / kMaxCode;
/// Unknowns per task of the per-texel loops.
constexpr int kUnknownsPerTask = 1 << 14;
/// Most sources a page may place with shift-clicks.
constexpr size_t kMaxSources = 64;
/// Steps between residual measurements (each costs two products of the multigrid's level-0
/// operator per system; the page shows the residual a few times a second).
constexpr int kResidualEvery = 8;

class GeodesicView final : public ViewerApp {
 public:
  GeodesicView(const TexelDomain& domain, const Image& texture, const ViewerAppOptions& options)
      : domain_(domain),
        solver_(domain, geodesicOptions(options)),
        distances_(texture.width, texture.height, 1, PixelFormat::Float),
        pixelOfUnknown_(pixelsOfUnknowns(domain.grid(), texture.width)) {}

  std::string name() const override { return "geodesic"; }

  void apply(const ClientMessage& message) override {
    if (const auto* source = std::get_if<SetSource>(&message)) {
      std::vector<GeodesicSource> next = source->add ? sources_ : std::vector<GeodesicSource>{};
      if (next.size() >= kMaxSources)
        throw ProtocolError("at most " + std::to_string(kMaxSources) + " sources");
      next.push_back(GeodesicSource::atUv(hitUv(domain_.mesh(), source->at)));
      solver_.setSources(next);  // a refused source (outside the image) keeps the old ones
      sources_ = std::move(next);
    } else if (const auto* run = std::get_if<Run>(&message);
               run && run->action == RunAction::Reset) {
      if (!sources_.empty()) solver_.setSources(sources_);
    } else {
      throw ProtocolError("the geodesic app does not take this message");
    }
    stepsSinceResidual_ = 0;
  }

  StepResult step() override {
    StepResult result;
    if (sources_.empty()) {
      result.settled = true;
      return result;
    }
    solver_.update();
    if (stepsSinceResidual_++ % kResidualEvery == 0) residual_ = solver_.residual();
    result.residual = residual_;
    const Sums sums = updatePicture();
    maxDistance_ = sums.largest;
    const double change = std::sqrt(sums.squaredChange / static_cast<double>(sums.count));
    result.settled = change <= kSettledRelativeChange * std::max(maxDistance_, 1e-12);
    return result;
  }

  void frame(FrameHeader& header, std::vector<uint8_t>& texels) const override {
    const TexelGrid& grid = domain_.grid();
    header.format = FrameFormat::R16;
    header.width = static_cast<uint32_t>(distances_.width);
    header.height = static_cast<uint32_t>(distances_.height);
    header.scale = static_cast<float>(maxDistance_ > 0.0 ? maxDistance_ : 1.0);
    const size_t n = static_cast<size_t>(distances_.width) * distances_.height;
    texels.assign(2 * n, 0xFFu);  // kNoValue, little-endian
    const Eigen::VectorXd& d = solver_.distances();
    if (sources_.empty() || d.size() != grid.unknownCount()) return;
    const double toCode = kMaxCode / static_cast<double>(header.scale);
    tbb::parallel_for(tbb::blocked_range<int>(0, grid.unknownCount(), kUnknownsPerTask),
                      [&](const tbb::blocked_range<int>& range) {
                        for (int u = range.begin(); u != range.end(); ++u) {
                          const int32_t pixel = pixelOfUnknown_[u];
                          if (pixel < 0) continue;
                          if (!std::isfinite(d[u])) continue;  // unreachable: no value
                          // Rounded to nearest (the value is clamped to be >= 0 first).
                          const auto code = static_cast<uint16_t>(
                              std::clamp(d[u] * toCode, 0.0, double{kMaxCode}) + 0.5);
                          uint8_t* out = texels.data() + 2 * static_cast<size_t>(pixel);
                          out[0] = static_cast<uint8_t>(code & 0xFFu);
                          out[1] = static_cast<uint8_t>(code >> 8);
                        }
                      });
  }

  std::vector<double> probe(const std::vector<SurfaceHit>& points) const override {
    std::vector<double> values;
    for (const SurfaceHit& hit : points)
      values.push_back(sources_.empty() ? std::nan("") : sampleActive(domain_, distances_, hit));
    return values;
  }

  void save(const std::filesystem::path& path) const override { writeImage(path, distances_); }

 private:
  /// Over the unknowns: the largest finite distance, and the squared change of the picture's
  /// pixels (count of them), in one pass that also writes the new distances into the picture.
  struct Sums {
    double largest = 0.0, squaredChange = 0.0;
    int64_t count = 0;
  };

  Sums updatePicture() {
    const TexelGrid& grid = domain_.grid();
    const Eigen::VectorXd& d = solver_.distances();
    const Sums sums = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<int>(0, grid.unknownCount(), kUnknownsPerTask), Sums{},
        [&](const tbb::blocked_range<int>& range, Sums acc) {
          for (int u = range.begin(); u != range.end(); ++u) {
            if (std::isfinite(d[u])) acc.largest = std::max(acc.largest, d[u]);
            if (pixelOfUnknown_[u] < 0) continue;
            float& pixel = distances_.pixels[static_cast<size_t>(pixelOfUnknown_[u])];
            if (std::isfinite(d[u]) && std::isfinite(pixel)) {
              acc.squaredChange += (d[u] - pixel) * (d[u] - pixel);
              ++acc.count;
            }
            pixel = static_cast<float>(d[u]);
          }
          return acc;
        },
        [](const Sums& a, const Sums& b) {
          return Sums{std::max(a.largest, b.largest), a.squaredChange + b.squaredChange,
                      a.count + b.count};
        });
    return {sums.largest, sums.squaredChange, std::max<int64_t>(sums.count, 1)};
  }

  /// Per unknown: its pixel (row * width + column) in an image of `width` columns, or -1 if its
  /// texel lies outside the image. Saves the per-frame divisions by the grid width.
  static std::vector<int32_t> pixelsOfUnknowns(const TexelGrid& grid, int width) {
    std::vector<int32_t> pixels(static_cast<size_t>(grid.unknownCount()));
    for (int u = 0; u < grid.unknownCount(); ++u) {
      const int t = grid.texelOfUnknown[u];
      const int x = t % grid.nx, y = t / grid.nx;
      pixels[static_cast<size_t>(u)] =
          grid.inImage(x, y) ? (y + grid.y0) * width + (x + grid.x0) : -1;
    }
    return pixels;
  }

  static GeodesicOptions geodesicOptions(const ViewerAppOptions& options) {
    GeodesicOptions g = GeodesicOptions::interactive();
    g.alpha = options.geodesicAlpha;
    return g;
  }

  const TexelDomain& domain_;
  GeodesicSolver solver_;
  std::vector<GeodesicSource> sources_;
  Image distances_;  ///< distance per texel (model units), 0 where inactive
  std::vector<int32_t> pixelOfUnknown_;  ///< pixelsOfUnknowns of the grid and distances_
  double maxDistance_ = 0.0;
  double residual_ = 0.0;       ///< last measured (every kResidualEvery steps)
  int stepsSinceResidual_ = 0;  ///< since the last change of sources
};

}  // namespace

std::unique_ptr<ViewerApp> makeGeodesicView(const TexelDomain& domain, const Image& texture,
                                            const ViewerAppOptions& options) {
  return std::make_unique<GeodesicView>(domain, texture, options);
}

}  // namespace texgrad::viewer
