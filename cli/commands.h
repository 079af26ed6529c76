// Registration of every `texgrad` subcommand; each lives in its own cmd_*.cpp file.
#pragma once

#include <CLI/CLI.hpp>

namespace texgrad::cli {

/// Exit status the chosen subcommand sets (0 success, 1 bad input/failure, 2 usage).
extern int exitStatus;

/// `texgrad info`: atlas diagnostics.
void addInfoCommand(CLI::App& app);
/// `texgrad mask`: texel class images.
void addMaskCommand(CLI::App& app);
/// `texgrad dilate`: gutter padding.
void addDilateCommand(CLI::App& app);
/// `texgrad sample`: writes the built-in sample mesh and texture.
void addSampleCommand(CLI::App& app);
/// `texgrad filter`: gradient-domain smoothing / sharpening.
void addFilterCommand(CLI::App& app);
/// `texgrad stitch`: seamless merging of several sources.
void addStitchCommand(CLI::App& app);
/// `texgrad seams`: re-solve chart-boundary texels.
void addSeamsCommand(CLI::App& app);
/// `texgrad lic`: line integral convolution of a vector field or curvature directions.
void addLicCommand(CLI::App& app);
/// `texgrad react`: Gray-Scott reaction-diffusion pattern.
void addReactCommand(CLI::App& app);
void addGeodesicCommand(CLI::App& app);  ///< `texgrad geodesic`: heat-method distances.
/// `texgrad project`: photos to partial textures and confidence maps.
void addProjectCommand(CLI::App& app);
/// `texgrad texture`: photos to one seamless texture.
void addTextureCommand(CLI::App& app);
/// `texgrad view`: browser viewer server.
void addViewCommand(CLI::App& app);

}  // namespace texgrad::cli
