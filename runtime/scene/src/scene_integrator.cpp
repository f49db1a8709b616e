// A scene's integrator settings (the `integrator` key, and --end): scene_parts.hpp's read_integrator.
#include "flexbody/scene/scene.hpp"
#include "scene_parts.hpp"

#include "flexbody/format/yaml_reader.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <utility>

namespace flexbody::scene {
namespace {

// step: auto (error control): error_tolerance [m] required; the output interval, initial_step and max_step [s]
// defaulted from the end time and the output interval (scene.hpp, kAutoRows), min_step by the integrator.
void read_error_control(const format::YamlReader& r, const YAML::Node& integrator, Scene& scene) {
  runtime::GeneralizedAlphaOptions& o = scene.integrator;
  const YAML::Node tolerance = integrator["error_tolerance"];
  if (!tolerance)
    r.fail(integrator["step"], "integrator step: auto needs error_tolerance, the local position error allowed per step "
                               "in metres (a rotation's counts at the body's radius of gyration)");
  o.error_tolerance = r.positive(tolerance, "integrator error_tolerance [m]");
  if (!scene.output_interval) scene.output_interval = scene.end_time / kAutoRows;  // rows by time
  const double interval = *scene.output_interval;
  o.max_step = scene.end_time / kAutoLongestSteps;
  if (const YAML::Node longest = integrator["max_step"]) {
    o.max_step = r.positive(longest, "integrator max_step");
    if (o.max_step > scene.end_time)
      r.fail(longest, fmt::format("integrator max_step {} s is larger than the end time {} s", o.max_step, scene.end_time));
  }
  o.step = std::min(o.max_step, interval) / kAutoFirstStepDivisor;
  if (const YAML::Node first = integrator["initial_step"]) {
    o.step = r.positive(first, "integrator initial_step");
    if (o.step > o.max_step)
      r.fail(first, fmt::format("integrator initial_step {} s is larger than max_step {} s", o.step, o.max_step));
  }
}

}  // namespace

void read_integrator(const format::YamlReader& r, const YAML::Node& root, const SceneOverrides& overrides,
                     Scene& scene) {
  const YAML::Node integrator = r.required(root, "integrator", "the scene");
  r.expect_map(integrator, "integrator",
               {"type", "rho_inf", "step", "min_step", "error_tolerance", "initial_step", "max_step", "end", "tolerance", "max_iterations", "output_every", "output_interval",
                "deformation_limit",
                "spin_warning", "spin_limit", "stiffened_spin_warning", "stiffened_spin_limit", "constraints",
                "linear_solver", "coupled_step"});
  if (const YAML::Node t = integrator["type"]; t && r.text(t, "integrator type") != "generalized-alpha")
    r.fail(t, fmt::format("integrator type '{}' is unknown; use generalized-alpha", t.Scalar()));
  if (const YAML::Node rho = integrator["rho_inf"]) scene.integrator.rho_infinity = r.number(rho, "integrator rho_inf");
  const YAML::Node step = r.required(integrator, "step", "integrator");
  const bool automatic = step.IsScalar() && step.Scalar() == "auto";
  scene.step_at = r.at(step);
  scene.outputs_at = integrator["output_every"]      ? r.at(integrator["output_every"])
                      : integrator["output_interval"] ? r.at(integrator["output_interval"])
                                                      : key_at(r, root, "integrator");
  scene.end_time = r.positive(r.required(integrator, "end", "integrator"), "integrator end");
  if (overrides.end_time) {
    if (!(*overrides.end_time > 0.0) || !std::isfinite(*overrides.end_time))
      throw std::invalid_argument(fmt::format("--end must be a positive time in seconds, got {}", *overrides.end_time));
    scene.end_time = *overrides.end_time;
  }
  read_cadence(r, integrator, "integrator", "output_every", "output_interval", automatic, scene.output_every,
               scene.output_interval);
  if (automatic) {
    read_error_control(r, integrator, scene);
  } else {
    for (const char* key : {"error_tolerance", "initial_step", "max_step"})
      if (const YAML::Node given = integrator[key])
        r.fail(given, fmt::format("integrator {} is for step: auto (error control); this scene's step is fixed", key));
    if (step.IsScalar() && !step.Scalar().empty() && std::isalpha(static_cast<unsigned char>(step.Scalar()[0])))
      r.fail(step, fmt::format("integrator step must be a time in seconds or auto, got '{}'", step.Scalar()));
    scene.integrator.step = r.positive(step, "integrator step");
    if (overrides.end_time && scene.integrator.step > *overrides.end_time)
      throw std::invalid_argument(fmt::format("--end {} s is shorter than the scene's integrator step {} s",
                                              *overrides.end_time, scene.integrator.step));
    if (scene.integrator.step > scene.end_time)
      r.fail(step, fmt::format("integrator step {} s is larger than the end time {} s", scene.integrator.step,
                               scene.end_time));
    if (const double steps = step_count(scene.end_time, scene.integrator.step); !(steps <= kMostSteps))
      r.fail(step, fmt::format("integrator step {} s would take {:.3g} steps to the end time {} s{}; at most {:.0e} are "
                               "allowed (is the step meant to be that small?)", scene.integrator.step, steps,
                               scene.end_time, overrides.end_time ? " (--end)" : "", kMostSteps));
  }
  if (const YAML::Node floor = integrator["min_step"])
    scene.integrator.min_step = r.positive(floor, "integrator min_step");
  if (const YAML::Node tol = integrator["tolerance"])
    scene.integrator.tolerance = r.positive(tol, "integrator tolerance");
  const std::pair<const char*, double*> levels[] = {
      {"spin_warning", &scene.integrator.spin_warning},
      {"spin_limit", &scene.integrator.spin_limit},
      {"stiffened_spin_warning", &scene.integrator.stiffened_spin_warning},
      {"stiffened_spin_limit", &scene.integrator.stiffened_spin_limit},
      {"deformation_limit", &scene.integrator.deformation_limit}};
  for (const auto& [key, level] : levels)
    if (const YAML::Node given = integrator[key]) *level = r.number(given, fmt::format("integrator {}", key));
  if (const YAML::Node form = integrator["constraints"]) {
    const std::string f = r.text(form, "integrator constraints");
    if (f == "stabilized-index2")
      scene.integrator.constraints = runtime::ConstraintForm::stabilized_index2;
    else if (f == "index3")
      scene.integrator.constraints = runtime::ConstraintForm::index3;
    else
      r.fail(form, fmt::format("integrator constraints '{}' is unknown; use stabilized-index2 (positions and "
                               "velocities, the default) or index3 (positions only)", f));
  }
  if (const YAML::Node solver = integrator["linear_solver"]) {
    const std::string f = r.text(solver, "integrator linear_solver");
    if (f == "auto")
      scene.integrator.reduced_matrix = runtime::ReducedMatrix::automatic;
    else if (f == "dense")
      scene.integrator.reduced_matrix = runtime::ReducedMatrix::dense;
    else if (f == "sparse")
      scene.integrator.reduced_matrix = runtime::ReducedMatrix::sparse;
    else
      r.fail(solver, fmt::format("integrator linear_solver '{}' is unknown; use auto (the default: sparse from {} rows "
                                 "of the reduced Newton matrix), dense or sparse", f, runtime::kSparseFromRows));
  }
  if (const YAML::Node coupled = integrator["coupled_step"]) {
    const std::string f = r.text(coupled, "integrator coupled_step");
    if (f != "on-failure" && f != "always")
      r.fail(coupled, fmt::format("integrator coupled_step '{}' is unknown; use on-failure (the default: the stabilised "
                                  "form's coupled Newton step after a step fails without it) or always", f));
    scene.integrator.coupled_from_start = f == "always";
  }
  if (const YAML::Node it = integrator["max_iterations"]) scene.integrator.max_iterations = r.count(it, "integrator max_iterations");
  // The options' ranges, as the integrator checks them (check_options), at the line of the key that is out of range:
  // under step: auto the step is the initial_step (or a default from the end time: then the line of step).
  if (const std::optional<runtime::OptionProblem> problem = runtime::check_options(scene.integrator)) {
    const char* key =
        problem->option == "step" && automatic && integrator["initial_step"] ? "initial_step" : problem->option.c_str();
    const YAML::Node given = integrator[key];
    r.fail(given ? given : integrator, "integrator " + problem->message);
  }
}

}  // namespace flexbody::scene
