// simulation.cpp: scenes and their runs from Python (flexbody._Simulation, made by _load_scene and _build_scene;
// python/flexbody/scene.py wraps them). A scene is read by fbsim's own reader (flexbody::scene) from its file or from
// the document a flexbody.Scene builds; forces that are Python functions of t are added through the scene's builder.
#include "bindings.hpp"
#include "yaml_document.hpp"

#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/scene/scene.hpp"
#include "flexbody/scene/simulation.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace flexbody::python {
namespace {

namespace py = pybind11;

// The Python objects a simulation's C++ side calls: its forces' functions and the warning callback. They live here,
// not in the std::functions of the System, so that Python's garbage collector sees them (tp_traverse) and can break
// a cycle through them (a controller's function that holds the simulation); the functions hold this by shared_ptr.
struct PythonCallables {
  std::vector<py::object> functions;
  bool cleared = false;  // by the collector: the simulation is being torn down
};

// `value` as 3 numbers (a list, a tuple, an array); `where` names it in the error.
Eigen::Vector3d vector3_of(const py::handle value, const std::string& where) {
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!array || array.size() != 3)
    throw std::invalid_argument(fmt::format("{} must be 3 numbers, got {}", where, py::repr(value).cast<std::string>()));
  return {array.at(0), array.at(1), array.at(2)};
}

// A force or torque whose value is a Python function of t [s] returning 3 numbers (N or N m, global axes).
std::function<Eigen::Vector3d(double)> python_load(std::shared_ptr<PythonCallables> callables, py::object function,
                                                   std::string where) {
  const std::size_t index = callables->functions.size();
  callables->functions.push_back(std::move(function));
  return [callables, index, where = std::move(where)](double t) -> Eigen::Vector3d {
    if (callables->cleared) throw std::runtime_error(where + ": its function was released with the simulation");
    const py::object value = callables->functions[index](t);  // a Python exception passes as error_already_set
    const std::string what = fmt::format("{}: the function's value at t = {} s", where, t);
    Eigen::Vector3d f;
    try {
      f = vector3_of(value, what);
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
    // Caught here, not as a singular start or a failed step far from its cause.
    if (!f.allFinite()) throw py::value_error(fmt::format("{} is not finite: {}", what, py::repr(value).cast<std::string>()));
    return f;
  };
}

// A marker given as a scene file gives it (body and one of interface, point, node), from the scene's builder.
runtime::Marker marker_of(const runtime::SceneBuilder& builder, const std::string& body, const py::dict& at,
                          const std::string& where) {
  const int given = static_cast<int>(at.contains("interface")) + static_cast<int>(at.contains("point")) +
                    static_cast<int>(at.contains("node"));
  if (given != 1) throw std::invalid_argument(where + " needs exactly one of interface, point, node");
  try {
    if (at.contains("interface")) return builder.interface(body, at["interface"].cast<std::string>());
    if (at.contains("point")) return builder.point(body, vector3_of(at["point"], where + " point"));
    return builder.node(body, at["node"].cast<Eigen::Index>());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where + ": " + e.what());
  }
}

// flexbody.SceneError (a ValueError): a scene refused with its one line (set up by bind_simulation).
PyObject* scene_error_type = nullptr;

class PythonSimulation {
 public:
  PythonSimulation(scene::Scene scene, std::shared_ptr<PythonCallables> callables,
                   const std::optional<std::filesystem::path>& directory, py::object warn)
      : callables_(std::move(callables)) {
    const std::size_t warn_index = callables_->functions.size();
    callables_->functions.push_back(std::move(warn));
    auto warning = [callables = callables_, warn_index](const std::string& line) {
      if (!callables->cleared && !callables->functions[warn_index].is_none()) callables->functions[warn_index](line);
    };
    simulation_ = std::make_unique<scene::Simulation>(std::move(scene), scene::OutputSinks{directory, true}, warning);
  }

  void step() {
    const Busy busy(*this);
    simulation_->step();
  }

  // To `end`, calling `progress(t)` every 100 steps; Ctrl-C stops the run there (KeyboardInterrupt), at the last
  // completed step.
  void run(double end, const py::object& progress) {
    const Busy busy(*this);
    try {
      simulation_->run(end, [&progress](double t) {
        // The KeyboardInterrupt stays Python's pending error until the run has stopped (termination: stopped).
        if (PyErr_CheckSignals() != 0) throw scene::RunInterrupted("KeyboardInterrupt");
        if (progress.is_none()) return;
        try {
          progress(t);
        } catch (py::error_already_set& e) {  // Ctrl-C while the function ran: a stop too
          if (!e.matches(PyExc_KeyboardInterrupt)) throw;
          e.restore();
          throw scene::RunInterrupted("KeyboardInterrupt");
        }
      });
    } catch (const scene::RunInterrupted&) {
      throw py::error_already_set();
    } catch (const std::invalid_argument& e) {  // an end before the time, or too many steps ahead
      throw py::value_error(e.what());
    }
  }

