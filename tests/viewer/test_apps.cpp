// Viewer module tests: the run-controlled apps behind a session (react, lic): start / pause / step
// advance the iteration, reset restarts it, messages the app does not take are answered with an
// error and the session keeps serving.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <nlohmann/json.hpp>

#include "texgrad/io/procedural.h"
#include "texgrad/viewer/viewer_session.h"

namespace texgrad::viewer {
namespace {

/// Sends one message and waits for its reply.
nlohmann::json ask(ViewerSession& session, const std::string& text) {
  std::mutex m;
  std::condition_variable cv;
  nlohmann::json reply;
  bool got = false;
  session.receive(text, [&](std::string r) {
    std::lock_guard lock(m);
    reply = nlohmann::json::parse(r);
    got = true;
    cv.notify_all();
  });
  std::unique_lock lock(m);
  EXPECT_TRUE(cv.wait_for(lock, std::chrono::seconds(60), [&] { return got; })) << text;
  return reply;
}

class ReactSession : public ::testing::Test {
 protected:
  ReactSession()
      : domain_(procedural::cubeSphere(6), 48, 48), texture_(48, 48, 3) {}

  std::unique_ptr<ViewerSession> open(int maxIterations) {
    SessionOptions options;
    options.maxIterations = maxIterations;
    auto session = std::make_unique<ViewerSession>(
        makeViewerApp(ViewerAppKind::React, domain_, texture_, {}),
        static_cast<int32_t>(domain_.mesh().faceCount()), options);
    session->start();
    return session;
  }

  TexelDomain domain_;
  Image texture_;
};

TEST_F(ReactSession, RunsToTheIterationLimitAndStartExtendsIt) {
  auto session = open(3);
  ASSERT_TRUE(session->waitSettled(60.0));
  SessionState s = session->state();
  EXPECT_EQ(s.app, "react");
  EXPECT_EQ(s.iteration, 3u);
  EXPECT_TRUE(std::isfinite(s.residual));
  EXPECT_EQ(ask(*session, R"({"type":"run","action":"start","id":4})")["id"], 4);
  ASSERT_TRUE(session->waitSettled(60.0));
  EXPECT_EQ(session->state().iteration, 6u);  // a time stepper: Start runs another 3 steps
  const SharedBytes frame = session->latestFrame();
  const FrameHeader header = decodeFrameHeader(*frame);
  EXPECT_EQ(header.format, FrameFormat::Rgba8);
  EXPECT_EQ(header.width, 48u);
  EXPECT_EQ(header.iteration, 6u);
}

TEST_F(ReactSession, StepAdvancesOneIterationAndResetRestarts) {
  auto session = open(1000);
  EXPECT_EQ(ask(*session, R"({"type":"run","action":"pause"})")["type"], "ok");
  ASSERT_TRUE(session->waitSettled(60.0));
  const SessionState before = session->state();
  EXPECT_TRUE(before.paused);
  EXPECT_EQ(ask(*session, R"({"type":"run","action":"step"})")["type"], "ok");
  ASSERT_TRUE(session->waitSettled(60.0));
  const SessionState after = session->state();
  EXPECT_EQ(after.iteration, before.iteration + 1);
  EXPECT_EQ(after.totalSteps, before.totalSteps + 1);
  EXPECT_EQ(after.sequence, before.sequence + 1);  // one frame per step
  EXPECT_GE(after.residual, 0.0);
  EXPECT_LT(after.residual, 1.0);

  // The page shows u: a seeded pattern has values below 1 somewhere and 1 (no pattern) elsewhere.
  const nlohmann::json probe =
      ask(*session, R"({"type":"probe","points":[{"face":0,"bary":[0.3,0.3,0.4]}]})");
  ASSERT_EQ(probe["type"], "probe");
  EXPECT_GE(probe["values"][0].get<double>(), 0.0);
  EXPECT_LE(probe["values"][0].get<double>(), 1.0 + 1e-6);

  EXPECT_EQ(ask(*session, R"({"type":"run","action":"reset"})")["type"], "ok");
  ASSERT_TRUE(session->waitSettled(60.0));
  EXPECT_EQ(session->state().iteration, 0u);  // still paused: reset does not step
}

TEST_F(ReactSession, RejectsMessagesOfOtherAppsAndKeepsServing) {
  auto session = open(2);
  ASSERT_TRUE(session->waitSettled(60.0));
  const nlohmann::json source =
      ask(*session, R"({"type":"source","face":1,"bary":[0.2,0.3,0.5],"id":7})");
  EXPECT_EQ(source["type"], "error");
  EXPECT_EQ(source["id"], 7);
  EXPECT_EQ(ask(*session, R"({"type":"params","alpha":100,"beta":1})")["type"], "error");
  EXPECT_EQ(ask(*session, R"({"type":"run","action":"fly"})")["type"], "error");
  EXPECT_EQ(ask(*session, R"({"type":"state"})")["iteration"], 2);
  EXPECT_TRUE(session->state().error.empty());
}

TEST(LicSession, ShowsNoiseThenConvolvesOncePerStep) {
  TexelDomain domain(procedural::cylinder(24, 12), 48, 48);
  const Image texture(48, 48, 3);
  ViewerSession session(makeViewerApp(ViewerAppKind::Lic, domain, texture, {}),
                        static_cast<int32_t>(domain.mesh().faceCount()), SessionOptions{});
  const uint32_t noiseFrame = decodeFrameHeader(*session.latestFrame()).sequence;
  session.start();
  ASSERT_TRUE(session.waitSettled(120.0));
  const SessionState s = session.state();
  EXPECT_EQ(s.app, "lic");
  EXPECT_EQ(s.iteration, 1u);  // one convolution, then settled
  EXPECT_TRUE(s.error.empty()) << s.error;
  EXPECT_LT(s.residual, 1e-4);
  EXPECT_GT(decodeFrameHeader(*session.latestFrame()).sequence, noiseFrame);
  EXPECT_EQ(ask(session, R"({"type":"run","action":"step"})")["type"], "ok");
  ASSERT_TRUE(session.waitSettled(120.0));
  EXPECT_EQ(session.state().iteration, 2u);
  EXPECT_EQ(ask(session, R"({"type":"run","action":"reset"})")["type"], "ok");
  EXPECT_EQ(ask(session, R"({"type":"brush","face":0,"bary":[0.3,0.3,0.4]})")["type"], "error");
  session.stop();
  // The const overload cannot set LIC up (it borrows the domain's operators).
  const TexelDomain& constDomain = domain;
  EXPECT_THROW(makeViewerApp(ViewerAppKind::Lic, constDomain, texture, {}), InvalidInputError);
}

TEST(ViewerApps, ParsesReactAndRejectsUnknownPresets) {
  EXPECT_EQ(parseViewerAppKind("react"), ViewerAppKind::React);
  EXPECT_EQ(toString(ViewerAppKind::React), "react");
  EXPECT_EQ(parseViewerAppKind("lic"), ViewerAppKind::Lic);
  EXPECT_THROW(parseViewerAppKind("paint"), InvalidInputError);
  ViewerAppOptions options;
  options.reactPreset = "waves";
  EXPECT_THROW(options.validate(), InvalidInputError);
}

}  // namespace
}  // namespace texgrad::viewer
