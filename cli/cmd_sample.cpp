// `texgrad sample`: writes the built-in procedural sample (mesh + texture) so other commands and
// other tools can read it.
#include <filesystem>
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_writer.h"
#include "texgrad/io/procedural.h"

namespace texgrad::cli {
namespace {

struct SampleArgs {
  std::string outDir = "sample";
  std::string mesh = "sample";
  int size = 1024;
};

void runSample(const SampleArgs& args) {
  const std::filesystem::path dir(args.outDir);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError("cannot create folder " + dir.string() + ": " + ec.message());
  const TexturedMesh mesh = loadMesh("builtin:" + args.mesh, {});
  const Image texture = procedural::sampleTexture(args.size, args.size);
  writeImage(dir / (args.mesh + ".png"), texture, PixelFormat::UInt8);
  writeObj(dir / (args.mesh + ".obj"), mesh, args.mesh + ".png");
  std::cout << "wrote " << (dir / (args.mesh + ".obj")).string() << " (" << mesh.triangles.size()
            << " faces) and " << (dir / (args.mesh + ".png")).string() << " (" << args.size << "x"
            << args.size << ")\n";
}

}  // namespace

void addSampleCommand(CLI::App& app) {
  auto args = std::make_shared<SampleArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sample", "Write a built-in procedural mesh (OBJ + MTL) and the sample texture (PNG).");
  cmd->add_option("--out-dir,-o", args->outDir, "Folder to write into")->default_val("sample");
  cmd->add_option("--mesh", args->mesh, "Which built-in mesh: " + builtinMeshNames())
      ->default_val("sample")
      ->check(CLI::IsMember({"sample", "sphere", "cube", "cylinder", "square", "two-charts",
                             "aligned-cube", "jittered-cube"}));
  cmd->add_option("--size", args->size, "Texture size in texels (square)")
      ->default_val(1024)
      ->check(CLI::Range(2, 16384));
  cmd->callback([args] { exitStatus = runGuarded([&] { runSample(*args); }); });
}

}  // namespace texgrad::cli
