// module.cpp: the compiled part of the flexbody Python package (flexbody._flexbody); python/flexbody/__init__.py
// re-exports it.
#include "bindings.hpp"

PYBIND11_MODULE(_flexbody, m) {
  m.doc() = "flexbody: flexible multibody bodies from CAD and their simulation (compiled part)";
  m.attr("__version__") = FLEXBODY_PACKAGE_VERSION;
  flexbody::python::bind_body_file(m);
  flexbody::python::bind_simulation(m);
#ifdef FLEXBODY_PYTHON_PREP
  flexbody::python::bind_prep(m);
#endif
}
