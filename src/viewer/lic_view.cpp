// Viewer module: the line integral convolution app (`texgrad lic`, paper §7.4) in the viewer: the
// page first shows the noise; Start or Step convolves it along the major principal curvature
// direction (LineIntegralConvolution, set up once); Reset draws new noise.
#include <algorithm>
#include <variant>

#include "app_views.h"
#include "texgrad/apps/lic.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/apps/vector_field.h"
#include "texgrad/io/image_io.h"

namespace texgrad::viewer {
namespace {

class LicView final : public ViewerApp {
 public:
  LicView(const TexelDomain& domain, const ViewerAppOptions& options)
      : domain_(domain),
        options_(licOptions(options)),
        seed_(options.seed),
        lic_(domain,
             fieldInTexelCoordinates(domain.mesh(), domain.grid(),
                                     curvatureField(domain.mesh(), CurvatureDirection::Major)),
             options_),
        area_(domain.operators().mass() * Eigen::VectorXd::Ones(domain.unknowns())),
        image_(domain.grid().imageWidth, domain.grid().imageHeight, 1, PixelFormat::Float) {
    showNoise();
  }

  std::string name() const override { return "lic"; }

  void apply(const ClientMessage& message) override {
    const auto* run = std::get_if<Run>(&message);
    if (!run || run->action != RunAction::Reset)
      throw ProtocolError("the lic app takes only run messages (start, pause, step, reset)");
    ++seed_;  // new noise, convolved on the next Start or Step
    showNoise();
  }

  StepResult step() override {
    LicReport report;
    const Eigen::MatrixXd values =
        lic_.convolve(licNoise(domain_.grid(), options_.channels, seed_), &report);
    scatterTexels(domain_.grid(), licContrast(values, area_, options_.contrast), image_);
    StepResult result;
    for (const SolveReport* r : {&report.diffusion, &report.sharpening})
      if (!r->residuals.empty()) result.residual = std::max(result.residual, r->residuals.back());
    result.settled = true;  // one convolution (both solves to tolerance) per step
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
    for (const SurfaceHit& hit : points) values.push_back(sampleActive(domain_, image_, hit));
    return values;
  }

  void save(const std::filesystem::path& path) const override { writeImage(path, image_); }

 private:
  static LicOptions licOptions(const ViewerAppOptions& options) {
    LicOptions l;
    l.seed = options.seed;
    l.validate();
    return l;
  }

  void showNoise() {
    scatterTexels(domain_.grid(), licNoise(domain_.grid(), options_.channels, seed_), image_);
  }

  const TexelDomain& domain_;
  LicOptions options_;
  uint64_t seed_;
  LineIntegralConvolution lic_;
  Eigen::VectorXd area_;  ///< surface area per unknown (M 1), weights of the contrast mapping
  Image image_;
};

}  // namespace

std::unique_ptr<ViewerApp> makeLicView(const TexelDomain& domain, const ViewerAppOptions& options) {
  return std::make_unique<LicView>(domain, options);
}

}  // namespace texgrad::viewer
