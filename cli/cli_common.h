// Shared plumbing of the `texgrad` subcommands: mesh/texture arguments, error reporting, progress.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>

#include "texgrad/core/progress.h"
#include "texgrad/io/image.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad::cli {

/// Mesh argument: a file path, or `builtin:NAME` for a procedural mesh (see builtinMeshNames()).
TexturedMesh loadMesh(const std::string& spec, double weldTolerance);

/// Names accepted after `builtin:` (sample, sphere, cube, cylinder, square, two-charts).
std::string builtinMeshNames();

/// Texture for a mesh: the explicit path if given, else the mesh's slot texture (file or embedded),
/// else the built-in sample texture for `builtin:` meshes; throws InvalidInputError if none.
Image loadTexture(const TexturedMesh& mesh, const std::string& meshSpec,
                  const std::string& explicitPath, const std::string& slot = "baseColor");

/// Parses "WxH" or "N" (square) into a resolution; throws InvalidInputError on anything else.
std::pair<int, int> parseResolution(const std::string& text);

/// A CLI11 validator for "WxH" / "N" resolutions.
const CLI::Validator& resolutionValidator();

/// Progress callback drawing a bar on stderr when it is a terminal (nothing otherwise).
ProgressCallback terminalProgress(bool enabled);

/// Runs a subcommand body, turning texgrad errors into one line on stderr and an exit status.
int runGuarded(const std::function<void()>& body);

/// Prints a JSON document to stdout (pretty, newline-terminated).
void printJson(const nlohmann::json& document);

}  // namespace texgrad::cli
