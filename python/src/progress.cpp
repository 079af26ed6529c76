// PythonProgress: the library's progress reports call back into Python with the GIL taken.
#include "progress.h"

#include <string>

namespace texgrad::python {

ProgressCallback PythonProgress::callback() {
  return [this](std::string_view stage, double fraction) {
    py::gil_scoped_acquire acquire;
    if (errorType_) return false;  // already cancelled (e.g. a report from another thread)
    // Runs the Python signal handlers on the main thread: SIGINT's raises KeyboardInterrupt.
    if (PyErr_CheckSignals() != 0) {
      PyObject *type = nullptr, *value = nullptr, *trace = nullptr;
      PyErr_Fetch(&type, &value, &trace);
      errorType_ = py::reinterpret_steal<py::object>(type);
      errorValue_ = py::reinterpret_steal<py::object>(value);
      errorTrace_ = py::reinterpret_steal<py::object>(trace);
      return false;
    }
    if (callable_.is_none()) return true;
    try {
      const py::object answer = callable_(std::string(stage), fraction);
      // Only an explicit False cancels: tqdm.update and most callables return None.
      return !(answer.ptr() == Py_False);
    } catch (py::error_already_set& error) {
      errorType_ = error.type();
      errorValue_ = error.value();
      errorTrace_ = error.trace();
      return false;
    }
  };
}

void PythonProgress::raiseCancellation() {
  if (errorType_) {
    PyErr_Restore(errorType_.release().ptr(), errorValue_.release().ptr(),
                  errorTrace_.release().ptr());
    throw py::error_already_set();
  }
  throw Cancelled();
}

}  // namespace texgrad::python
