// Fuzz target for the mesh readers (readMesh): the extension is fixed at compile time
// (TEXGRAD_FUZZ_EXTENSION: .obj, .ply, .gltf, .glb). For OBJ the input may carry its material
// library after a line "#--mtl--": that part is written to fuzz.mtl beside the OBJ.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace texgrad;
  std::string_view text = fuzz::asText(data, size);
  const std::string_view separator = "\n#--mtl--\n";
  const size_t split = text.find(separator);
  if (split != std::string_view::npos) {
    fuzz::writeScratch("fuzz.mtl", text.substr(split + separator.size()));
    text = text.substr(0, split);
  }
  try {
    const TexturedMesh mesh = readMesh(fuzz::writeScratch("fuzz" TEXGRAD_FUZZ_EXTENSION, text));
    validateMesh(mesh, "fuzzed mesh");
  } catch (const Error&) {
    // A typed refusal with a message is the expected outcome for a malformed file.
  }
  return 0;
}
