// A program outside texgrad that uses the installed library: smooths a mesh's texture with the
// screened Poisson filter (paper §7.1) exactly as `texgrad filter MESH TEXTURE --beta 0 --out OUT`.
// scripts/test-consumers.sh builds it three ways and compares its output with the CLI's.
#include <exception>
#include <iostream>
#include <utility>

#include <texgrad/apps/filter.h>
#include <texgrad/apps/texel_domain.h>
#include <texgrad/io/image_io.h>
#include <texgrad/io/mesh_reader.h>
#include <texgrad/io/uv_tiles.h>

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: filter_texture MESH TEXTURE OUT\n";
    return 2;
  }
  try {
    texgrad::TexturedMesh mesh = texgrad::readMesh(argv[1]);
    const texgrad::Image texture = texgrad::readImage(argv[2]);
    // UVs as the texture samples them (the CLI's --wrap auto): charts in other unit tiles are
    // moved into the image and faces across a tile border are cut there.
    const texgrad::UvWrap wrap = texgrad::samplerWrap(mesh, "baseColor");
    mesh = texgrad::wrapTextureCoordinates(std::move(mesh), wrap).mesh;

    // Atlas, texel grid and operators at the texture's resolution. Without a beta map the
    // per-piece integrals are not needed after assembly (the CLI drops them too).
    texgrad::OperatorOptions operatorOptions;
    operatorOptions.keepPieceIntegrals = false;
    const texgrad::TexelDomain domain(std::move(mesh), texture.width, texture.height,
                                      operatorOptions);

    // The CLI's defaults (alpha 1e4, multigrid-preconditioned CG to a residual of 1e-4) with all
    // gradients removed: beta 0 is the strongest smoothing.
    texgrad::FilterOptions options;
    options.beta = 0.0;
    const texgrad::FilterResult result = texgrad::filterTexture(domain, texture, options);

    texgrad::writeImage(argv[3], result.image);
    std::cout << "filtered " << domain.unknowns() << " texels in " << result.report.iterations
              << " iterations\n";
  } catch (const std::exception& e) {
    std::cerr << "filter_texture: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
