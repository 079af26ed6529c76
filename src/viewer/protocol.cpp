// Viewer module: parsing and validation of client messages, binary texture frames.
#include "texgrad/viewer/protocol.h"

#include <cmath>
#include <cstring>
#include <initializer_list>
#include <nlohmann/json.hpp>

#include "texgrad/core/json_depth.h"

namespace texgrad::viewer {
namespace {

using nlohmann::json;

void requireOnlyKeys(const json& object, std::initializer_list<std::string_view> allowed) {
  for (const auto& item : object.items()) {
    bool known = item.key() == "id";
    for (std::string_view key : allowed) known = known || item.key() == key;
    if (!known) throw ProtocolError("unknown field \"" + item.key() + "\"");
  }
}

double number(const json& object, const char* key, double low, double high) {
  const auto it = object.find(key);
  if (it == object.end()) throw ProtocolError(std::string("missing field \"") + key + "\"");
  if (!it->is_number()) throw ProtocolError(std::string("field \"") + key + "\" must be a number");
  const double v = it->get<double>();
  if (!std::isfinite(v) || v < low || v > high)
    throw ProtocolError(std::string("field \"") + key + "\" must lie in [" + std::to_string(low) +
                        ", " + std::to_string(high) + "]");
  return v;
}

std::string text(const json& object, const char* key) {
  const auto it = object.find(key);
  if (it == object.end() || !it->is_string())
    throw ProtocolError(std::string("field \"") + key + "\" must be a string");
  return it->get<std::string>();
}

bool flag(const json& object, const char* key) {
  const auto it = object.find(key);
  if (it == object.end()) return false;
  if (!it->is_boolean())
    throw ProtocolError(std::string("field \"") + key + "\" must be a boolean");
  return it->get<bool>();
}

SurfaceHit surfaceHit(const json& object, int32_t faceCount) {
  SurfaceHit hit;
  const auto face = object.find("face");
  if (face == object.end() || !face->is_number_integer())
    throw ProtocolError("field \"face\" must be an integer");
  const int64_t f = face->get<int64_t>();
  if (f < 0 || f >= faceCount)
    throw ProtocolError("face " + std::to_string(f) + " is out of range (the mesh has " +
                        std::to_string(faceCount) + " faces)");
  hit.face = static_cast<int32_t>(f);
  const auto bary = object.find("bary");
  if (bary == object.end() || !bary->is_array() || bary->size() != 3)
    throw ProtocolError("field \"bary\" must be an array of 3 numbers");
  double sum = 0.0;
  for (size_t i = 0; i < 3; ++i) {
    const json& b = (*bary)[i];
    if (!b.is_number()) throw ProtocolError("field \"bary\" must be an array of 3 numbers");
    const double v = b.get<double>();
    if (!std::isfinite(v) || v < -kBarycentricTolerance || v > 1.0 + kBarycentricTolerance)
      throw ProtocolError("barycentric coordinates must lie in [0, 1]");
    hit.bary[i] = v;
    sum += v;
  }
  if (std::abs(sum - 1.0) > kBarycentricTolerance)
    throw ProtocolError("barycentric coordinates must sum to 1");
  return hit;
}

ClientMessage parseObject(const json& msg, int32_t faceCount) {
  const std::string type = text(msg, "type");
  if (type == "source") {
    requireOnlyKeys(msg, {"type", "face", "bary", "add"});
    return SetSource{surfaceHit(msg, faceCount), flag(msg, "add")};
  }
  if (type == "params") {
    requireOnlyKeys(msg, {"type", "alpha", "beta"});
    return SetFilterParameters{number(msg, "alpha", kMinAlpha, kMaxAlpha),
                               number(msg, "beta", 0.0, kMaxBeta)};
  }
  if (type == "brush") {
    requireOnlyKeys(msg, {"type", "face", "bary", "radius", "strength", "mode"});
    BrushDab dab;
    dab.at = surfaceHit(msg, faceCount);
    dab.radius = number(msg, "radius", kMinBrushRadius, kMaxBrushRadius);
    dab.strength = number(msg, "strength", 0.0, 1.0);
    const std::string mode = text(msg, "mode");
    if (mode == "smooth")
      dab.mode = BrushMode::Smooth;
    else if (mode == "sharpen")
      dab.mode = BrushMode::Sharpen;
    else if (mode == "erase")
      dab.mode = BrushMode::Erase;
    else if (mode == "lock")
      dab.mode = BrushMode::Lock;
    else if (mode == "unlock")
      dab.mode = BrushMode::Unlock;
    else
      throw ProtocolError("brush mode must be smooth, sharpen, erase, lock or unlock");
    return dab;
  }
  if (type == "show") {
    requireOnlyKeys(msg, {"type", "texture"});
    const std::string texture = text(msg, "texture");
    if (texture == "stitched") return ShowTexture{true};
    if (texture == "composite") return ShowTexture{false};
    throw ProtocolError("show texture must be composite or stitched");
  }
  if (type == "run") {
    requireOnlyKeys(msg, {"type", "action"});
    const std::string action = text(msg, "action");
    if (action == "start") return Run{RunAction::Start};
    if (action == "pause") return Run{RunAction::Pause};
    if (action == "step") return Run{RunAction::Step};
    if (action == "reset") return Run{RunAction::Reset};
    throw ProtocolError("run action must be start, pause, step or reset");
  }
  if (type == "save") {
    requireOnlyKeys(msg, {"type"});
    return Save{};
  }
  if (type == "probe") {
    requireOnlyKeys(msg, {"type", "points"});
    const auto points = msg.find("points");
    if (points == msg.end() || !points->is_array() || points->size() > kMaxProbePoints)
      throw ProtocolError("field \"points\" must be an array of at most " +
                          std::to_string(kMaxProbePoints) + " surface points");
    Probe probe;
    for (const json& p : *points) {
      if (!p.is_object()) throw ProtocolError("probe points must be objects {face, bary}");
      requireOnlyKeys(p, {"face", "bary"});
      probe.points.push_back(surfaceHit(p, faceCount));
    }
    return probe;
  }
  if (type == "state") {
    requireOnlyKeys(msg, {"type"});
    return QueryState{};
  }
  throw ProtocolError("unknown message type \"" + type + "\"");
}

void put32(uint8_t* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<uint8_t>(v >> (8 * i));
}
uint32_t get32(const uint8_t* in) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(in[i]) << (8 * i);
  return v;
}
uint32_t floatBits(float f) {
  uint32_t v;
  std::memcpy(&v, &f, sizeof v);
  return v;
}
float bitsFloat(uint32_t v) {
  float f;
  std::memcpy(&f, &v, sizeof f);
  return f;
}

int64_t requestId(const json& msg) {
  const auto it = msg.find("id");
  if (it == msg.end()) return -1;
  if (!it->is_number_integer() || it->get<int64_t>() < 0 || it->get<int64_t>() > kMaxRequestId)
    throw ProtocolError("field \"id\" must be an integer in [0, " + std::to_string(kMaxRequestId) +
                        "]");
  return it->get<int64_t>();
}

json parseJson(std::string_view message, size_t maxBytes) {
  if (message.size() > maxBytes)
    throw ProtocolError("message of " + std::to_string(message.size()) +
                        " bytes exceeds the limit of " + std::to_string(maxBytes));
  // Reject deep nesting before parsing: no valid message nests deeper than 3 levels.
  if (jsonNestsDeeperThan(message, 4)) throw ProtocolError("message nests too deeply");
  json msg = json::parse(message, nullptr, false);
  if (msg.is_discarded()) throw ProtocolError("message is not valid JSON");
  if (!msg.is_object()) throw ProtocolError("message must be a JSON object");
  return msg;
}

}  // namespace

