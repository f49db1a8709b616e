#pragma once
// run.hpp: integrates a scene and writes what it asks for (one CSV per output, monitors.csv on request).

#include "scene.hpp"

#include <filesystem>
#include <functional>
#include <string>

namespace flexbody::fbsim {

struct RunSummary {
  long steps = 0;
  long newton_iterations = 0;
  double cpu_seconds = 0.0;
  double energy_initial = 0.0, energy_final = 0.0;
  /// max_t |E(t) − E_0| / max_t (kinetic + elastic + spring energy): meaningful for conservative scenes (no
  /// applied forces, torques or damping, whose work it does not count).
  double energy_drift = 0.0;
  double max_constraint_residual = 0.0;  ///< max over the steps of |Φ|∞
  std::vector<std::filesystem::path> files;
};

/// Runs the scene to its end time, writing into `directory` (created). Throws runtime::StepFailure (after
/// writing every completed step) when a step fails.
RunSummary run_scene(Scene& scene, const std::filesystem::path& directory,
                     const std::function<void(double)>& progress = {});

}  // namespace flexbody::fbsim
