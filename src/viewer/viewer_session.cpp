// Viewer module: the worker loop (apply queued messages, one solver step per frame, publish).
#include "texgrad/viewer/viewer_session.h"

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <variant>

namespace texgrad::viewer {
namespace {

using Clock = std::chrono::steady_clock;
/// Weight of the newest interval in the updates-per-second moving average.
constexpr double kRateSmoothing = 0.2;

nlohmann::json okReply(const char* what) {
  return {{"type", "ok"}, {"for", what}};
}

}  // namespace

void SessionOptions::validate() const {
  if (!(maxUpdatesPerSecond > 0.0) || !std::isfinite(maxUpdatesPerSecond))
    throw InvalidInputError("maxUpdatesPerSecond must be a positive number");
  if (maxIterations < 1) throw InvalidInputError("maxIterations must be at least 1");
}

ViewerSession::ViewerSession(std::unique_ptr<ViewerApp> app, int32_t faceCount,
                             const SessionOptions& options)
    : app_(std::move(app)), faceCount_(faceCount), options_(options) {
  options_.validate();
  state_.app = app_->name();
  iterationLimit_ = static_cast<uint32_t>(options_.maxIterations);
  publish();
}

ViewerSession::~ViewerSession() {
  stop();
}

void ViewerSession::setFrameSink(FrameSink sink) {
  std::lock_guard lock(mutex_);
  sink_ = std::move(sink);
}

void ViewerSession::start() {
  std::lock_guard lock(mutex_);
  if (worker_.joinable() || stopping_) return;
  worker_ = std::thread([this] { run(); });
}

void ViewerSession::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void ViewerSession::receive(std::string_view text, const Reply& reply) {
  try {
    ClientRequest request = parseClientMessage(text, faceCount_);
    {
      std::lock_guard lock(mutex_);
      queue_.push_back({std::move(request), reply});
    }
    wake_.notify_all();
  } catch (const ProtocolError& e) {
    reply(errorReply(e.what(), peekRequestId(text)));
  }
}

SharedBytes ViewerSession::latestFrame() const {
  std::lock_guard lock(mutex_);
  return frame_;
}

SessionState ViewerSession::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

std::string ViewerSession::stateJson() const {
  const SessionState s = state();
  return nlohmann::json{{"type", "state"},
                        {"app", s.app},
                        {"running", s.running},
                        {"paused", s.paused},
                        {"iteration", s.iteration},
                        {"totalSteps", s.totalSteps},
                        {"sequence", s.sequence},
                        {"residual", s.residual},
                        {"updatesPerSecond", s.updatesPerSecond},
                        {"lastStepSeconds", s.lastStepSeconds},
                        {"lastFrameSeconds", s.lastFrameSeconds},
                        {"error", s.error}}
      .dump();
}

bool ViewerSession::waitSettled(double seconds) const {
  std::unique_lock lock(mutex_);
  return wake_.wait_for(lock, std::chrono::duration<double>(seconds), [&] {
    return queue_.empty() && !state_.running && (!dirty_ || state_.paused) &&
           stepsRequested_ == 0;
  });
}

void ViewerSession::publish() {
  const Clock::time_point start = Clock::now();
  FrameHeader header;
  std::vector<uint8_t> texels;
  app_->frame(header, texels);
  FrameSink sink;
  SharedBytes bytes;
  {
    std::lock_guard lock(mutex_);
    header.sequence = ++state_.sequence;
    header.iteration = state_.iteration;
    header.residual = static_cast<float>(state_.residual);
    bytes = std::make_shared<const std::vector<uint8_t>>(encodeFrame(header, texels));
    frame_ = bytes;
    sink = sink_;
    state_.lastFrameSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  }
  if (sink) sink(bytes);
}

void ViewerSession::handle(Pending& pending) {
  ClientMessage& message = pending.request.message;
  nlohmann::json reply;
  if (std::holds_alternative<QueryState>(message)) {
    reply = nlohmann::json::parse(stateJson());
  } else if (const auto* probe = std::get_if<Probe>(&message)) {
    nlohmann::json values = nlohmann::json::array();
    for (double v : app_->probe(probe->points))
      values.push_back(std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr));
    reply = {{"type", "probe"}, {"values", values}};
  } else if (std::holds_alternative<Save>(message)) {
    if (options_.savePath.empty())
      throw InvalidInputError("saving is off: start `texgrad view` with --out PATH");
    app_->save(options_.savePath);
    reply = {{"type", "saved"}, {"path", options_.savePath.string()}};
  } else if (const auto* run = std::get_if<Run>(&message); run && run->action != RunAction::Reset) {
    std::lock_guard lock(mutex_);
    if (run->action == RunAction::Start) {
      state_.paused = false;
      dirty_ = true;
      iterationLimit_ = state_.iteration + static_cast<uint32_t>(options_.maxIterations);
    } else if (run->action == RunAction::Pause) {
      state_.paused = true;
    } else {
      state_.paused = true;
      ++stepsRequested_;
    }
    reply = okReply("run");
  } else {
    app_->apply(message);
    std::lock_guard lock(mutex_);
    dirty_ = true;
    state_.iteration = 0;
    iterationLimit_ = static_cast<uint32_t>(options_.maxIterations);
    reply = okReply("change");
  }
  if (pending.request.id >= 0) reply["id"] = pending.request.id;
  pending.reply(reply.dump());
}

