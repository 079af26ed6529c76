// Viewer module: the reaction-diffusion app (Gray-Scott, `texgrad react`) driven interactively:
// start / pause / step advance ReactionDiffusion one time step per frame; reset reseeds it.
#include <algorithm>
#include <cmath>
#include <variant>

#include "app_views.h"
#include "texgrad/apps/reaction_diffusion.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/io/image_io.h"

namespace texgrad::viewer {
namespace {

class ReactView final : public ViewerApp {
 public:
  ReactView(const TexelDomain& domain, const ViewerAppOptions& options)
      : domain_(domain), simulation_(domain, reactionOptions(options)), seed_(options.seed) {
    render();
  }

  std::string name() const override { return "react"; }

  void apply(const ClientMessage& message) override {
    const auto* run = std::get_if<Run>(&message);
    if (!run || run->action != RunAction::Reset)
      throw ProtocolError("the react app takes only run messages (start, pause, step, reset)");
    simulation_.reseed(seed_);
    render();
  }

  StepResult step() override {
    simulation_.step();
    render();
    StepResult result;
    for (int species = 0; species < 2; ++species) {
      const auto& residuals = simulation_.lastReport(species).residuals;
      if (!residuals.empty()) result.residual = std::max(result.residual, residuals.back());
    }
    result.settled = false;  // a time stepper: runs until paused or the iteration limit
    return result;
  }

  void frame(FrameHeader& header, std::vector<uint8_t>& texels) const override {
    header.format = FrameFormat::Rgba8;
    header.width = static_cast<uint32_t>(image_.width);
    header.height = static_cast<uint32_t>(image_.height);
    header.scale = 1.0f;
    texels = toRgba8(image_);
  }

  std::vector<double> probe(const std::vector<SurfaceHit>& points) const override {
    std::vector<double> values;  // concentration of u (1 = no pattern)
    for (const SurfaceHit& hit : points) values.push_back(sampleActive(domain_, uImage_, hit));
    return values;
  }

  void save(const std::filesystem::path& path) const override { writeImage(path, image_); }

 private:
  static ReactionDiffusionOptions reactionOptions(const ViewerAppOptions& options) {
    ReactionDiffusionOptions r;
    const GrayScottRates rates = presetRates(parseReactionPreset(options.reactPreset));
    r.feed = rates.feed;
    r.kill = rates.kill;
    r.seed = options.seed;
    return r;
  }

  void render() {
    image_ = reactionImage(domain_, simulation_.u());
    if (uImage_.width == 0) uImage_ = Image(image_.width, image_.height, 1, PixelFormat::Float);
    scatterTexels(domain_.grid(), simulation_.u(), uImage_);
  }

  const TexelDomain& domain_;
  ReactionDiffusion simulation_;
  uint64_t seed_;
  Image image_;   ///< reactionImage of the current state (what the page shows)
  Image uImage_;  ///< u per texel (probes)
};

}  // namespace

std::unique_ptr<ViewerApp> makeReactView(const TexelDomain& domain, const Image&,
                                         const ViewerAppOptions& options) {
  return std::make_unique<ReactView>(domain, options);
}

}  // namespace texgrad::viewer
