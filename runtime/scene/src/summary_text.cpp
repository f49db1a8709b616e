// The run summary as text (simulation.hpp: summary_text): what fbsim prints after a run.
#include "flexbody/scene/simulation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <sstream>

namespace flexbody::scene {

std::string summary_text(const Simulation& simulation, const std::filesystem::path& directory, bool end_checkpoint) {
  const Scene& scene = simulation.scene();
  const RunSummary summary = simulation.summary();
  std::ostringstream out;
  out << fmt::format(
      "fbsim: {} steps, {} Newton iterations ({:.2f} per step), {:.3f} s CPU\n", summary.steps,
      summary.newton_iterations,
      summary.steps ? static_cast<double>(summary.newton_iterations) / static_cast<double>(summary.steps) : 0.0,
      summary.cpu_seconds);
  if (summary.termination != Termination::end_reached)
    out << fmt::format("  ended at t = {:.6g} s: {}{}\n", summary.time, termination_name(summary.termination),
                       summary.termination_message.empty() ? "" : " (" + summary.termination_message + ")");
  if (summary.resumed_at)
    out << fmt::format("  resumed at t = {:.6g} s from {} (the counts are the whole run's)\n", *summary.resumed_at,
                       (directory / kCheckpointFileName).string());
  out << fmt::format("  {} Newton matrices, factorized {}\n", summary.newton_matrices,
                     summary.sparse ? "sparse (KLU)" : "dense");
  if (scene.integrator.error_tolerance > 0.0) {
    out << fmt::format(
        "  step: auto, error tolerance {:.3g} m per step: steps from {:.3g} to {:.3g} s, {} taken "
        "again for their error, {} for Newton\n",
        scene.integrator.error_tolerance, summary.smallest_step, summary.largest_step, summary.rejected_steps,
        summary.retried_steps);
    if (summary.steps_above_tolerance > 0)
      out << fmt::format("  {} steps at min_step = {:.3g} s were accepted above the tolerance\n",
                         summary.steps_above_tolerance, simulation.integrator().min_step());
  } else if (summary.retried_steps > 0) {
    out << fmt::format("  {} steps failed and were taken again in halves; the smallest step was {:.3g} s\n",
                       summary.retried_steps, summary.smallest_step);
  }
  if (const int moved = scene.assembly.most_moved(); scene.assembly.iterations > 0 && moved >= 0)
    out << fmt::format("  assembly: joint gaps up to {:.3g} m closed in {} steps; largest move {:.3g} m (body '{}')\n",
                       scene.assembly.largest_gap, scene.assembly.iterations,
                       scene.assembly.moves[static_cast<std::size_t>(moved)], scene.system.body_name(moved));
  if (const auto& d = scene.assembly.deformations; !d.empty()) {
    // A closed loop that rigid moves could not close deformed its flexible bodies (runtime/initial_assembly.hpp); a
    // share below 1e-3 of the largest move is the ε-share of a gap closed rigidly, not worth a line.
    const auto most = std::max_element(d.begin(), d.end());
    const double largest_move = *std::max_element(scene.assembly.moves.begin(), scene.assembly.moves.end());
    if (*most > 1e-3 * largest_move)
      out << fmt::format("  assembly deformed body '{}' by up to {:.3g} m to close its loop (strain energy {:.3g} J)\n",
                         scene.system.body_name(static_cast<int>(most - d.begin())), *most,
                         scene.assembly.strain_energy);
  }
  for (int b = 0; b < scene.system.body_count(); ++b)
    if (const auto& prestress = scene.system.model(b).prestress) {
      const std::string gap = scene.system.prestress_gap(b);
      out << fmt::format("  body '{}': geometric stiffening on ({} prestress cases){}\n", scene.system.body_name(b),
                         prestress->cases.size(), gap.empty() ? "" : "; " + gap);
    }
  for (std::size_t k = 0; k < scene.removed.size();) {  // one line per joint
    const std::size_t joint = scene.removed[k].joint;
    std::string rows;
    double gap = 0.0;
    for (; k < scene.removed.size() && scene.removed[k].joint == joint; ++k) {
      rows += (rows.empty() ? "" : "; ") + scene.removed[k].meaning;
      gap = std::max(gap, scene.removed[k].gap);
    }
    out << fmt::format("  joint '{}': redundant rows left out ({}): the other joints carry them{}\n",
                       scene.system.joints()[joint].name, rows,
                       gap > 1e-9 ? fmt::format(" (they are off by up to {:.3g} at the start)", gap) : "");
  }
  out << fmt::format("  {:.1f} us per step ({:.1f} in the integrator, the rest checks and outputs)\n",
                     1e6 * summary.wall_seconds / std::max(1.0, static_cast<double>(summary.steps)),
                     1e6 * summary.integrator_wall_seconds / std::max(1.0, static_cast<double>(summary.steps)));
  out << fmt::format("  energy {:.6g} J -> {:.6g} J (drift {:.2e}), max constraint residual {:.2e}\n",
                     summary.energy_initial, summary.energy_final, summary.energy_drift,
                     summary.max_constraint_residual);
  if (!summary.warnings.empty())
    out << fmt::format("  {} warning{} (on stderr)\n", summary.warnings.size(),
                       summary.warnings.size() == 1 ? "" : "s");
  for (const auto& f : summary.files) out << "  wrote " << f.string() << '\n';
  if (end_checkpoint)
    out << fmt::format("  checkpoint {} at t = {:.6g} s\n", (directory / kCheckpointFileName).string(),
                       simulation.time());
  out << fmt::format("  wrote {} in {:.0f} files (estimated before the run: {} in {:.0f})\n",
                     format_size(summary.written_bytes), summary.written_files, format_size(summary.estimated_bytes),
                     summary.estimated_files);
  return out.str();
}

}  // namespace flexbody::scene