  [[nodiscard]] double time() const { return simulation_->time(); }
  [[nodiscard]] double end_time() const { return simulation_->scene().end_time; }
  [[nodiscard]] std::vector<std::string> bodies() const {
    std::vector<std::string> names;
    for (int b = 0; b < simulation_->scene().system.body_count(); ++b) names.push_back(simulation_->scene().system.body_name(b));
    return names;
  }

  [[nodiscard]] py::dict state() const {
    const runtime::IntegratorState s = simulation_->state();
    py::dict d;
    d["t"] = s.time;
    d["q"] = s.q;
    d["v"] = s.v;
    d["qdd"] = s.qdd;
    d["a"] = s.a;
    d["lambda"] = s.lambda;
    d["nu"] = s.nu;
    return d;
  }

  void set_state(const py::dict& d) {
    const Busy busy(*this);
    try {
      set_entries(d);
    } catch (const std::invalid_argument& e) {  // a size that is not the system's, a non-finite value
      throw py::value_error(e.what());
    }
  }

  void set_entries(const py::dict& d) {
    static constexpr const char* kKeys[] = {"t", "q", "v", "qdd", "a", "lambda", "nu"};
    for (const auto& [key, value] : d) {
      const std::string k = py::str(key);
      if (std::find(std::begin(kKeys), std::end(kKeys), k) == std::end(kKeys))
        throw py::key_error(fmt::format("set_state: unknown entry '{}' (a state has t, q, v, qdd, a, lambda, nu)", k));
    }
    runtime::IntegratorState s = simulation_->state();  // entries not given stay as they are
    if (d.contains("t")) s.time = d["t"].cast<double>();
    auto take = [&d](const char* key, Eigen::VectorXd& into) {
      if (d.contains(key)) into = d[key].cast<Eigen::VectorXd>();
    };
    take("q", s.q);
    take("v", s.v);
    take("qdd", s.qdd);
    take("a", s.a);
    take("lambda", s.lambda);
    take("nu", s.nu);
    simulation_->set_state(s);
  }

  [[nodiscard]] std::string summary_json(const std::string& source) const { return scene::summary_json(*simulation_, source); }

  // (name, columns, times (n,), values (n, c)) per output, copies of the rows so far.
  [[nodiscard]] py::list tables() const {
    py::list out;
    for (const scene::OutputTable& t : simulation_->tables()) {
      const auto rows = static_cast<py::ssize_t>(t.times.size());
      const auto columns = static_cast<py::ssize_t>(t.columns.size());
      py::array_t<double> times(rows);
      std::copy(t.times.begin(), t.times.end(), times.mutable_data());
      py::array_t<double> values({rows, columns});
      std::copy(t.values.begin(), t.values.end(), values.mutable_data());
      out.append(py::make_tuple(t.name, t.columns, times, values));
    }
    return out;
  }

  // The garbage collector's view of the Python objects held (see PythonCallables).
  int traverse(visitproc visit, void* arg) const {
    for (const py::object& f : callables_->functions) Py_VISIT(f.ptr());
    return 0;
  }
  void clear() {
    callables_->cleared = true;
    std::vector<py::object> released;
    released.swap(callables_->functions);  // released here, after the simulation no longer refers to them
  }

 private:
  // A step, a run or a set_state in progress: a force's function that calls one of them would step the integrator
  // inside its own step.
  class Busy {
   public:
    explicit Busy(PythonSimulation& s) : s_(s) {
      if (s_.busy_) throw std::runtime_error("step, run and set_state cannot be called from a force's function while "
                                             "its simulation is stepping");
      s_.busy_ = true;
    }
    ~Busy() { s_.busy_ = false; }
    Busy(const Busy&) = delete;
    Busy& operator=(const Busy&) = delete;

   private:
    PythonSimulation& s_;
  };

  std::shared_ptr<PythonCallables> callables_;
  std::unique_ptr<scene::Simulation> simulation_;
  bool busy_ = false;
};

