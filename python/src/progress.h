// Progress, Ctrl-C and the GIL around library calls from Python: the library runs with the GIL
// released and calls back into Python (a `progress=` callable, pending signals) at its stages.
#pragma once

#include <pybind11/pybind11.h>

#include <utility>

#include "texgrad/core/progress.h"

namespace texgrad::python {

namespace py = pybind11;

/// Bridges a Python `progress(stage, fraction)` callable (or None) to a ProgressCallback. At each
/// report, with the GIL taken: pending signals are handled (PyErr_CheckSignals: a Ctrl-C raises
/// KeyboardInterrupt there), then the callable is called; a raised exception, or a callable
/// returning False, cancels the stage (the callback returns false, the library throws Cancelled).
class PythonProgress {
 public:
  /// `callable` may be None (only signals are checked).
  explicit PythonProgress(py::object callable) : callable_(std::move(callable)) {}
  PythonProgress(const PythonProgress&) = delete;
  PythonProgress& operator=(const PythonProgress&) = delete;

  /// The callback to pass to the library; valid while this object lives.
  ProgressCallback callback();

  /// Runs `body` with the GIL released. If the library cancelled (Cancelled), re-raises what
  /// stopped it: the KeyboardInterrupt or the callable's exception, else texgrad.Cancelled.
  template <typename Body>
  auto run(Body&& body) {
    try {
      py::gil_scoped_release release;
      return body();
    } catch (const Cancelled&) {
      raiseCancellation();
    }
  }

 private:
  /// Restores the stored Python error (or raises texgrad.Cancelled); never returns.
  [[noreturn]] void raiseCancellation();

  py::object callable_;
  py::object errorType_, errorValue_, errorTrace_;  ///< first error a callback saw
};

/// Runs `body` with the GIL released and signals checked at every progress report of the library.
template <typename Body>
auto withProgress(const py::object& callable, Body&& body) {
  PythonProgress progress(callable);
  const ProgressCallback callback = progress.callback();
  return progress.run([&] { return body(callback); });
}

}  // namespace texgrad::python
