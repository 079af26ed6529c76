// Entry point of the `texgrad` command: registers subcommands; errors become one clear line.
#include <CLI/CLI.hpp>
#include <cstddef>
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "texgrad/core/heap_reuse.h"

int texgrad::cli::exitStatus = 0;

int main(int argc, char** argv) {
  texgrad::cli::installInterruptCleanup();  // a killed run leaves no temporary output file
  CLI::App app{
      "texgrad: gradient-domain processing of surface signals inside a texture atlas.\n"
      "Meshes: .obj (+.mtl), .ply, .gltf, .glb, or builtin:NAME for a procedural mesh.\n"
      "Outputs: an image, or for a mesh read from glTF a .gltf/.glb copy of its asset with the "
      "processed texture replaced. A copy is one self-contained file that can be moved: every "
      "image is embedded (.glb: binary chunk; .gltf: base64, a third larger). A source image file "
      "that is missing is left out of the copy with the material slots that used it, with one "
      "warning line naming it (none with --quiet); the processed slot's image must exist."};
  app.set_version_flag("--version", "texgrad " TEXGRAD_VERSION);  // project() in CMakeLists.txt
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
  texgrad::cli::addProjectCommand(app);
  texgrad::cli::addTextureCommand(app);
#ifdef TEXGRAD_WITH_VIEWER  // TEXGRAD_BUILD_VIEWER
  texgrad::cli::addViewCommand(app);
#endif
  // One-shot commands allocate and free large texel buffers many times, then exit: they opt into
  // keeping freed memory for reuse (no fresh page faults; include/texgrad/core/heap_reuse.h).
  // `view` runs until stopped, mostly idle between edits: with glibc's defaults the memory its
  // set-up frees (assembly and factorisation scratch) goes back to the system instead of staying
  // resident for the whole session.
  for (CLI::App* command : app.get_subcommands({}))
    if (command->get_name() != "view")
      command->preparse_callback([](std::size_t) { texgrad::reuseFreedMemory(); });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return texgrad::cli::exitStatus;
}