int64_t peekRequestId(std::string_view message) {
  try {
    return requestId(parseJson(message, kMaxFrameBytes));
  } catch (const std::exception&) {
    return -1;
  }
}

ClientRequest parseClientMessage(std::string_view message, int32_t faceCount) {
  const json msg = parseJson(message, kMaxMessageBytes);
  try {
    ClientRequest request;
    request.id = requestId(msg);
    request.message = parseObject(msg, faceCount);
    return request;
  } catch (const json::exception& e) {
    throw ProtocolError(std::string("malformed message: ") + e.what());
  }
}

std::string errorReply(std::string_view message, int64_t id) {
  json reply{{"type", "error"}, {"message", std::string(message)}};
  if (id >= 0) reply["id"] = id;
  return reply.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::vector<uint8_t> encodeFrame(const FrameHeader& header, const std::vector<uint8_t>& texels) {
  std::vector<uint8_t> out(kFrameHeaderBytes + texels.size());
  uint8_t* p = out.data();
  put32(p + 0, FrameHeader::kMagic);
  put32(p + 4, static_cast<uint32_t>(header.format));
  put32(p + 8, header.width);
  put32(p + 12, header.height);
  put32(p + 16, header.sequence);
  put32(p + 20, header.iteration);
  put32(p + 24, floatBits(header.residual));
  put32(p + 28, floatBits(header.scale));
  if (!texels.empty()) std::memcpy(p + kFrameHeaderBytes, texels.data(), texels.size());
  return out;
}

FrameHeader decodeFrameHeader(const std::vector<uint8_t>& frame) {
  if (frame.size() < kFrameHeaderBytes || get32(frame.data()) != FrameHeader::kMagic)
    throw ProtocolError("not a texgrad texture frame");
  const uint8_t* p = frame.data();
  FrameHeader h;
  const uint32_t format = get32(p + 4);
  if (format != 1 && format != 2) throw ProtocolError("unknown frame format");
  h.format = static_cast<FrameFormat>(format);
  h.width = get32(p + 8);
  h.height = get32(p + 12);
  h.sequence = get32(p + 16);
  h.iteration = get32(p + 20);
  h.residual = bitsFloat(get32(p + 24));
  h.scale = bitsFloat(get32(p + 28));
  const size_t bytesPerTexel = h.format == FrameFormat::Rgba8 ? 4 : 2;
  if (frame.size() != kFrameHeaderBytes + size_t{h.width} * h.height * bytesPerTexel)
    throw ProtocolError("frame size does not match its header");
  return h;
}

}  // namespace texgrad::viewer
