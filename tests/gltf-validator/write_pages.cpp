// For CTest GltfOutputsValidate: writes the two-material fixture
// (tests/support/two_material_gltf.h) into OUT/source and its write-back with both base-colour
// images replaced at once (writeGltfWithTextures) as OUT/pages.gltf and OUT/pages.glb, and the
// fixture with a material on every primitive as OUT/source/every.gltf (for the CLI's write-back
// of two texture pages). Usage: gltf_write_pages OUT
#include <exception>
#include <filesystem>
#include <iostream>
#include <vector>

#include "texgrad/io/gltf_writer.h"
#include "texgrad/io/mesh_reader.h"
#include "two_material_gltf.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: gltf_write_pages OUT_FOLDER\n";
    return 2;
  }
  try {
    const std::filesystem::path out = argv[1], source = out / "source";
    std::filesystem::create_directories(source);
    const texgrad::TexturedMesh mesh =
        texgrad::readMesh(texgrad::test::TwoMaterialGltf{}.write(source, "two"));
    std::vector<texgrad::Image> pictures;
    std::vector<texgrad::GltfImageReplacement> replacements;
    for (const texgrad::TextureRef& ref : mesh.textures)
      if (ref.slot == "baseColor")
        pictures.push_back(texgrad::test::fixtureImage(10 + static_cast<int>(pictures.size())));
    size_t next = 0;
    for (const texgrad::TextureRef& ref : mesh.textures)
      if (ref.slot == "baseColor") {
        const texgrad::Image& picture = pictures[next++];
        replacements.push_back({&ref, [&picture]() -> const texgrad::Image& { return picture; }});
      }
    texgrad::test::TwoMaterialGltf every;
    every.everyMaterial = true;
    every.write(source, "every");
    for (const char* name : {"pages.gltf", "pages.glb"})
      texgrad::writeGltfWithTextures(mesh.sourcePath, out / name, "baseColor", replacements);
    std::cout << replacements.size() << " base-colour images replaced\n";
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}