void ViewerSession::run() {
  Clock::time_point nextFrame = Clock::now();
  Clock::time_point lastStep{};
  bool wasStepping = false;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / options_.maxUpdatesPerSecond));
  for (;;) {
    std::deque<Pending> batch;
    {
      std::unique_lock lock(mutex_);
      const auto busy = [&] { return (!state_.paused && dirty_) || stepsRequested_ > 0; };
      if (queue_.empty() && !busy()) {
        state_.running = false;
        wake_.notify_all();
      }
      wake_.wait(lock, [&] { return stopping_ || !queue_.empty() || busy(); });
      if (stopping_) return;
      batch.swap(queue_);
    }
    for (Pending& p : batch) {
      try {
        handle(p);
      } catch (const std::exception& e) {
        p.reply(errorReply(e.what(), p.request.id));
      }
    }
    {
      std::unique_lock lock(mutex_);
      const bool step = (!state_.paused && dirty_) || stepsRequested_ > 0;
      if (!step) {
        state_.running = false;
        wasStepping = false;
        wake_.notify_all();
        continue;
      }
      if (stepsRequested_ > 0) --stepsRequested_;
      state_.running = true;
      wake_.wait_until(lock, nextFrame, [&] { return stopping_; });
      if (stopping_) return;
    }
    nextFrame = Clock::now() + period;
    const Clock::time_point t0 = Clock::now();
    StepResult result;
    try {
      result = app_->step();
    } catch (const std::exception& e) {
      std::lock_guard lock(mutex_);
      state_.paused = true;  // a failed solve (e.g. not positive definite) stops refinement
      state_.error = e.what();
      continue;
    }
    const Clock::time_point t1 = Clock::now();
    {
      std::lock_guard lock(mutex_);
      ++state_.iteration;
      ++state_.totalSteps;
      state_.residual = result.residual;
      state_.lastStepSeconds = std::chrono::duration<double>(t1 - t0).count();
      if (wasStepping) {
        const double rate =
            1.0 / std::max(1e-9, std::chrono::duration<double>(t1 - lastStep).count());
        state_.updatesPerSecond =
            state_.updatesPerSecond == 0.0
                ? rate
                : (1.0 - kRateSmoothing) * state_.updatesPerSecond + kRateSmoothing * rate;
      }
      if (result.settled || state_.iteration >= iterationLimit_)
        dirty_ = false;
    }
    lastStep = t1;
    wasStepping = true;
    publish();
  }
}

}  // namespace texgrad::viewer
