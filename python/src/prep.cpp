// prep.cpp: fbprep's pipeline from Python (flexbody._prep; python/flexbody/prep.py wraps it): a body spec's file, or
// its document built in Python, read by fbprep's own spec reader, run by its pipeline, the report as fbprep --json's
// object.
#include "bindings.hpp"
#include "yaml_document.hpp"

#include "flexbody/preprocess/body_spec.hpp"
#include "flexbody/preprocess/fbprep_pipeline.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <stdexcept>
#include <string>

namespace flexbody::python {
namespace {

namespace py = pybind11;

PyObject* spec_error_type = nullptr;  // flexbody.SpecError (a ValueError), set up by bind_prep

// Runs fbprep on `options` (read from a spec) writing `output`; `warn(line)` gets the mesher's warnings.
std::string run(preprocess::PrepOptions options, const std::filesystem::path& output, const py::object& warn) {
  options.output = output;
  preprocess::record_resolved_options(options);
  if (!warn.is_none()) options.mesh.warning = [&warn](const std::string& line) { warn(line); };
  return preprocess::run_fbprep(options).json();
}

// A spec that fbprep refuses (std::invalid_argument: exit code 2 of the command line) as flexbody.SpecError.
template <class F>
std::string refusing(F&& f) {
  try {
    return f();
  } catch (const std::invalid_argument& e) {
    PyErr_SetString(spec_error_type, e.what());
    throw py::error_already_set();
  }
}

}  // namespace

void bind_prep(py::module_& m) {
  static py::exception<std::invalid_argument> spec_error(m, "SpecError", PyExc_ValueError);
  spec_error_type = spec_error.ptr();
  m.def(
      "_prep_file",
      [](const std::filesystem::path& spec, const std::filesystem::path& output, const py::object& warn) {
        return refusing([&] { return run(preprocess::read_body_spec(spec), output, warn); });
      },
      py::arg("spec"), py::arg("output"), py::arg("warn"));
  m.def(
      "_prep_document",
      [](const py::dict& document, const std::string& source, const std::filesystem::path& base,
         const std::filesystem::path& output, const py::object& warn) {
        const YAML::Node root = yaml_document(document);
        return refusing([&] { return run(preprocess::read_body_spec(root, source, base), output, warn); });
      },
      py::arg("document"), py::arg("source"), py::arg("base"), py::arg("output"), py::arg("warn"));
}

}  // namespace flexbody::python
