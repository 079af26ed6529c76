// Viewer module: what the server needs from an interactive app (filter, geodesic): apply a page
// message, refine by one solver step, and hand out the current texture as a frame.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/image.h"
#include "texgrad/viewer/protocol.h"

namespace texgrad::viewer {

/// Apps the viewer can drive.
enum class ViewerAppKind { Filter, Geodesic, React, Lic, Stitch };
/// Parses "filter", "geodesic", "react", "lic" or "stitch"; throws InvalidInputError otherwise
/// (naming the others).
ViewerAppKind parseViewerAppKind(const std::string& text);
/// Name accepted by parseViewerAppKind.
std::string toString(ViewerAppKind kind);

/// Outcome of one refinement step.
struct StepResult {
  double residual = 0.0;  ///< relative residual after the step (0 for exact solves)
  bool settled = false;   ///< nothing left to refine until the next change
};

/// One interactive app on a TexelDomain (filter, geodesic: refine towards a target after each
/// change; react: a time stepper; lic, stitch: one full solve per change). Not thread-safe: the
/// session calls it from its worker.
class ViewerApp {
 public:
  virtual ~ViewerApp() = default;
  /// "filter", "geodesic", "react", "lic" or "stitch".
  virtual std::string name() const = 0;
  /// Applies a state-changing message (source, parameters, brush, reset); throws ProtocolError
  /// for a message this app does not take.
  virtual void apply(const ClientMessage& message) = 0;
  /// One V-cycle (or exact solve) towards the current target.
  virtual StepResult step() = 0;
  /// Current texture as a frame (header fields format, width, height, scale; texels).
  virtual void frame(FrameHeader& header, std::vector<uint8_t>& texels) const = 0;
  /// The app's scalar at surface points (geodesic: distance; filter: luminance in [0, 1]).
  virtual std::vector<double> probe(const std::vector<SurfaceHit>& points) const = 0;
  /// Writes the current result (texture, or distances) in any image format writeImage knows.
  virtual void save(const std::filesystem::path& path) const = 0;
};

/// Options of the apps as the viewer runs them.
struct ViewerAppOptions {
  double alpha = 1e4;  ///< filter screening weight (paper §7.1 default on the unit-area surface)
  double beta = 1.0;   ///< filter global gradient scale
  /// Gradient scale a sharpen brush paints towards (a smooth brush paints towards 0).
  double sharpenBeta = 3.0;
  /// Geodesic screening weight of the diffusion step (heat time 1 / alpha on the unit-area
  /// surface, paper §7.3); GeodesicOptions::alpha.
  double geodesicAlpha = 1e3;
  /// Reaction-diffusion preset (parseReactionPreset: "stripes" or "dots").
  std::string reactPreset = "stripes";
  /// Seed of the reaction-diffusion spots (reset reseeds with it).
  uint64_t seed = 1;
  /// Stitch: source mask of the composite (one colour per source, black = none; the texture's
  /// size). The composite itself is the app's texture.
  Image segments;
  /// Stitch: screening weight (StitchOptions::alpha, paper default 1e2).
  double stitchAlpha = 1e2;
  /// Stitch: divide out one gain per source and colour channel (StitchOptions::compensateGains).
  bool compensateGains = true;
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// Creates an app on `domain` (which must outlive it) for `texture` (filter input; stitch: the
/// composite, with options.segments; the other apps only need its size). No app changes the
/// domain.
std::unique_ptr<ViewerApp> makeViewerApp(ViewerAppKind kind, const TexelDomain& domain,
                                         const Image& texture, const ViewerAppOptions& options);

/// Value of per-texel image `values` (channel `channel`) at a surface point: bilinear over the
/// active texels around it (inactive corners dropped, weights renormalised).
double sampleActive(const TexelDomain& domain, const Image& values, const SurfaceHit& at,
                    int channel = 0);

/// UV coordinates of a surface point.
Eigen::Vector2d hitUv(const TexturedMesh& mesh, const SurfaceHit& at);
/// 3-D position of a surface point.
Eigen::Vector3d hitPosition(const TexturedMesh& mesh, const SurfaceHit& at);

}  // namespace texgrad::viewer
