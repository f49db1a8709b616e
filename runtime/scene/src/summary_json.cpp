// The run summary as one JSON object (simulation.hpp: summary_json): fbsim --json prints it, the Python package
// returns it as a dict. docs/scenes.md lists its fields.
#include "flexbody/scene/simulation.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>

namespace flexbody::scene {

std::string summary_json(const Simulation& simulation, const std::string& scene_file) {
  const Scene& scene = simulation.scene();
  const RunSummary summary = simulation.summary();
  nlohmann::ordered_json j;
  j["scene"] = scene_file;
  j["termination"] = termination_name(summary.termination);
  j["termination_message"] = summary.termination_message;
  j["time_s"] = summary.time;
  j["steps"] = summary.steps;
  j["newton_iterations"] = summary.newton_iterations;
  j["newton_matrices"] = summary.newton_matrices;
  j["retried_steps"] = summary.retried_steps;
  j["smallest_step_s"] = summary.smallest_step;
  j["largest_step_s"] = summary.largest_step;
  j["rejected_steps"] = summary.rejected_steps;
  j["steps_above_tolerance"] = summary.steps_above_tolerance;
  j["error_tolerance_m"] = scene.integrator.error_tolerance > 0.0 ? nlohmann::ordered_json(scene.integrator.error_tolerance)
                                                                   : nlohmann::ordered_json(nullptr);
  j["linear_solver"] = summary.sparse ? "sparse" : "dense";
  {
    const runtime::InitialAssemblyReport& a = scene.assembly;
    nlohmann::ordered_json assembly;
    assembly["iterations"] = a.iterations;
    assembly["largest_gap_m"] = a.largest_gap;
    const int moved = a.most_moved();
    assembly["largest_move_m"] = moved >= 0 ? a.moves[static_cast<std::size_t>(moved)] : 0.0;
    assembly["most_moved_body"] = moved >= 0 ? scene.system.body_name(moved) : std::string();
    assembly["moves_m"] = a.moves;
    assembly["deformations_m"] = a.deformations;
    assembly["strain_energy_j"] = a.strain_energy;
    j["assembly"] = assembly;
  }
  {
    nlohmann::ordered_json removed = nlohmann::ordered_json::array();
    for (const runtime::RemovedConstraint& c : scene.removed)
      removed.push_back({{"joint", c.name}, {"row", c.row + 1}, {"meaning", c.meaning}, {"gap", c.gap}});
    j["removed_constraints"] = removed;
  }
  {
    nlohmann::ordered_json stiffened = nlohmann::ordered_json::array();
    for (int b = 0; b < scene.system.body_count(); ++b)
      if (const auto& prestress = scene.system.model(b).prestress) {
        const std::string gap = scene.system.prestress_gap(b);
        stiffened.push_back({{"body", scene.system.body_name(b)}, {"cases", prestress->cases.size()},
                             {"covers_all_loads", gap.empty()}, {"gap", gap}});
      }
    j["geometric_stiffening"] = stiffened;
  }
  j["cpu_s"] = summary.cpu_seconds;
  j["energy_initial_j"] = summary.energy_initial;
  j["energy_final_j"] = summary.energy_final;
  j["energy_drift"] = summary.energy_drift;
  j["max_constraint_residual"] = summary.max_constraint_residual;
  const double steps = std::max(1.0, static_cast<double>(summary.steps));
  j["wall_s"] = summary.wall_seconds;
  j["us_per_step"] = 1e6 * summary.wall_seconds / steps;
  j["integrator_us_per_step"] = 1e6 * summary.integrator_wall_seconds / steps;
  j["conserves_energy"] = scene.conserves.energy;
  j["conserves_angular_momentum"] = scene.conserves.angular_momentum;
  j["energy_growth"] = summary.energy_growth;
  j["angular_momentum_growth"] = summary.angular_momentum_growth;
  j["conservation_warnings"] = summary.conservation_warnings;
  j["validity_warnings"] = summary.validity_warnings;
  j["warnings"] = summary.warnings;
  std::vector<std::string> files;
  for (const auto& f : summary.files) files.push_back(f.string());
  j["outputs"] = files;
  j["output_bytes"] = summary.written_bytes;
  j["output_files"] = summary.written_files;
  j["estimated_output_bytes"] = summary.estimated_bytes;
  j["estimated_output_files"] = summary.estimated_files;
  j["resumed_at_s"] = summary.resumed_at ? nlohmann::ordered_json(*summary.resumed_at) : nlohmann::ordered_json();
  return j.dump();
}

}  // namespace flexbody::scene
