// Viewer module: one running app behind the server. A worker thread applies queued page messages
// and refines the solution by one solver step per frame, publishing each result as a binary frame.
#pragma once

#include <condition_variable>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "texgrad/viewer/protocol.h"
#include "texgrad/viewer/viewer_app.h"

namespace texgrad::viewer {

/// Pacing and stopping rules of the worker.
struct SessionOptions {
  /// Upper bound on solver steps (and frames) per second; the page cannot show more.
  double maxUpdatesPerSecond = 60.0;
  /// Steps after a change (or after Start) beyond which the worker idles even if not settled.
  int maxIterations = 400;
  /// Where "save" writes (empty: saving is refused with an error reply).
  std::filesystem::path savePath;
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// Counters the page and the tests read through the "state" message.
struct SessionState {
  std::string app;
  bool running = false;    ///< the worker is stepping (not paused, not settled)
  bool paused = false;     ///< paused by the page
  uint32_t iteration = 0;  ///< steps since the last change
  uint64_t totalSteps = 0;
  uint32_t sequence = 0;  ///< frames published
  double residual = 0.0;
  double updatesPerSecond = 0.0;  ///< solver steps per second while running (moving average)
  double lastStepSeconds = 0.0;
  double lastFrameSeconds = 0.0;  ///< encoding the last frame (app texels + header), worker side
  std::string error;  ///< why the last step failed (the worker then pauses), empty if none
};

/// A shared, immutable binary message.
using SharedBytes = std::shared_ptr<const std::vector<uint8_t>>;

/// Owns an app and its worker thread. receive() may be called from any thread.
class ViewerSession {
 public:
  /// Called with every text reply for the connection that sent the message.
  using Reply = std::function<void(std::string)>;
  /// Called from the worker with every new frame.
  using FrameSink = std::function<void(SharedBytes)>;

  /// Takes the app; faceCount bounds face indices in messages. Computes the first frame.
  ViewerSession(std::unique_ptr<ViewerApp> app, int32_t faceCount, const SessionOptions& options);
  ~ViewerSession();
  ViewerSession(const ViewerSession&) = delete;
  ViewerSession& operator=(const ViewerSession&) = delete;

  /// Sets the frame sink (before start()).
  void setFrameSink(FrameSink sink);
  /// Starts the worker thread; it refines until settled, then waits for messages.
  void start();
  /// Stops and joins the worker (idempotent).
  void stop();
  /// Validates a text message; errors are replied at once, valid messages are queued for the
  /// worker, which replies (probe, state, save, or {"type":"ok"}) when it has applied them. Every
  /// message gets exactly one reply, carrying the message's "id" if it had one.
  void receive(std::string_view text, const Reply& reply);
  /// The most recent frame (never null after construction).
  SharedBytes latestFrame() const;
  /// Current counters.
  SessionState state() const;
  /// JSON object of state().
  std::string stateJson() const;
  /// Blocks until the worker has nothing left to refine or `seconds` pass; true if settled.
  bool waitSettled(double seconds) const;

 private:
  struct Pending {
    ClientRequest request;
    Reply reply;
  };
  void run();
  void handle(Pending& pending);
  void publish();

  std::unique_ptr<ViewerApp> app_;
  int32_t faceCount_;
  SessionOptions options_;
  FrameSink sink_;

  mutable std::mutex mutex_;
  mutable std::condition_variable wake_;
  std::deque<Pending> queue_;
  bool stopping_ = false;
  bool dirty_ = true;       ///< something changed since the app settled
  int stepsRequested_ = 0;  ///< explicit single steps while paused
  uint32_t iterationLimit_ = 0;  ///< iteration at which the worker idles (Start extends it)
  SessionState state_;
  SharedBytes frame_;
  std::thread worker_;
};

}  // namespace texgrad::viewer
