#include "yaml_document.hpp"

#include <fmt/format.h>

#include <string>

namespace flexbody::python {

namespace py = pybind11;

YAML::Node yaml_document(py::handle value) {
  // A list or dict that holds itself would recurse without end.
  if (Py_EnterRecursiveCall(" while reading a scene or body spec given in Python") != 0) throw py::error_already_set();
  struct Leave {
    ~Leave() { Py_LeaveRecursiveCall(); }
  } leave;
  if (value.is_none()) return YAML::Node(YAML::NodeType::Null);
  if (py::isinstance<py::bool_>(value)) return YAML::Node(value.cast<bool>() ? "true" : "false");
  if (py::isinstance<py::str>(value)) return YAML::Node(value.cast<std::string>());
  if (py::isinstance<py::dict>(value)) {
    YAML::Node map(YAML::NodeType::Map);
    for (const auto& [key, item] : value.cast<py::dict>()) {
      if (!py::isinstance<py::str>(key))
        throw py::type_error(fmt::format("scene keys are strings, not {}", py::repr(key).cast<std::string>()));
      map[key.cast<std::string>()] = yaml_document(item);
    }
    return map;
  }
  if (py::hasattr(value, "tolist") && !py::isinstance<py::float_>(value))  // NumPy arrays and NumPy scalars
    return yaml_document(value.attr("tolist")());
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    YAML::Node sequence(YAML::NodeType::Sequence);
    for (const py::handle item : value) sequence.push_back(yaml_document(item));
    return sequence;
  }
  if (PyIndex_Check(value.ptr())) return YAML::Node(py::str(py::int_(py::reinterpret_borrow<py::object>(value))).cast<std::string>());
  if (py::isinstance<py::float_>(value)) return YAML::Node(fmt::format("{}", value.cast<double>()));
  throw py::type_error(fmt::format("a scene holds numbers, strings, lists and dicts, not {}",
                                   py::repr(value).cast<std::string>()));
}

}  // namespace flexbody::python