// A scene from its file, or from the document a flexbody.Scene built (`loads`: (name, body, marker dict, force
// function or None, torque function or None) per force that is a function of t).
std::unique_ptr<PythonSimulation> simulate(const std::function<scene::Scene(const scene::SceneExtras&)>& read,
                                           const py::list& loads, const std::optional<std::filesystem::path>& directory,
                                           const py::object& warn) {
  auto callables = std::make_shared<PythonCallables>();
  auto extras = [&loads, &callables](runtime::SceneBuilder& builder) {
    for (const py::handle item : loads) {
      const auto load = item.cast<py::tuple>();
      const std::string where = fmt::format("force '{}'", load[0].cast<std::string>());
      const runtime::Marker at = marker_of(builder, load[1].cast<std::string>(), load[2].cast<py::dict>(), where);
      if (!load[3].is_none()) builder.add_force(at, python_load(callables, load[3].cast<py::object>(), where + " force"));
      if (!load[4].is_none()) builder.add_torque(at, python_load(callables, load[4].cast<py::object>(), where + " torque"));
    }
  };
  try {
    scene::Scene scene = read(extras);
    return std::make_unique<PythonSimulation>(std::move(scene), std::move(callables), directory, warn);
  } catch (const std::invalid_argument& e) {  // the scene's one line: the reader's, the builder's or the integrator's
    PyErr_SetString(scene_error_type, e.what());
    throw py::error_already_set();
  }
}

}  // namespace

void bind_simulation(py::module_& m) {
  static py::exception<std::invalid_argument> scene_error(m, "SceneError", PyExc_ValueError);
  scene_error_type = scene_error.ptr();
  static py::exception<runtime::StepFailure> step_failure(m, "StepFailure", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const runtime::StepFailure& e) {
      step_failure(e.what());
    }
  });

  py::class_<PythonSimulation>(m, "_Simulation", py::custom_type_setup([](PyHeapTypeObject* heap_type) {
                                 auto* type = &heap_type->ht_type;
                                 type->tp_flags |= Py_TPFLAGS_HAVE_GC;
                                 type->tp_traverse = [](PyObject* self, visitproc visit, void* arg) {
#if PY_VERSION_HEX >= 0x03090000
                                   Py_VISIT(Py_TYPE(self));
#endif
                                   auto* instance = reinterpret_cast<py::detail::instance*>(self);
                                   if (!instance->get_value_and_holder().holder_constructed()) return 0;
                                   return py::cast<const PythonSimulation&>(py::handle(self)).traverse(visit, arg);
                                 };
                                 // pybind11 2.10 deallocates without untracking the object from the
                                 // collector (2.11 does, pybind11 PR 4461): a collection that a released
                                 // function's finaliser starts must not traverse a half-destroyed simulation.
                                 // (The type inherits pybind11's dealloc at PyType_Ready, after this.)
                                 type->tp_dealloc = [](PyObject* self) {
                                   PyObject_GC_UnTrack(self);
                                   py::detail::pybind11_object_dealloc(self);
                                 };
                                 type->tp_clear = [](PyObject* self) {
                                   auto* instance = reinterpret_cast<py::detail::instance*>(self);
                                   if (instance->get_value_and_holder().holder_constructed())
                                     py::cast<PythonSimulation&>(py::handle(self)).clear();
                                   return 0;
                                 };
                               }))
      .def("step", &PythonSimulation::step)
      .def("run", &PythonSimulation::run, py::arg("end"), py::arg("progress"))
      .def_property_readonly("time", &PythonSimulation::time)
      .def_property_readonly("end_time", &PythonSimulation::end_time)
      .def_property_readonly("bodies", &PythonSimulation::bodies)
      .def("state", &PythonSimulation::state)
      .def("set_state", &PythonSimulation::set_state)
      .def("summary_json", &PythonSimulation::summary_json)
      .def("tables", &PythonSimulation::tables);

  m.def(
      "_load_scene",
      [](const std::filesystem::path& path, std::optional<double> end, std::optional<std::filesystem::path> directory,
         const py::object& warn) {
        scene::SceneOverrides overrides;
        overrides.end_time = end;
        return simulate([&](const scene::SceneExtras&) { return scene::read_scene(path, overrides); }, py::list(),
                        directory, warn);
      },
      py::arg("path"), py::arg("end"), py::arg("directory"), py::arg("warn"));
  m.def(
      "_build_scene",
      [](const py::dict& document, const std::string& source, const std::filesystem::path& base, std::optional<double> end,
         std::optional<std::filesystem::path> directory, const py::list& loads, const py::object& warn) {
        const YAML::Node root = yaml_document(document);
        scene::SceneOverrides overrides;
        overrides.end_time = end;
        return simulate([&](const scene::SceneExtras& extras) { return scene::read_scene(root, source, base, overrides, extras); },
                        loads, directory, warn);
      },
      py::arg("document"), py::arg("source"), py::arg("base"), py::arg("end"), py::arg("directory"), py::arg("loads"),
      py::arg("warn"));
}

}  // namespace flexbody::python
