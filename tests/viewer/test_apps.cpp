// Viewer module tests: the run-controlled apps behind a session (react, lic): start / pause / step
// advance the iteration, reset restarts it, messages the app does not take are answered with an
// error and the session keeps serving; stitch: composite then stitched, toggle, lock brush.
#include <gtest/gtest.h>

#include <algorithm>
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
  const TexelDomain domain(procedural::cylinder(24, 12), 48, 48);
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
}

/// Stitch fixture: a cube sphere whose composite takes the left half of the image from one source
/// and the right half from a second one that is 0.3 brighter.
class StitchSession : public ::testing::Test {
 protected:
  StitchSession()
      : domain_(procedural::cubeSphere(6), 48, 48), composite_(48, 48, 3), segments_(48, 48, 1) {
    for (int j = 0; j < 48; ++j)
      for (int i = 0; i < 48; ++i) {
        const bool right = i >= 24;
        for (int c = 0; c < 3; ++c)
          composite_.at(i, j, c) =
              0.3f + 0.1f * std::sin(0.4f * static_cast<float>(i + 2 * c)) *
                         std::cos(0.3f * static_cast<float>(j)) +
              (right ? 0.3f : 0.0f);
        segments_.at(i, j) = right ? 1.0f : 0.5f;
      }
  }

  std::unique_ptr<ViewerSession> open() {
    ViewerAppOptions options;
    options.segments = segments_;
    auto session = std::make_unique<ViewerSession>(
        makeViewerApp(ViewerAppKind::Stitch, domain_, composite_, options),
        static_cast<int32_t>(domain_.mesh().faceCount()), SessionOptions{});
    return session;
  }

  static std::vector<uint8_t> texels(const SharedBytes& frame) {
    return {frame->begin() + static_cast<std::ptrdiff_t>(kFrameHeaderBytes), frame->end()};
  }

  TexelDomain domain_;
  Image composite_, segments_;
};

TEST_F(StitchSession, ShowsTheCompositeThenTheStitchedResultAndToggles) {
  auto session = open();
  const std::vector<uint8_t> composite = texels(session->latestFrame());
  session->start();
  ASSERT_TRUE(session->waitSettled(120.0));
  SessionState s = session->state();
  EXPECT_EQ(s.app, "stitch");
  EXPECT_TRUE(s.error.empty()) << s.error;
  EXPECT_EQ(s.iteration, 1u);  // one solve, then settled
  EXPECT_GE(s.residual, 0.0);
  EXPECT_LT(s.residual, 1e-2);
  EXPECT_GT(s.lastStepSeconds, 0.0);
  const std::vector<uint8_t> stitched = texels(session->latestFrame());
  ASSERT_EQ(stitched.size(), composite.size());
  EXPECT_NE(stitched, composite);

  EXPECT_EQ(ask(*session, R"({"type":"show","texture":"composite","id":3})")["id"], 3);
  ASSERT_TRUE(session->waitSettled(60.0));
  EXPECT_EQ(texels(session->latestFrame()), composite);
  EXPECT_EQ(ask(*session, R"({"type":"show","texture":"stitched"})")["type"], "ok");
  ASSERT_TRUE(session->waitSettled(60.0));
  EXPECT_EQ(texels(session->latestFrame()), stitched);
  EXPECT_EQ(session->state().residual, s.residual);  // a toggle does not solve again
}

