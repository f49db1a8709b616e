#pragma once
// yaml_document.hpp: a Python value (dicts, lists, tuples, NumPy arrays, strings, numbers, booleans, None) as the
// YAML document a scene file would hold, so that a scene built in Python is read by fbsim's own scene reader: the
// same keys, the same checks, the same messages (without line numbers: the nodes come from no file).

#include <pybind11/pybind11.h>
#include <yaml-cpp/yaml.h>

namespace flexbody::python {

/// `value` as a YAML node; a float keeps all its digits (the shortest text that reads back as the same double).
/// Throws pybind11::type_error naming a value of another type (a function, an object).
[[nodiscard]] YAML::Node yaml_document(pybind11::handle value);

}  // namespace flexbody::python
