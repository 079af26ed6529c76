// Fuzz target for image decoding (readImageFromMemory: libpng, libjpeg, OpenEXR, libtiff): the first byte picks
// the extension the name carries, the rest are the file's bytes.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::array<const char*, 4> kNames = {"fuzz.png", "fuzz.jpg", "fuzz.exr", "fuzz.ppm"};
  if (size < 1) return 0;
  const std::vector<unsigned char> bytes(data + 1, data + size);
  try {
    texgrad::readImageFromMemory(bytes, kNames[data[0] % kNames.size()]);
  } catch (const texgrad::Error&) {
    // A typed refusal with a message is the expected outcome for a malformed file.
  }
  return 0;
}
