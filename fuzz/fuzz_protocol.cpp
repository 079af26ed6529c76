// Fuzz target for the viewer's message protocol (parseClientMessage, peekRequestId): one text
// message from the browser page, as the server receives it.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.h"
#include "texgrad/viewer/protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  constexpr int32_t kFaceCount = 100;  ///< bounds the face indices a message may name
  const std::string_view text = texgrad::fuzz::asText(data, size);
  texgrad::viewer::peekRequestId(text);
  try {
    texgrad::viewer::parseClientMessage(text, kFaceCount);
  } catch (const texgrad::viewer::ProtocolError&) {
    // A refusal the page is told about is the expected outcome for a malformed message.
  }
  return 0;
}
