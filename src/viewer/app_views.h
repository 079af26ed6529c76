// Viewer module (internal): constructors of the concrete apps behind makeViewerApp.
#pragma once

#include <memory>

#include "texgrad/viewer/viewer_app.h"

namespace texgrad::viewer {

std::unique_ptr<ViewerApp> makeFilterView(const TexelDomain& domain, const Image& texture,
                                          const ViewerAppOptions& options);
std::unique_ptr<ViewerApp> makeGeodesicView(const TexelDomain& domain, const Image& texture,
                                            const ViewerAppOptions& options);

std::unique_ptr<ViewerApp> makeReactView(const TexelDomain& domain, const Image& texture,
                                         const ViewerAppOptions& options);

std::unique_ptr<ViewerApp> makeLicView(const TexelDomain& domain, const ViewerAppOptions& options);

std::unique_ptr<ViewerApp> makeStitchView(const TexelDomain& domain, const Image& composite,
                                          const ViewerAppOptions& options);

/// RGBA8 texels of a float image in [0, 1] (grey replicated, alpha 255 when absent).
std::vector<uint8_t> toRgba8(const Image& image);

}  // namespace texgrad::viewer
