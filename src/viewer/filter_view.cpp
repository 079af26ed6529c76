// Viewer module: the filter app (paper §7.1) driven interactively: alpha/beta sliders and a brush
// that paints the per-cell gradient scale; InteractiveFilter does the solving.
#include <cmath>
#include <variant>

#include "app_views.h"
#include "texgrad/apps/filter.h"
#include "texgrad/io/image_io.h"
#include "texgrad/viewer/beta_brush.h"

namespace texgrad::viewer {
namespace {

/// RMS change per step (colour units in [0, 1]) below which the texture counts as settled: far
/// below one 8-bit quantisation step.
constexpr double kSettledChange = 1e-5;

class FilterView final : public ViewerApp {
 public:
  FilterView(const TexelDomain& domain, const Image& texture, const ViewerAppOptions& options)
      : domain_(domain),
        options_(options),
        alpha_(options.alpha),
        beta_(options.beta),
        brush_(domain.mesh(), domain.grid()),
        filter_(domain, texture, filterOptions(options)),
        image_(filter_.image()) {}

  std::string name() const override { return "filter"; }

  void apply(const ClientMessage& message) override {
    if (const auto* p = std::get_if<SetFilterParameters>(&message)) {
      alpha_ = p->alpha;
      beta_ = p->beta;
    } else if (const auto* dab = std::get_if<BrushDab>(&message)) {
      if (dab->mode == BrushMode::Lock || dab->mode == BrushMode::Unlock)
        throw ProtocolError("the filter brush paints smooth, sharpen or erase (lock is stitch's)");
      const double target = dab->mode == BrushMode::Smooth    ? 0.0
                            : dab->mode == BrushMode::Sharpen ? options_.sharpenBeta
                                                              : 1.0;
      brush_.paint(hitPosition(domain_.mesh(), dab->at), dab->radius * brush_.diagonal(),
                   dab->strength, target);
    } else if (const auto* run = std::get_if<Run>(&message);
               run && run->action == RunAction::Reset) {
      brush_.clear();
      alpha_ = options_.alpha;
      beta_ = options_.beta;
    } else {
      throw ProtocolError("the filter app does not take this message");
    }
    dirty_ = true;
  }

  StepResult step() override {
    if (dirty_) {
      if (brush_.untouched()) {
        filter_.setParameters(alpha_, beta_);
      } else {
        std::vector<double> betaPerCell = brush_.factors();
        for (double& b : betaPerCell) b *= beta_;
        filter_.setParameters(alpha_, beta_, std::move(betaPerCell));
      }
      dirty_ = false;
    }
    const SolveReport report = filter_.step();
    image_ = filter_.image();
    StepResult result;
    result.residual = report.residuals.empty() ? 0.0 : report.residuals.back();
    result.settled = report.rmsChange.empty() || report.rmsChange.back() < kSettledChange;
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
    std::vector<double> values;
    const int channels = std::min(image_.channels, 3);
    for (const SurfaceHit& hit : points) {
      double sum = 0.0;
      for (int c = 0; c < channels; ++c) sum += sampleActive(domain_, image_, hit, c);
      values.push_back(sum / channels);
    }
    return values;
  }

  void save(const std::filesystem::path& path) const override { writeImage(path, image_); }

 private:
  static FilterOptions filterOptions(const ViewerAppOptions& options) {
    FilterOptions f;
    f.alpha = options.alpha;
    f.beta = options.beta;
    f.solver.kind = SolverKind::Multigrid;  // one V-cycle per frame refines the shown texture
    return f;
  }

  const TexelDomain& domain_;
  ViewerAppOptions options_;
  double alpha_, beta_;
  bool dirty_ = false;
  BetaBrush brush_;
  InteractiveFilter filter_;
  Image image_;
};

}  // namespace

std::unique_ptr<ViewerApp> makeFilterView(const TexelDomain& domain, const Image& texture,
                                          const ViewerAppOptions& options) {
  return std::make_unique<FilterView>(domain, texture, options);
}

}  // namespace texgrad::viewer
