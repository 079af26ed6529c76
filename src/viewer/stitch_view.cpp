// Viewer module: the stitch app (`texgrad stitch`, paper §7.2) in the viewer: the page first shows
// the composite, then the stitched result (one stitchComposite solve); a toggle switches between
// them, and a brush paints a lock mask (locked texels keep the composite value exactly) and
// re-solves. Frames carry the lock mask in alpha so the page can tint locked texels. The solving is stitchComposite's; this file only keeps the lock mask.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <variant>

#include "app_views.h"
#include "texgrad/apps/stitch.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"

namespace texgrad::viewer {
namespace {

/// Twice the signed UV area (in texels²) below which a triangle is skipped (no texel inside).
constexpr double kDegenerateUvArea = 1e-14;
/// V-cycles per solve (as `texgrad stitch` by default).
constexpr int kStitchCycles = 10;

/// 3-D position of every active texel inside the image, so a lock dab reaches every texel within
/// a 3-D radius, across seams. Texels outside every UV triangle (boundary texels) take the
/// nearest point of the triangle that needs the least clamping.
class TexelLocator {
 public:
  TexelLocator(const TexturedMesh& mesh, const TexelGrid& grid) {
    Eigen::AlignedBox3d box;
    for (const auto& p : mesh.positions) box.extend(p);
    if (!box.isEmpty()) diagonal_ = std::max(box.diagonal().norm(), 1e-12);
    const size_t count = static_cast<size_t>(grid.nx) * static_cast<size_t>(grid.ny);
    std::vector<float> misfit(count, std::numeric_limits<float>::infinity());
    std::vector<Eigen::Vector3f> position(count, Eigen::Vector3f::Zero());
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
      std::array<Eigen::Vector2d, 3> g;
      for (int k = 0; k < 3; ++k) g[k] = grid.toGrid(mesh.uvs[mesh.uvTriangles[f][k]]);
      const double area2 =
          (g[1] - g[0]).x() * (g[2] - g[0]).y() - (g[1] - g[0]).y() * (g[2] - g[0]).x();
      if (std::abs(area2) < kDegenerateUvArea) continue;
      const auto [minX, maxX] = std::minmax({g[0].x(), g[1].x(), g[2].x()});
      const auto [minY, maxY] = std::minmax({g[0].y(), g[1].y(), g[2].y()});
      const int x0 = std::max(0, static_cast<int>(std::floor(minX - 1.0)));
      const int x1 = std::min(grid.nx - 1, static_cast<int>(std::ceil(maxX + 1.0)));
      const int y0 = std::max(0, static_cast<int>(std::floor(minY - 1.0)));
      const int y1 = std::min(grid.ny - 1, static_cast<int>(std::ceil(maxY + 1.0)));
      const auto& tri = mesh.triangles[f];
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const int t = grid.texelIndex(x, y);
          if (grid.unknownOfTexel[t] < 0 || !grid.inImage(x, y)) continue;
          const Eigen::Vector2d p(x, y);
          const auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
            return u.x() * v.y() - u.y() * v.x();
          };
          const double l0 = cross(g[1] - p, g[2] - p) / area2;
          const double l1 = cross(g[2] - p, g[0] - p) / area2;
          Eigen::Vector3d l(l0, l1, 1.0 - l0 - l1);
          const double outside = -std::min({l.x(), l.y(), l.z(), 0.0});
          if (outside > 1.0 || static_cast<float>(outside) >= misfit[t]) continue;
          l = l.cwiseMax(0.0);
          l /= l.sum();
          misfit[t] = static_cast<float>(outside);
          position[t] = (l.x() * mesh.positions[tri[0]] + l.y() * mesh.positions[tri[1]] +
                         l.z() * mesh.positions[tri[2]])
                            .cast<float>();
        }
    }
    for (int y = 0; y < grid.ny; ++y)
      for (int x = 0; x < grid.nx; ++x) {
        const int t = grid.texelIndex(x, y);
        if (!std::isfinite(misfit[t])) continue;
        pixels_.push_back({x + grid.x0, y + grid.y0});
        positions_.push_back(position[t]);
      }
  }

  /// Calls f(image x, image y) for every located texel within `radius` of `centre`.
  template <typename F>
  int within(const Eigen::Vector3d& centre, double radius, F&& f) const {
    const Eigen::Vector3f c = centre.cast<float>();
    const float r2 = static_cast<float>(radius * radius);
    int count = 0;
    for (size_t i = 0; i < positions_.size(); ++i)
      if ((positions_[i] - c).squaredNorm() < r2) {
        f(pixels_[i][0], pixels_[i][1]);
        ++count;
      }
    return count;
  }

  double diagonal() const { return diagonal_; }

 private:
  std::vector<std::array<int, 2>> pixels_;
  std::vector<Eigen::Vector3f> positions_;
  double diagonal_ = 1.0;
};

