// Viewer module: the geodesic app (paper §7.3) driven interactively: a click sets the source, a
// shift-click adds one, and GeodesicSolver::update() refines u and the distance once per frame.
#include <algorithm>
#include <cmath>
#include <variant>

#include "app_views.h"
#include "texgrad/apps/geodesic.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/io/image_io.h"

namespace texgrad::viewer {
namespace {

/// Largest R16 code for a value; kNoValue marks texels without one.
constexpr uint16_t kMaxCode = 65534;
/// RMS change of the distance per step, relative to the largest distance, below which the
/// field counts as settled: one step of the 16-bit frame encoding, so further steps would not
/// change the picture. (Float updates keep moving by about that much: GeodesicSolver::update.)
constexpr double kSettledRelativeChange = 1.0 / kMaxCode;
constexpr uint16_t kNoValue = 65535;
/// Most sources a page may place with shift-clicks.
constexpr size_t kMaxSources = 64;
/// Steps between residual measurements (each costs a sparse product per system, a sixth of an
/// update; the page shows the residual a few times a second).
constexpr int kResidualEvery = 8;

class GeodesicView final : public ViewerApp {
 public:
  GeodesicView(const TexelDomain& domain, const Image& texture, const ViewerAppOptions& options)
      : domain_(domain),
        solver_(domain, geodesicOptions(options)),
        distances_(texture.width, texture.height, 1, PixelFormat::Float) {}

  std::string name() const override { return "geodesic"; }

  void apply(const ClientMessage& message) override {
    if (const auto* source = std::get_if<SetSource>(&message)) {
      if (!source->add) sources_.clear();
      if (sources_.size() >= kMaxSources)
        throw ProtocolError("at most " + std::to_string(kMaxSources) + " sources");
      sources_.push_back(GeodesicSource::atUv(hitUv(domain_.mesh(), source->at)));
      solver_.setSources(sources_);
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
    const Eigen::VectorXd previous = solver_.distances();
    solver_.update();
    const Eigen::VectorXd& d = solver_.distances();
    maxDistance_ = 0.0;  // over reachable texels (GeodesicSolver marks the others +inf)
    for (Eigen::Index u = 0; u < d.size(); ++u)
      if (std::isfinite(d[u])) maxDistance_ = std::max(maxDistance_, d[u]);
    scatterTexels(domain_.grid(), d, distances_);
    if (stepsSinceResidual_++ % kResidualEvery == 0) residual_ = solver_.residual();
    result.residual = residual_;
    double change = 1.0;
    if (previous.size() == d.size() && d.size() > 0) {
      double sum = 0.0;
      for (Eigen::Index u = 0; u < d.size(); ++u)
        if (std::isfinite(d[u]) && std::isfinite(previous[u]))
          sum += (d[u] - previous[u]) * (d[u] - previous[u]);
      change = std::sqrt(sum / static_cast<double>(d.size()));
    }
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
    for (int u = 0; u < grid.unknownCount(); ++u) {
      const int t = grid.texelOfUnknown[u];
      const int x = t % grid.nx, y = t / grid.nx;
      if (!grid.inImage(x, y)) continue;
      if (!std::isfinite(d[u])) continue;  // unreachable from every source: no value
      const auto code =
          static_cast<uint16_t>(std::lround(std::clamp(d[u] * toCode, 0.0, double{kMaxCode})));
      uint8_t* out = texels.data() + 2 * (static_cast<size_t>(y + grid.y0) * distances_.width +
                                          static_cast<size_t>(x + grid.x0));
      out[0] = static_cast<uint8_t>(code & 0xFFu);
      out[1] = static_cast<uint8_t>(code >> 8);
    }
  }

  std::vector<double> probe(const std::vector<SurfaceHit>& points) const override {
    std::vector<double> values;
    for (const SurfaceHit& hit : points)
      values.push_back(sources_.empty() ? std::nan("") : sampleActive(domain_, distances_, hit));
    return values;
  }

  void save(const std::filesystem::path& path) const override { writeImage(path, distances_); }

 private:
  static GeodesicOptions geodesicOptions(const ViewerAppOptions& options) {
    GeodesicOptions g;
    g.alpha = options.geodesicAlpha;
    return g;
  }

  const TexelDomain& domain_;
  GeodesicSolver solver_;
  std::vector<GeodesicSource> sources_;
  Image distances_;  ///< distance per texel (model units), 0 where inactive
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
