// Progress and cancellation callback passed to long library stages (no printing in the library).
#pragma once

#include <functional>
#include <string_view>

namespace texgrad {

/// Called with a stage name and a fraction in [0, 1]; returning false asks the stage to cancel.
using ProgressCallback = std::function<bool(std::string_view stage, double fraction)>;

/// Thrown by a stage whose ProgressCallback returned false.
class Cancelled : public std::exception {
 public:
  const char* what() const noexcept override { return "operation cancelled"; }
};

/// Reports progress if a callback is set and throws Cancelled if it asks to stop.
inline void reportProgress(const ProgressCallback& callback, std::string_view stage,
                           double fraction) {
  if (callback && !callback(stage, fraction)) throw Cancelled();
}

}  // namespace texgrad
