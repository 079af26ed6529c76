// Entry point of the `texgrad` command: registers subcommands; errors become one clear line.
#include <CLI/CLI.hpp>
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "texgrad/core/heap_reuse.h"

int texgrad::cli::exitStatus = 0;

int main(int argc, char** argv) {
  texgrad::reuseFreedMemory();  // large texel buffers: reuse the heap, no fresh page faults
  texgrad::cli::installInterruptCleanup();  // a killed run leaves no temporary output file
  CLI::App app{
      "texgrad: gradient-domain processing of surface signals inside a texture atlas.\n"
      "Meshes: .obj (+.mtl), .ply, .gltf, .glb, or builtin:NAME for a procedural mesh."};
  app.set_version_flag("--version", "texgrad 0.1.0");
  app.require_subcommand(1);
  app.option_defaults()->always_capture_default(true);  // --help shows every default
  app.fallthrough(false);
  // A bad flag is one line on stderr, like every other error (cli_common.cpp:runGuarded).
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return "texgrad: error: " + std::string(e.what()) + " (see --help)\n";
  });
  texgrad::cli::addInfoCommand(app);
  texgrad::cli::addMaskCommand(app);
  texgrad::cli::addDilateCommand(app);
  texgrad::cli::addSampleCommand(app);
  texgrad::cli::addFilterCommand(app);
  texgrad::cli::addStitchCommand(app);
  texgrad::cli::addSeamsCommand(app);
  texgrad::cli::addLicCommand(app);
  texgrad::cli::addReactCommand(app);
  texgrad::cli::addGeodesicCommand(app);
  texgrad::cli::addViewCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return texgrad::cli::exitStatus;
}