class StitchView final : public ViewerApp {
 public:
  StitchView(const TexelDomain& domain, const Image& composite, const ViewerAppOptions& options)
      : domain_(domain),
        composite_(composite),
        segments_(options.segments),
        locator_(domain.mesh(), domain.grid()),
        compositeTexels_(toRgba8(composite)),
        stitched_(composite) {
    if (segments_.empty())
      throw InvalidInputError("the stitch app needs a segment mask (--segments MASK)");
    if (segments_.width != composite.width || segments_.height != composite.height)
      throw InvalidInputError("the segment mask is " + std::to_string(segments_.width) + "x" +
                              std::to_string(segments_.height) + " but the composite is " +
                              std::to_string(composite.width) + "x" +
                              std::to_string(composite.height) + "; they must match");
    stitch_.alpha = options.stitchAlpha;
    stitch_.compensateGains = options.compensateGains;
    stitch_.solver.cycles = kStitchCycles;
    stitch_.lock = Image(composite.width, composite.height, 1, PixelFormat::Float);
    stitch_.validate();
  }

  std::string name() const override { return "stitch"; }

  void apply(const ClientMessage& message) override {
    if (const auto* show = std::get_if<ShowTexture>(&message)) {
      showStitched_ = show->stitched;
    } else if (const auto* dab = std::get_if<BrushDab>(&message)) {
      if (dab->mode != BrushMode::Lock && dab->mode != BrushMode::Unlock)
        throw ProtocolError("the stitch brush paints lock or unlock");
      const float value = dab->mode == BrushMode::Lock ? 1.0f : 0.0f;
      int changed = 0;
      locator_.within(hitPosition(domain_.mesh(), dab->at), dab->radius * locator_.diagonal(),
                      [&](int x, int y) {
                        float& texel = stitch_.lock.at(x, y, 0);
                        changed += texel != value;
                        texel = value;
                      });
      if (changed > 0) ++lockVersion_;
      showStitched_ = true;  // show what the lock does
    } else if (const auto* run = std::get_if<Run>(&message);
               run && run->action == RunAction::Reset) {
      std::fill(stitch_.lock.pixels.begin(), stitch_.lock.pixels.end(), 0.0f);
      ++lockVersion_;
      showStitched_ = true;
    } else {
      throw ProtocolError("the stitch app takes show, brush (lock, unlock) and run messages");
    }
  }

  StepResult step() override {
    // A toggle (or Start / Step without a change) only re-publishes: the solve is one-shot per
    // lock mask.
    if (solvedVersion_ != lockVersion_) {
      const StitchResult result = stitchComposite(domain_, composite_, segments_, stitch_);
      stitched_ = result.image;
      stitchedTexels_ = toRgba8(stitched_);
      solvedLock_ = stitch_.lock;
      residual_ = result.report.residuals.empty() ? 0.0 : result.report.residuals.back();
      solvedVersion_ = lockVersion_;
      if (!solvedOnce_) showStitched_ = true;  // composite first, then the stitched result
      solvedOnce_ = true;
    }
    StepResult result;
    result.residual = residual_;
    result.settled = true;
    return result;
  }

  void frame(FrameHeader& header, std::vector<uint8_t>& texels) const override {
    const bool stitched = showStitched_ && solvedOnce_;
    header.format = FrameFormat::Rgba8;
    header.width = static_cast<uint32_t>(composite_.width);
    header.height = static_cast<uint32_t>(composite_.height);
    header.scale = 1.0f;
    texels = stitched ? stitchedTexels_ : compositeTexels_;
    // Alpha carries the lock mask for the page (0 = locked, 255 = free) as of the last solve;
    // the colour bytes are the texture's.
    const std::vector<float>& lock = solvedLock_.pixels;
    for (size_t i = 0; i < lock.size() && 4 * i + 3 < texels.size(); ++i)
      texels[4 * i + 3] = lock[i] > 0.5f ? 0 : 255;
  }

  std::vector<double> probe(const std::vector<SurfaceHit>& points) const override {
    const Image& image = showStitched_ && solvedOnce_ ? stitched_ : composite_;
    std::vector<double> values;
    const int channels = std::min(image.channels, 3);
    for (const SurfaceHit& hit : points) {
      double sum = 0.0;
      for (int c = 0; c < channels; ++c) sum += sampleActive(domain_, image, hit, c);
      values.push_back(sum / channels);
    }
    return values;
  }

  /// The stitched result (the composite before the first solve).
  void save(const std::filesystem::path& path) const override { writeImage(path, stitched_); }

 private:
  const TexelDomain& domain_;
  Image composite_, segments_;
  TexelLocator locator_;
  StitchOptions stitch_;
  std::vector<uint8_t> compositeTexels_, stitchedTexels_;
  Image solvedLock_;  ///< lock mask of the last solve (shown in the frames' alpha)
  Image stitched_;
  double residual_ = 0.0;
  uint64_t lockVersion_ = 1, solvedVersion_ = 0;
  bool solvedOnce_ = false;
  bool showStitched_ = false;
};

}  // namespace

std::unique_ptr<ViewerApp> makeStitchView(const TexelDomain& domain, const Image& composite,
                                          const ViewerAppOptions& options) {
  return std::make_unique<StitchView>(domain, composite, options);
}

}  // namespace texgrad::viewer