TEST_F(StitchSession, LockBrushKeepsTheCompositeExactlyAfterTheResolve) {
  auto session = open();
  const std::vector<uint8_t> composite = texels(session->latestFrame());
  session->start();
  ASSERT_TRUE(session->waitSettled(120.0));
  const std::string point = R"({"type":"probe","points":[{"face":5,"bary":[0.3,0.3,0.4]}]})";
  const double stitchedValue = ask(*session, point)["values"][0].get<double>();
  ask(*session, R"({"type":"show","texture":"composite"})");
  const double compositeValue = ask(*session, point)["values"][0].get<double>();
  ASSERT_NE(stitchedValue, compositeValue);
  const auto matching = [&](const std::vector<uint8_t>& frame) {
    size_t same = 0;
    for (size_t t = 0; t < frame.size(); t += 4)
      same += std::equal(frame.begin() + t, frame.begin() + t + 3, composite.begin() + t);
    return same;
  };
  const auto lockedInFrame = [&](const std::vector<uint8_t>& frame) {
    size_t locked = 0, lockedAndSame = 0;
    for (size_t t = 0; t < frame.size(); t += 4)
      if (frame[t + 3] == 0) {
        ++locked;
        lockedAndSame += std::equal(frame.begin() + t, frame.begin() + t + 3, composite.begin() + t);
      }
    return std::make_pair(locked, lockedAndSame);
  };
  ask(*session, R"({"type":"show","texture":"stitched"})");
  ASSERT_TRUE(session->waitSettled(60.0));
  const size_t before = matching(texels(session->latestFrame()));

  // Two dabs in one batch or in two: at most one solve is pending; the page sees stitched.
  EXPECT_EQ(ask(*session, R"({"type":"show","texture":"composite"})")["type"], "ok");
  EXPECT_EQ(ask(*session, R"({"type":"brush","face":5,"bary":[0.3,0.3,0.4],"radius":0.1,)"
                          R"("strength":1,"mode":"lock","id":9})")["id"],
            9);
  EXPECT_EQ(ask(*session, R"({"type":"brush","face":5,"bary":[0.3,0.3,0.4],"radius":0.1,)"
                          R"("strength":1,"mode":"lock"})")["type"],
            "ok");
  ASSERT_TRUE(session->waitSettled(120.0));
  EXPECT_TRUE(session->state().error.empty()) << session->state().error;
  // Locked texels around the point hold the composite bit for bit: the interpolated value too.
  EXPECT_EQ(ask(*session, point)["values"][0].get<double>(), compositeValue);
  const std::vector<uint8_t> lockedFrame = texels(session->latestFrame());
  const size_t after = matching(lockedFrame);
  EXPECT_GT(after, before + 20) << before << " -> " << after;
  // The frame's alpha marks the locked texels (for the page's tint); each holds the composite.
  const auto [locked, lockedAndSame] = lockedInFrame(lockedFrame);
  EXPECT_GT(locked, 20u);
  EXPECT_EQ(lockedAndSame, locked);

  // Reset unlocks everything: the stitched value comes back.
  EXPECT_EQ(ask(*session, R"({"type":"run","action":"reset"})")["type"], "ok");
  ASSERT_TRUE(session->waitSettled(120.0));
  EXPECT_NEAR(ask(*session, point)["values"][0].get<double>(), stitchedValue, 1e-5);
  EXPECT_EQ(lockedInFrame(texels(session->latestFrame())).first, 0u);
}

TEST_F(StitchSession, RejectsBadMessagesAndKeepsServing) {
  auto session = open();
  session->start();
  ASSERT_TRUE(session->waitSettled(120.0));
  const uint64_t steps = session->state().totalSteps;
  for (const char* bad : {
           R"({"type":"brush","face":5,"bary":[0.3,0.3,0.4],"radius":0.1,"strength":1,)"
           R"("mode":"smooth","id":11})",
           R"({"type":"brush","face":5,"bary":[0.3,0.3,0.4],"radius":2,"strength":1,)"
           R"("mode":"lock","id":11})",
           R"({"type":"brush","face":99999,"bary":[0.3,0.3,0.4],"radius":0.1,"strength":1,)"
           R"("mode":"lock","id":11})",
           R"({"type":"brush","face":5,"bary":[0.3,0.3,0.4],"radius":0.1,"mode":"lock","id":11})",
           R"({"type":"show","texture":"both","id":11})",
           R"({"type":"show","texture":"stitched","extra":1,"id":11})",
           R"({"type":"source","face":1,"bary":[0.2,0.3,0.5],"id":11})",
           R"({"type":"params","alpha":100,"beta":1,"id":11})"}) {
    const nlohmann::json reply = ask(*session, bad);
    EXPECT_EQ(reply["type"], "error") << bad;
    EXPECT_EQ(reply["id"], 11) << bad;
  }
  ASSERT_TRUE(session->waitSettled(60.0));
  EXPECT_EQ(session->state().totalSteps, steps);  // nothing was applied
  EXPECT_TRUE(session->state().error.empty());
  EXPECT_EQ(ask(*session, R"({"type":"state"})")["app"], "stitch");
}

TEST_F(StitchSession, NeedsASegmentMaskOfTheCompositesSize) {
  EXPECT_EQ(parseViewerAppKind("stitch"), ViewerAppKind::Stitch);
  EXPECT_EQ(toString(ViewerAppKind::Stitch), "stitch");
  EXPECT_THROW(makeViewerApp(ViewerAppKind::Stitch, domain_, composite_, {}), InvalidInputError);
  ViewerAppOptions options;
  options.segments = Image(24, 24, 1);
  EXPECT_THROW(makeViewerApp(ViewerAppKind::Stitch, domain_, composite_, options),
               InvalidInputError);
  options.segments = segments_;
  options.stitchAlpha = -1.0;
  EXPECT_THROW(makeViewerApp(ViewerAppKind::Stitch, domain_, composite_, options),
               InvalidInputError);
}

TEST(ViewerApps, FilterBrushRejectsTheLockModes) {
  TexelDomain domain(procedural::cubeSphere(4), 32, 32);
  const Image texture(32, 32, 3);
  ViewerSession session(makeViewerApp(ViewerAppKind::Filter, domain, texture, {}),
                        static_cast<int32_t>(domain.mesh().faceCount()), SessionOptions{});
  session.start();
  EXPECT_EQ(ask(session, R"({"type":"brush","face":0,"bary":[0.3,0.3,0.4],"radius":0.1,)"
                         R"("strength":1,"mode":"lock"})")["type"],
            "error");
  EXPECT_EQ(ask(session, R"({"type":"show","texture":"composite"})")["type"], "error");
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
