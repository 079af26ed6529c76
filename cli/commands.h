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

}  // namespace texgrad::cli
