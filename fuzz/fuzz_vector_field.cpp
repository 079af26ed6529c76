// Fuzz target for the `.vf` per-face vector-field reader (readFaceVectorField): the first byte
// picks the basis, the rest is the file; the mesh is taken to have as many faces as the file's
// header says (else every input would stop at the count check).
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fuzz_input.h"
#include "texgrad/apps/vector_field.h"
#include "texgrad/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace texgrad;
  if (size < 1) return 0;
  const FieldBasis basis = data[0] % 2 == 0 ? FieldBasis::Intrinsic : FieldBasis::Extrinsic;
  int32_t declared = 0;
  if (size >= 1 + sizeof(declared)) std::memcpy(&declared, data + 1, sizeof(declared));
  const size_t faceCount = declared > 0 ? static_cast<size_t>(declared) : 0;
  try {
    readFaceVectorField(fuzz::writeScratch("fuzz.vf", fuzz::asText(data + 1, size - 1)), basis,
                        faceCount);
  } catch (const Error&) {
    // A typed refusal with a message is the expected outcome for a malformed file.
  }
  return 0;
}
