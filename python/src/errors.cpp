// texgrad's typed exceptions as Python exceptions: each derives from the built-in exception a
// Python user catches for that kind of failure.
#include "texgrad/core/error.h"

#include "bindings.h"
#include "texgrad/core/progress.h"

namespace texgrad::python {
namespace {

/// A new exception class texgrad.<name> deriving from `bases` (a type or a tuple of types).
py::object newException(py::module_& m, const char* name, const char* doc, py::handle bases) {
  const std::string qualified = std::string("texgrad.") + name;
  py::object type = py::reinterpret_steal<py::object>(
      PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr));
  if (!type) throw py::error_already_set();
  m.attr(name) = type;
  return type;
}

}  // namespace

void registerErrors(py::module_& m) {
  // Kept alive by the module attributes; the translator runs while the module is loaded.
  static py::handle invalidInput, io, numerical, unsupported, cancelled;
  invalidInput =
      newException(m, "InvalidInputError", "Bad input (array shape, value, option); a ValueError.",
                   PyExc_ValueError)
          .release();
  io = newException(m, "IoError", "A file could not be read or written; an OSError.", PyExc_OSError)
           .release();
  numerical = newException(m, "NumericalError",
                           "A numerical step failed (e.g. a factorisation); a RuntimeError.",
                           PyExc_RuntimeError)
                  .release();
  // Valid input that uses a feature texgrad does not handle: both a ValueError (the input is
  // refused) and a NotImplementedError.
  const py::tuple unsupportedBases =
      py::make_tuple(py::handle(PyExc_ValueError), py::handle(PyExc_NotImplementedError));
  unsupported = newException(m, "UnsupportedError",
                             "Input texgrad does not handle; a ValueError and NotImplementedError.",
                             unsupportedBases)
                    .release();
  cancelled = newException(m, "Cancelled", "A progress callback returned False.", PyExc_Exception)
                  .release();
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const InvalidInputError& e) {
      PyErr_SetString(invalidInput.ptr(), e.what());
    } catch (const IoError& e) {
      PyErr_SetString(io.ptr(), e.what());
    } catch (const NumericalError& e) {
      PyErr_SetString(numerical.ptr(), e.what());
    } catch (const UnsupportedError& e) {
      PyErr_SetString(unsupported.ptr(), e.what());
    } catch (const Error& e) {
      PyErr_SetString(PyExc_RuntimeError, e.what());
    } catch (const Cancelled& e) {
      PyErr_SetString(cancelled.ptr(), e.what());
    }
  });
}

}  // namespace texgrad::python
