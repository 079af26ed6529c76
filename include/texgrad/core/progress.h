// Progress and cancellation callback passed to long library stages (no printing in the library).
#pragma once

#include <cstddef>
#include <exception>
#include <functional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

namespace texgrad {

/// One report of a long stage. Within a stage, fraction never decreases and its last report is 1.
struct Progress {
  std::string_view stage;  ///< e.g. "assemble", "solver setup", "solve"
  double fraction = 0.0;   ///< share of the stage done, in [0, 1]
  int step = 0;            ///< iterative stages: V-cycles or CG iterations done (0 otherwise)
  int steps = 0;           ///< iterative stages: the most step can reach (0: not iterative)
};

class ProgressCallback;

namespace detail {
/// Callables ProgressCallback's constructor takes (not ProgressCallback itself: that is copied).
template <typename F>
inline constexpr bool kProgressCallable =
    !std::is_same_v<F, ProgressCallback> &&
    (std::is_invocable_r_v<bool, F&, const Progress&> ||
     std::is_invocable_r_v<bool, F&, std::string_view, double>);
}  // namespace detail

/// Called by long stages with their progress; returning false asks the stage to cancel (it then
/// throws Cancelled). Built from a callable taking (std::string_view stage, double fraction) or
/// one taking (const Progress&) for the step counts too; empty (no reports) by default.
class ProgressCallback {
 public:
  ProgressCallback() = default;
  ProgressCallback(std::nullptr_t) {}  // NOLINT: an empty callback, as std::function's
  /// Wraps a callable bool(const Progress&) or bool(std::string_view stage, double fraction).
  template <typename F, typename = std::enable_if_t<detail::kProgressCallable<F>>>
  ProgressCallback(F f) {  // NOLINT: implicit, so lambdas pass as callbacks
    if (!isSet(f)) return;
    if constexpr (std::is_invocable_r_v<bool, F&, const Progress&>)
      call_ = std::move(f);
    else
      call_ = [g = std::move(f)](const Progress& p) mutable { return g(p.stage, p.fraction); };
  }

  /// True when a callable is set.
  explicit operator bool() const { return static_cast<bool>(call_); }
  /// Passes one report on (the callback must be set); false asks to cancel.
  bool operator()(const Progress& progress) const { return call_(progress); }
  /// Passes a report without step counts on.
  bool operator()(std::string_view stage, double fraction) const {
    return call_(Progress{stage, fraction, 0, 0});
  }

 private:
  /// False for an empty std::function or null function pointer given as the callable.
  template <typename F>
  static bool isSet(const F& f) {
    if constexpr (std::is_constructible_v<bool, const F&>) return static_cast<bool>(f);
    return true;
  }
  std::function<bool(const Progress&)> call_;
};

/// Thrown by a stage whose ProgressCallback returned false.
class Cancelled : public std::exception {
 public:
  const char* what() const noexcept override { return "operation cancelled"; }
};

/// Reports progress if a callback is set and throws Cancelled if it asks to stop.
inline void reportProgress(const ProgressCallback& callback, const Progress& progress) {
  if (callback && !callback(progress)) throw Cancelled();
}

/// Reports progress without step counts (see above).
inline void reportProgress(const ProgressCallback& callback, std::string_view stage,
                           double fraction) {
  reportProgress(callback, Progress{stage, fraction, 0, 0});
}

/// A callback that passes every report of `callback` on under the stage name `stage` (a solve
/// inside an app's named stage, e.g. "heat solve"); empty if `callback` is.
inline ProgressCallback renameStage(ProgressCallback callback, std::string stage) {
  if (!callback) return {};
  return [inner = std::move(callback), name = std::move(stage)](const Progress& p) {
    Progress renamed = p;
    renamed.stage = name;
    return inner(renamed);
  };
}

}  // namespace texgrad
