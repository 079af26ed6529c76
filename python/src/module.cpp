// The `texgrad._texgrad` extension module: registers each part (errors first, so that every
// later part's exceptions translate).
#include "bindings.h"

PYBIND11_MODULE(_texgrad, m) {
  m.doc() = "texgrad: gradient-domain processing in a texture atlas (native part).";
  m.attr("__version__") = TEXGRAD_VERSION;
  texgrad::python::registerErrors(m);
  texgrad::python::registerMesh(m);
  texgrad::python::registerDomain(m);
  texgrad::python::registerApps(m);
  texgrad::python::registerPages(m);
  texgrad::python::registerInteractive(m);
}
