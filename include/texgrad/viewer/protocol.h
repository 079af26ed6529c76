// Viewer module (on top of apps): the WebSocket protocol between `texgrad view` and its page.
// Client messages are small JSON texts, validated here; texture updates go out as binary frames.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "texgrad/core/error.h"

namespace texgrad::viewer {

/// A client message that is malformed, oversized or out of range; what() is sent back as the
/// error reply and the connection stays open.
class ProtocolError : public InvalidInputError {
 public:
  using InvalidInputError::InvalidInputError;
};

/// Largest text message the protocol accepts (bytes); longer ones are answered with an error.
inline constexpr size_t kMaxMessageBytes = 16 * 1024;
/// Largest message the WebSocket layer reads at all; beyond it the connection is closed (1009).
inline constexpr size_t kMaxFrameBytes = 1024 * 1024;
/// Most surface points one probe message may ask for.
inline constexpr size_t kMaxProbePoints = 256;
/// Brush radius bounds, as a fraction of the bounding-box diagonal of the mesh.
inline constexpr double kMinBrushRadius = 1e-4;
inline constexpr double kMaxBrushRadius = 0.5;
/// Range of the filter's screening weight alpha and gradient scale beta accepted from the page.
inline constexpr double kMinAlpha = 1e-2;
inline constexpr double kMaxAlpha = 1e8;
inline constexpr double kMaxBeta = 10.0;
/// Tolerance on barycentric coordinates (each >= -tol, sum within tol of 1).
inline constexpr double kBarycentricTolerance = 1e-3;

/// A point on the mesh: face index and barycentric coordinates of its three corners.
struct SurfaceHit {
  int32_t face = -1;
  std::array<double, 3> bary{};
};

/// geodesic: set (add = false) or add (shift-click) a source point.
struct SetSource {
  SurfaceHit at;
  bool add = false;
};
/// filter: global screening weight and gradient scale (paper §7.1).
struct SetFilterParameters {
  double alpha = 1e4;
  double beta = 1.0;
};
/// What a brush dab does: filter: to the painted gradient-scale map (smooth, sharpen, erase);
/// stitch: to the lock mask (lock, unlock).
enum class BrushMode : uint8_t { Smooth, Sharpen, Erase, Lock, Unlock };
/// filter, stitch: one brush dab at a surface point.
struct BrushDab {
  SurfaceHit at;
  double radius = 0.05;   ///< fraction of the bounding-box diagonal
  double strength = 0.5;  ///< in [0, 1]: how far one dab moves the map towards its target (the
                          ///< lock modes are all or nothing and ignore it)
  BrushMode mode = BrushMode::Smooth;
};
/// stitch: which texture the page is shown (the composite input or the stitched result).
struct ShowTexture {
  bool stitched = true;
};
/// Solver control of any app.
enum class RunAction : uint8_t { Start, Pause, Step, Reset };
struct Run {
  RunAction action = RunAction::Start;
};
/// Writes the current texture to the path given on the command line.
struct Save {};
/// Asks for the app's scalar value (distance, luminance) at surface points.
struct Probe {
  std::vector<SurfaceHit> points;
};
/// Asks for the server state (iterations, residual, updates per second).
struct QueryState {};

/// Any validated client message.
using ClientMessage =
    std::variant<SetSource, SetFilterParameters, BrushDab, ShowTexture, Run, Save, Probe,
                 QueryState>;

/// Largest request id a page may attach (ids pair replies with requests).
inline constexpr int64_t kMaxRequestId = (int64_t{1} << 31) - 1;

/// A validated message with the page's optional request id (-1 if none), echoed in the reply.
struct ClientRequest {
  int64_t id = -1;
  ClientMessage message;
};

/// Parses and validates one text message: sizes, types, finite numbers, ranges and unknown keys.
/// `faceCount` bounds face indices. Throws ProtocolError with a message for the page; its id()
/// is the message's request id when that much could be read.
ClientRequest parseClientMessage(std::string_view text, int32_t faceCount);

/// Request id of a message up to kMaxFrameBytes (so an oversized request still gets its id back)
/// if it is a JSON object with a valid "id", else -1.
int64_t peekRequestId(std::string_view text);

/// JSON error reply {"type":"error","message":...,"id":id} (no id if id < 0).
std::string errorReply(std::string_view message, int64_t id = -1);

/// Pixel layout of a binary texture frame.
enum class FrameFormat : uint32_t {
  Rgba8 = 1,  ///< 4 bytes per texel, sRGB-encoded colour as stored in the texture
  R16 = 2,    ///< 2 bytes per texel: value / scale in [0, 1] (65535 = no value, e.g. inactive)
};

/// Header of the binary texture frame (little-endian, 32 bytes), followed by width*height texels
/// in texel order (row 0 = bottom, v upward).
struct FrameHeader {
  static constexpr uint32_t kMagic = 0x31464754;  ///< "TGF1"
  FrameFormat format = FrameFormat::Rgba8;
  uint32_t width = 0, height = 0;
  uint32_t sequence = 0;   ///< frame counter of the session
  uint32_t iteration = 0;  ///< solver iterations since the last change
  float residual = 0.0f;   ///< relative residual of the last step
  float scale = 1.0f;      ///< R16: value = texel / 65534 * scale
};
/// Size of the serialised header in bytes.
inline constexpr size_t kFrameHeaderBytes = 32;
/// Serialises header + texels into one binary message.
std::vector<uint8_t> encodeFrame(const FrameHeader& header, const std::vector<uint8_t>& texels);
/// Reads back a header (tests and tools); throws ProtocolError if the bytes are not a frame.
FrameHeader decodeFrameHeader(const std::vector<uint8_t>& frame);

}  // namespace texgrad::viewer
