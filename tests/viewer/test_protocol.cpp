// Viewer module tests: message validation (sizes, types, ranges), frames, access tokens.
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <variant>

#include "texgrad/viewer/access_token.h"
#include "texgrad/viewer/protocol.h"

namespace texgrad::viewer {
namespace {

constexpr int32_t kFaces = 10;

ClientMessage parse(const std::string& text) {
  return parseClientMessage(text, kFaces).message;
}

TEST(ViewerProtocol, ParsesEveryMessageType) {
  const auto source =
      std::get<SetSource>(parse(R"({"type":"source","face":3,"bary":[0.2,0.3,0.5],"add":true})"));
  EXPECT_EQ(source.at.face, 3);
  EXPECT_TRUE(source.add);
  EXPECT_DOUBLE_EQ(source.at.bary[2], 0.5);
  const auto params =
      std::get<SetFilterParameters>(parse(R"({"type":"params","alpha":100,"beta":0.5})"));
  EXPECT_DOUBLE_EQ(params.alpha, 100.0);
  const auto dab = std::get<BrushDab>(parse(
      R"({"type":"brush","face":0,"bary":[1,0,0],"radius":0.1,"strength":1,"mode":"sharpen"})"));
  EXPECT_EQ(dab.mode, BrushMode::Sharpen);
  EXPECT_EQ(std::get<viewer::Run>(parse(R"({"type":"run","action":"step"})")).action,
            RunAction::Step);
  EXPECT_TRUE(std::holds_alternative<Save>(parse(R"({"type":"save"})")));
  EXPECT_TRUE(std::holds_alternative<QueryState>(parse(R"({"type":"state"})")));
  const auto probe =
      std::get<Probe>(parse(R"({"type":"probe","points":[{"face":9,"bary":[0,0,1]}]})"));
  EXPECT_EQ(probe.points.size(), 1u);
  EXPECT_EQ(parseClientMessage(R"({"type":"state","id":42})", kFaces).id, 42);
  EXPECT_EQ(parseClientMessage(R"({"type":"state"})", kFaces).id, -1);
}

TEST(ViewerProtocol, RefusesMalformedMessages) {
  const char* bad[] = {
      "",
      "{",
      "[]",
      "42",
      R"("state")",
      R"({"type":"nope"})",
      R"({"type":7})",
      R"({"kind":"state"})",
      R"({"type":"state","extra":1})",
      R"({"type":"state","id":-1})",
      R"({"type":"state","id":1e20})",
      R"({"type":"state","id":"x"})",
      R"({"type":"source","face":10,"bary":[1,0,0]})",
      R"({"type":"source","face":-1,"bary":[1,0,0]})",
      R"({"type":"source","face":1.5,"bary":[1,0,0]})",
      R"({"type":"source","face":99999999999999999999,"bary":[1,0,0]})",
      R"({"type":"source","face":1,"bary":[1,0]})",
      R"({"type":"source","face":1,"bary":[0.5,0.5,0.5]})",
      R"({"type":"source","face":1,"bary":[2,-1,0]})",
      R"({"type":"source","face":1,"bary":["1",0,0]})",
      R"({"type":"source","face":1,"bary":[1,0,0],"add":"yes"})",
      R"({"type":"params","alpha":0,"beta":1})",
      R"({"type":"params","alpha":1e400,"beta":1})",
      R"({"type":"params","alpha":100,"beta":-1})",
      R"({"type":"params","alpha":100})",
      R"({"type":"brush","face":0,"bary":[1,0,0],"radius":5,"strength":1,"mode":"smooth"})",
      R"({"type":"brush","face":0,"bary":[1,0,0],"radius":0.1,"strength":2,"mode":"smooth"})",
      R"({"type":"brush","face":0,"bary":[1,0,0],"radius":0.1,"strength":1,"mode":"melt"})",
      R"({"type":"run","action":"explode"})",
      R"({"type":"probe","points":{}})",
      R"({"type":"probe","points":[1]})",
      R"({"type":"probe","points":[{"face":0,"bary":[1,0,0],"x":1}]})",
  };
  for (const char* text : bad)
    EXPECT_THROW(parseClientMessage(text, kFaces), ProtocolError) << text;
}

TEST(ViewerProtocol, RefusesOversizedAndDeepMessages) {
  const std::string pad(kMaxMessageBytes, ' ');
  EXPECT_THROW(parseClientMessage(R"({"type":"state"})" + pad, kFaces), ProtocolError);
  EXPECT_THROW(parseClientMessage(std::string(5000, '[') + std::string(5000, ']'), kFaces),
               ProtocolError);
  std::string points = R"({"type":"probe","points":[)";
  for (size_t i = 0; i <= kMaxProbePoints; ++i)
    points += std::string(i ? "," : "") + R"({"face":0,"bary":[1,0,0]})";
  points += "]}";
  ASSERT_LE(points.size(), kMaxMessageBytes);
  EXPECT_THROW(parseClientMessage(points, kFaces), ProtocolError);
  // An oversized request still gets its id back in the error reply.
  EXPECT_EQ(peekRequestId(R"({"type":"state","id":7,"pad":")" + pad + "\"}"), 7);
  EXPECT_EQ(peekRequestId("not json"), -1);
}

TEST(ViewerProtocol, ErrorReplyIsJsonWithId) {
  EXPECT_EQ(errorReply("bad \"thing\"", 3), R"({"id":3,"message":"bad \"thing\"","type":"error"})");
  EXPECT_EQ(errorReply("x"), R"({"message":"x","type":"error"})");
}

