// Viewer module: app selection, surface-point lookups and texel conversions shared by the apps.
#include "texgrad/viewer/viewer_app.h"

#include <algorithm>
#include <cmath>

#include "app_views.h"
#include "texgrad/apps/reaction_diffusion.h"
#include "texgrad/core/error.h"

namespace texgrad::viewer {

ViewerAppKind parseViewerAppKind(const std::string& text) {
  if (text == "filter") return ViewerAppKind::Filter;
  if (text == "geodesic") return ViewerAppKind::Geodesic;
  if (text == "react") return ViewerAppKind::React;
  if (text == "lic") return ViewerAppKind::Lic;
  if (text == "stitch") return ViewerAppKind::Stitch;
  throw InvalidInputError("unknown viewer app \"" + text +
                          "\": use filter, geodesic, react, lic or stitch");
}

std::string toString(ViewerAppKind kind) {
  switch (kind) {
    case ViewerAppKind::Filter: return "filter";
    case ViewerAppKind::Geodesic: return "geodesic";
    case ViewerAppKind::React: return "react";
    case ViewerAppKind::Lic: return "lic";
    case ViewerAppKind::Stitch: return "stitch";
  }
  return "?";
}

void ViewerAppOptions::validate() const {
  if (!(alpha >= kMinAlpha && alpha <= kMaxAlpha))
    throw InvalidInputError("alpha must lie in [" + std::to_string(kMinAlpha) + ", " +
                            std::to_string(kMaxAlpha) + "]");
  if (!(beta >= 0.0 && beta <= kMaxBeta))
    throw InvalidInputError("beta must lie in [0, " + std::to_string(kMaxBeta) + "]");
  if (!(sharpenBeta > 1.0 && sharpenBeta <= kMaxBeta))
    throw InvalidInputError("sharpenBeta must lie in (1, " + std::to_string(kMaxBeta) + "]");
  if (!(geodesicAlpha >= kMinAlpha && geodesicAlpha <= kMaxAlpha))
    throw InvalidInputError("geodesicAlpha must lie in [" + std::to_string(kMinAlpha) + ", " +
                            std::to_string(kMaxAlpha) + "]");
  parseReactionPreset(reactPreset);  // throws InvalidInputError naming the presets
  if (!(stitchAlpha > 0.0) || !std::isfinite(stitchAlpha))
    throw InvalidInputError("stitchAlpha must be a positive number");
}

namespace {

void checkAppInputs(const TexelDomain& domain, const Image& texture,
                    const ViewerAppOptions& options) {
  options.validate();
  if (texture.width != domain.grid().imageWidth || texture.height != domain.grid().imageHeight)
    throw InvalidInputError("the texture is " + std::to_string(texture.width) + "x" +
                            std::to_string(texture.height) + " but the domain was built at " +
                            std::to_string(domain.grid().imageWidth) + "x" +
                            std::to_string(domain.grid().imageHeight));
}

}  // namespace

std::unique_ptr<ViewerApp> makeViewerApp(ViewerAppKind kind, const TexelDomain& domain,
                                         const Image& texture, const ViewerAppOptions& options) {
  checkAppInputs(domain, texture, options);
  switch (kind) {
    case ViewerAppKind::Filter: return makeFilterView(domain, texture, options);
    case ViewerAppKind::Geodesic: return makeGeodesicView(domain, texture, options);
    case ViewerAppKind::React: return makeReactView(domain, texture, options);
    case ViewerAppKind::Stitch: return makeStitchView(domain, texture, options);
    case ViewerAppKind::Lic:
      return makeLicView(domain, options);
  }
  throw InvalidInputError("unknown viewer app");
}

Eigen::Vector2d hitUv(const TexturedMesh& mesh, const SurfaceHit& at) {
  const auto& t = mesh.uvTriangles.at(static_cast<size_t>(at.face));
  return at.bary[0] * mesh.uvs[t[0]] + at.bary[1] * mesh.uvs[t[1]] + at.bary[2] * mesh.uvs[t[2]];
}

Eigen::Vector3d hitPosition(const TexturedMesh& mesh, const SurfaceHit& at) {
  const auto& t = mesh.triangles.at(static_cast<size_t>(at.face));
  return at.bary[0] * mesh.positions[t[0]] + at.bary[1] * mesh.positions[t[1]] +
         at.bary[2] * mesh.positions[t[2]];
}

double sampleActive(const TexelDomain& domain, const Image& values, const SurfaceHit& at,
                    int channel) {
  const TexelGrid& grid = domain.grid();
  const Eigen::Vector2d p = grid.toGrid(hitUv(domain.mesh(), at));
  const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
  const double fx = p.x() - x, fy = p.y() - y;
  double sum = 0.0, weight = 0.0;
  for (int dy = 0; dy <= 1; ++dy)
    for (int dx = 0; dx <= 1; ++dx) {
      const int tx = x + dx, ty = y + dy;
      if (tx < 0 || ty < 0 || tx >= grid.nx || ty >= grid.ny) continue;
      if (grid.unknownOfTexel[grid.texelIndex(tx, ty)] < 0 || !grid.inImage(tx, ty)) continue;
      const double w = (dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy);
      sum += w * values.at(tx + grid.x0, ty + grid.y0, channel);
      weight += w;
    }
  return weight > 0.0 ? sum / weight : std::nan("");
}

std::vector<uint8_t> toRgba8(const Image& image) {
  const size_t n = static_cast<size_t>(image.width) * static_cast<size_t>(image.height);
  std::vector<uint8_t> out(n * 4, 255);
  const auto quantise = [](float v) {
    return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
  };
  const int c = image.channels;
  for (size_t i = 0; i < n; ++i) {
    const float* px = image.pixels.data() + i * static_cast<size_t>(c);
    uint8_t* o = out.data() + 4 * i;
    if (c < 3) {
      o[0] = o[1] = o[2] = quantise(px[0]);
      if (c == 2) o[3] = quantise(px[1]);
    } else {
      o[0] = quantise(px[0]);
      o[1] = quantise(px[1]);
      o[2] = quantise(px[2]);
      if (c == 4) o[3] = quantise(px[3]);
    }
  }
  return out;
}

}  // namespace texgrad::viewer
