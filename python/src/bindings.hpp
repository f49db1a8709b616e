#pragma once
// bindings.hpp: the parts of the flexbody Python module, one function per source file.

#include <pybind11/pybind11.h>

namespace flexbody::python {

void bind_body_file(pybind11::module_& m);   ///< read_body, Body, Interface, OutputRegion, BodyFileError
void bind_simulation(pybind11::module_& m);  ///< _Simulation, _load_scene, _build_scene, SceneError, StepFailure
void bind_prep(pybind11::module_& m);        ///< _prep_file, _prep_document, SpecError (builds with the preprocessor)

}  // namespace flexbody::python