TEST(ViewerProtocol, FrameRoundTrip) {
  FrameHeader h;
  h.format = FrameFormat::R16;
  h.width = 3;
  h.height = 2;
  h.sequence = 9;
  h.iteration = 4;
  h.residual = 0.25f;
  h.scale = 2.5f;
  const std::vector<uint8_t> texels(12, 7);
  const std::vector<uint8_t> frame = encodeFrame(h, texels);
  ASSERT_EQ(frame.size(), kFrameHeaderBytes + texels.size());
  const FrameHeader back = decodeFrameHeader(frame);
  EXPECT_EQ(back.format, FrameFormat::R16);
  EXPECT_EQ(back.width, 3u);
  EXPECT_EQ(back.sequence, 9u);
  EXPECT_EQ(back.iteration, 4u);
  EXPECT_FLOAT_EQ(back.residual, 0.25f);
  EXPECT_FLOAT_EQ(back.scale, 2.5f);
  std::vector<uint8_t> truncated(frame.begin(), frame.end() - 1);
  EXPECT_THROW(decodeFrameHeader(truncated), ProtocolError);
}

TEST(ViewerAccess, LoopbackTokensAndTargets) {
  EXPECT_TRUE(isLoopbackHost("127.0.0.1"));
  EXPECT_TRUE(isLoopbackHost("127.1.2.3"));
  EXPECT_TRUE(isLoopbackHost("::1"));
  EXPECT_TRUE(isLoopbackHost("localhost"));
  EXPECT_FALSE(isLoopbackHost("0.0.0.0"));
  EXPECT_FALSE(isLoopbackHost("192.168.1.2"));
  EXPECT_FALSE(isLoopbackHost("evil.example"));
  std::set<std::string> tokens;
  for (int i = 0; i < 20; ++i) {
    const std::string t = generateAccessToken();
    EXPECT_EQ(t.size(), 32u);
    EXPECT_EQ(t.find_first_not_of("0123456789abcdef"), std::string::npos);
    tokens.insert(t);
  }
  EXPECT_EQ(tokens.size(), 20u);
  EXPECT_TRUE(tokenMatches("abc", "abc"));
  EXPECT_FALSE(tokenMatches("abd", "abc"));
  EXPECT_FALSE(tokenMatches("ab", "abc"));
  EXPECT_FALSE(tokenMatches("", "abc"));
  EXPECT_TRUE(tokenMatches("", ""));
  EXPECT_EQ(queryParameter("/ws?a=1&token=xyz", "token"), "xyz");
  EXPECT_EQ(queryParameter("/ws?tokenx=1", "token"), "");
  EXPECT_EQ(queryParameter("/ws", "token"), "");
  EXPECT_EQ(targetPath("/api/mesh?token=1"), "/api/mesh");
}

}  // namespace
}  // namespace texgrad::viewer
