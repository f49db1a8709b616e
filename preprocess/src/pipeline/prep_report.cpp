// PrepSummary::full_report() and json(): what fbprep did, for people and for programs.
#include "flexbody/preprocess/fbprep_pipeline.hpp"
#include "flexbody/preprocess/length_unit.hpp"

#include "flexbody/preprocess/eigen_residual.hpp"

#include "report_text.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace flexbody::preprocess {
namespace {

using detail::vector3;

std::vector<double> to_std(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

// "50 of 6271 after raising the order; gmsh's elastic smoothing left 18; 25 straightened (...)": the straightened
// elements' largest node move bounds how far the mesh left the CAD surface there.
std::string curved_repair_text(const CurvedElementRepair& c, double element_size_m) {
  std::string text = fmt::format("{} of {} after raising the order", c.folded, c.elements);
  if (c.after_elastic >= 0)
    text += fmt::format("; gmsh's elastic smoothing left {}{}", c.after_elastic, c.elastic_message.empty() ? "" : " (it failed)");
  if (c.straightened.elements > 0)
    text += fmt::format("; {} straightened ({} mid-edge nodes moved onto their edges, by up to {:.3g} m: {:.2g} % of "
                        "the element size)", c.straightened.elements, c.straightened.nodes,
                        c.straightened.largest_move_m, 100.0 * c.straightened.largest_move_m / element_size_m);
  return text + fmt::format(" ({:.1f} s)", c.seconds);
}

std::vector<std::vector<double>> to_rows(const Eigen::Matrix3d& m) {
  return {{m(0, 0), m(0, 1), m(0, 2)}, {m(1, 0), m(1, 1), m(1, 2)}, {m(2, 0), m(2, 1), m(2, 2)}};
}

std::string shift_as_frequency(double sigma) {
  return fmt::format("-(2 pi * {:.4g} Hz)^2", std::sqrt(-sigma) / (2.0 * std::numbers::pi));
}

}  // namespace

std::string PrepSummary::accuracy_warning() const {
  if (frequency_errors.size() == 0 || !(frequency_errors(0) > kAccuracyWarning)) return {};
  const std::string amount = std::isfinite(frequency_errors(0))
                                 ? fmt::format("{:.0f} % too high", 100.0 * frequency_errors(0))
                                 : std::string("not resolved at all");
  // A size to try: an eigenvalue's error falls like h^(2p) for elements of order p, so h (e_target / e)^(1/(2p)) with
  // e_target half the warning level, and at least a halving (a thin feature's estimate is pre-asymptotic: RLF_7030's
  // 18 % estimate was 26 % against its refined mesh).
  std::string smaller = "a smaller --mesh-size";
  const std::optional<LengthUnit> in = length_unit_from_string(unit);
  if (mesh_size_m > 0.0 && in && std::isfinite(frequency_errors(0))) {
    const double shrink =
        std::min(0.5, std::pow(0.5 * kAccuracyWarning / frequency_errors(0), 1.0 / (2.0 * element_order)));
    smaller = fmt::format("a smaller --mesh-size (about {:.2g} {}, {:.2g} of this mesh's)",
                          shrink * mesh_size_m / metres_per(*in), unit, shrink);
  }
  return fmt::format("the first frequency ({:.4g} Hz) is likely {} with {} elements at this mesh (estimate from "
                     "the stresses' jumps between elements): {}; where thin leads, ribs or walls carry the mode, "
                     "--thin-features 1 refines them alone", frequencies_hz(0), amount,
                     element_order == 2 ? "quadratic" : "linear",
                     element_order == 2 ? "give " + smaller : "use --order 2, or " + smaller);
}

double PrepSummary::max_residual_to_floor() const {
  const bool free_free = reduction == ReductionKind::free_free;
  const Eigen::VectorXd& residuals = free_free ? relative_residuals : fixed_interface_residuals;
  const Eigen::VectorXd& floors = free_free ? residual_floors : fixed_interface_residual_floors;
  const Eigen::Index checked = free_free ? floors.size() - static_correction_modes : floors.size();
  if (checked <= 0 || residuals.size() < checked) return 0.0;
  return (residuals.head(checked).array() / floors.head(checked).array()).maxCoeff();
}

std::string PrepSummary::full_report() const {
  std::string r;
  auto line = [&r](std::string_view label, const std::string& value) { r += fmt::format("  {:<22}{}\n", label, value); };
  auto factor_description = [this] {
    return factor.processes > 1 ? fmt::format("{} over {} MPI ranks", factor.factor_library, factor.processes)
                                : std::string(factor.factor_library);
  };
  auto residual_check_line = [this] {
    return fmt::format("  {:<22}max residual / rounding floor {:.2g}; accepted: residual <= max({:.0e}, {:g} x "
                       "floor),\n  {:<22}floor = eps (|abs(K) abs(phi)| + lambda |abs(M) abs(phi)|) / |K phi|\n",
                       "residual check", max_residual_to_floor(), kMinResidualBound, kResidualFloorFactor, "");
  };
  r += fmt::format("fbprep {} report\n\n", kFbprepVersion);
  r += "Input\n";
  line("file", fmt::format("{} ({})", input.string(), to_string(format)));
  line("sha256", input_sha256);
  line("length unit", fmt::format("{}: {}", unit, unit_reason));
  if (meshed_here) line("volumes", std::to_string(volumes));
  if (loose_entities[0] + loose_entities[1] + loose_entities[2] > 0)
    line("left out", fmt::format("{} faces, {} curves and {} points beside the solid(s), bounding none: not meshed",
                                 loose_entities[2], loose_entities[1], loose_entities[0]));
  if (sewn_faces > 0)
    line("sewn", fmt::format("the input had no volume: its {} faces were sewn into one closed solid (OpenCASCADE)",
                             sewn_faces));
  if (meshed_here) line("size", fmt::format("{:.4g} m across (bounding-box diagonal)", extent_m));
  if (!size_warning.empty()) line("warning", size_warning);
  r += element_order == 2 ? "\nMesh (quadratic tetrahedra, 10 nodes)\n" : "\nMesh (linear tetrahedra)\n";
  line("source", meshed_here ? fmt::format("gmsh ({}), element size {:.4g} m", to_string(mesher), mesh_size_m)
                             : "tetrahedra read from the .msh");
  if (refined_from_m > 0.0 && first_volume_error)
    line("", fmt::format("(the default {:.4g} m held {:.2f} % of the CAD solid's volume: refined)", refined_from_m,
                         100.0 * (1.0 + *first_volume_error)));
  if (refinement)
    line("", fmt::format("(refined by the error estimate: the first mesh's {} DOFs put the first frequency, {:.4g} Hz, "
                         "{:.1f} % too high, beyond the {:.2g} % target; remeshed where the estimate puts the error, "
                         "{:.3g} tetrahedra planned from {}{})", refinement->first_dofs, refinement->first_frequency_hz,
                         100.0 * refinement->first_estimate, 100.0 * refinement->error_target,
                         refinement->predicted_elements, refinement->first_elements,
                         refinement->budget_bound ? fmt::format(", the budget of {:g} times", kRefinementGrowth)
                                                  : std::string()));
  line("nodes", fmt::format("{}", nodes));
  line("elements", fmt::format("{}", elements));
  line("DOFs", fmt::format("{}", dofs));
  line("surface triangles", element_order == 2 ? fmt::format("{} (each 6-node face as 4)", surface_triangles)
                                              : fmt::format("{}", surface_triangles));
  line("radius ratio", fmt::format("min {:.3f} (element {}), mean {:.3f}; {} below 0.1, {} below 0.3{}",
                                   quality.min_radius_ratio, quality.worst_element, quality.mean_radius_ratio,
                                   quality.below_0_1, quality.below_0_3, element_order == 2 ? " (of the corners)" : ""));
  if (curved_repair && curved_repair->folded > 0) line("folded elements", curved_repair_text(*curved_repair, mesh_size_m));
  if (element_order == 2)
    line("Jacobian ratio", fmt::format("min {:.3f} (element {}): min/max of det J over Gauss points and nodes",
                                       quality.min_jacobian_ratio, quality.worst_jacobian_element));
  line("edge length", fmt::format("{:.4g} .. {:.4g} m", quality.min_edge_m, quality.max_edge_m));
  line("volume", fmt::format("{:.6g} m^3", quality.volume_m3) +
                    (cad_volume_m3 ? fmt::format(" ({:+.2f} % of the CAD solid's {:.6g} m^3)", 100.0 * volume_error(),
                                                 *cad_volume_m3)
                                   : std::string()));
  r += "\nMaterial\n";
  line(material.name, fmt::format("E = {:.4g} Pa, nu = {:.4g}, rho = {:.6g} kg/m^3", material.youngs_modulus,
                                  material.poisson_ratio, material.density));
  r += "\nMass properties (consistent mass: exact for the meshed volume)\n";
  line("mass", fmt::format("{:.6g} kg", mass.mass));
  line("centre of mass", vector3(mass.center_of_mass_input) + " m (input frame)");
  for (int i = 0; i < 3; ++i)
    line(i == 0 ? "inertia about CoM" : "", vector3(mass.inertia_about_com.row(i).transpose()) + (i == 0 ? " kg m^2" : ""));
  if (reduction == ReductionKind::craig_bampton) {
    r += fmt::format("\nCraig-Bampton: fixed-interface modes ({}, shift-invert on {}, sigma = {}, rbe2 interfaces "
                     "clamped)\n", eigensolver, factor_description(), shift_as_frequency(shift));
    r += fmt::format("  {:>4}  {:>16}  {:>14}  {:>14}\n", "mode", "frequency [Hz]", "rel. residual", "rounding floor");
    for (Eigen::Index k = 0; k < fixed_interface_frequencies_hz.size(); ++k)
      r += fmt::format("  {:>4}  {:>16.6f}  {:>14.2e}  {:>14.2e}\n", k + 1, fixed_interface_frequencies_hz(k),
                       fixed_interface_residuals(k), fixed_interface_residual_floors(k));
    r += residual_check_line();
    r += "\nOrthonormalised modes (reduced eigenproblem on fixed-interface + constraint modes, 6 rigid dropped;\n"
         "residual: in the model with the rbe2 patches rigid, the reduction error)\n";
  } else {
    r += fmt::format("\nFree-free modes ({}, shift-invert on {}, sigma = {}, 6 rigid-body modes deflated)\n",
                     eigensolver, factor_description(), shift_as_frequency(shift));
  }
  // Free-free modes have floors; the orthonormalised Craig-Bampton modes' residuals are reduction errors, not
  // rounding, and have none.
  const bool floors = residual_floors.size() == frequencies_hz.size();
  const Eigen::Index first_static = frequencies_hz.size() - static_correction_modes;
  const bool errors = frequency_errors.size() == first_static && first_static > 0;
  r += fmt::format("  {:>4}  {:>16}  {:>14}{}{}\n", "mode", "frequency [Hz]", "rel. residual",
                   floors ? fmt::format("  {:>14}", "rounding floor") : "",
                   errors ? fmt::format("  {:>15}", "mesh error est.") : "");
  for (Eigen::Index k = 0; k < frequencies_hz.size(); ++k)
    r += fmt::format("  {:>4}  {:>16.6f}  {:>14.2e}{}{}{}\n", k + 1, frequencies_hz(k), relative_residuals(k),
                     floors && k < first_static ? fmt::format("  {:>14.2e}", residual_floors(k)) : "",
                     errors && k < first_static ? fmt::format("  {:>14.1f}%", 100.0 * frequency_errors(k)) : "",
                     k >= first_static ? "  static correction (Ritz value)" : "");
  if (reduction == ReductionKind::free_free) r += residual_check_line();
  if (errors)
    line("mesh error estimate", "f_h / f - 1 from the recovered stresses' jump (Zienkiewicz-Zhu)");
  if (const std::string warning = accuracy_warning(); !warning.empty()) line("warning", warning);
  if (!static_loads.empty()) {
    line("static correction", fmt::format("{} unit loads ({}), {} dropped as dependent", static_correction.loads,
                                          fmt::join(static_loads, " "), static_correction.dropped));
    line("", fmt::format("{} preconditioned CG iterations, max static residual {:.1e} ({:.2g} x its rounding floor); "
                         "{}", static_correction.iterations, static_correction.max_relative_residual,
                         static_correction.max_residual_to_floor,
                         reduction == ReductionKind::free_free
                             ? "inertia relief, less the normal modes' part"
                             : "interfaces clamped, in the basis before orthonormalisation"));
  }
  if (!prestress_cases.empty()) {
    line("geometric stiffness", fmt::format("{} prestress cases ({}), inertia relief", prestress_cases.size(),
                                            fmt::join(prestress_cases, " ")));
    line("", fmt::format("{} preconditioned CG iterations, max static residual {:.1e} ({:.2g} x its rounding floor)",
                         prestress.iterations, prestress.max_relative_residual, prestress.max_residual_to_floor));
  }
  if (reduction == ReductionKind::free_free)
    line("rigid-body check", fmt::format("|K r|/(|K| |r|) = {:.1e}, max |r^T M phi| = {:.1e}", rigid_body_residual,
                                         rigid_body_coupling));
  else
    line("rigid-body check", fmt::format("max |r^T M phi| = {:.1e}", rigid_body_coupling));
  if (factor.factor_megabytes > 0.0)  // MUMPS: its analysis and factorization are one step here
    line("factorization", fmt::format("nnz(L) = {:.3g}, {:.3g} GFlop, {:.0f} MB over the ranks; analysis and numeric "
                                      "{:.2f} s", factor.factor_nonzeros, factor.factor_flops * 1e-9,
                                      factor.factor_megabytes, factor.factorize_seconds));
  else
    line("factorization", fmt::format("nnz(L) = {:.3g}, {:.3g} GFlop, about {:.3g} MB; ordering {:.2f} s, "
                                      "numeric {:.2f} s",
                                      factor.factor_nonzeros, factor.factor_flops * 1e-9,
                                      factor.factor_estimate_megabytes, factor.analyze_seconds,
                                      factor.factorize_seconds));
  if (factor.solve_passes < factor.solves)  // block Lanczos: several right-hand sides per pass over the factor
    line("solves", fmt::format("{} in {:.2f} s, {} passes over the factor ({} block steps, {} solver run{})",
                               factor.solves, factor.solve_seconds, factor.solve_passes, restarts, solver_runs,
                               solver_runs == 1 ? "" : "s"));
  else
    line("solves", fmt::format("{} in {:.2f} s ({} Lanczos restarts, {} solver run{})", factor.solves,
                               factor.solve_seconds, restarts, solver_runs, solver_runs == 1 ? "" : "s"));
  r += "\nGCMS constants (Y = [1, X, fields]; G = Y^T M_s Y, K_hat = (fields x I3)^T K (fields x I3))\n";
  line("fields", fmt::format("{} kept of {} (3 per mode), {} dropped as dependent", gcms_fields,
                             gcms_fields + dropped_fields, dropped_fields));
  line("cond(Ups^T M_s Ups)", fmt::format("{:.3g} before", condition_mode_gram_before));
  line("cond(G), scaled", fmt::format("{:.3g} before, {:.3g} after (D^-1/2 G D^-1/2, D = diag G: unit-free)",
                                      condition_mass_scaled_before, condition_mass_scaled_after));
  line("cond(G), SI units", fmt::format("{:.3g} before, {:.3g} after (kg, kg m^2 and 1 mixed: depends on the size)",
                                        condition_mass_before, condition_mass_after));
  if (!interfaces.empty()) {
    r += "\nInterfaces (markers: weighted node average and least-squares rotation of the node set)\n";
    for (const auto& i : interfaces)
      line(i.name, fmt::format("{}, {} nodes, reference point {} m (input frame)", i.coupling, i.nodes,
                               vector3(i.reference_point_input)));
  }
  r += "\nStress recovery (nodal stress modes: xx yy zz xy xz yz per field and direction)\n";
  line("output regions", output_regions_reason);
  for (const auto& region : output_regions) line(region.name, fmt::format("{} nodes", region.nodes));
  r += fmt::format("\n  {:<22}{:>10}  {:>18}\n", "stage", "time [s]", "peak memory [MB]");
  for (const auto& stage : stages) r += fmt::format("  {:<22}{:>10.3f}  {:>18.1f}\n", stage.name, stage.seconds, stage.peak_memory_mb);
  r += fmt::format("  {:<22}{:>10.3f}  {:>18.1f}\n", "total", total_seconds, peak_memory_mb);
  if (factor.processes > 1)
    r += fmt::format("  {:<22}{:>10}  {:>18.1f}  (the largest of MPI ranks 1-{}; the column above is rank 0's)\n",
                     "other ranks", "", factor.other_ranks_peak_megabytes, factor.processes - 1);
  r += "\nOutput\n";
  line("body file", fmt::format("{} ({:.3g} MB)", output.string(), static_cast<double>(output_bytes) / 1e6));
  return r;
}

std::string PrepSummary::json() const {
  nlohmann::ordered_json j;
  j["input"] = input.string();
  j["input_format"] = std::string(to_string(format));
  j["input_sha256"] = input_sha256;
  j["length_unit"] = unit;
  j["length_unit_reason"] = unit_reason;
  j["declared_unit"] = declared_unit.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(declared_unit);
  j["unit_overrides_declared"] = unit_overrides_declared;
  j["volumes"] = volumes;
  j["loose_faces"] = loose_entities[2];
  j["loose_curves"] = loose_entities[1];
  j["loose_points"] = loose_entities[0];
  j["sewn_faces"] = sewn_faces > 0 ? nlohmann::ordered_json(sewn_faces) : nlohmann::ordered_json(nullptr);
  j["extent_m"] = meshed_here ? nlohmann::ordered_json(extent_m) : nlohmann::ordered_json(nullptr);
  j["size_warning"] = size_warning.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(size_warning);
  j["mesh_size_m"] = mesh_size_m;
  j["mesher"] = meshed_here ? nlohmann::ordered_json(std::string(to_string(mesher))) : nlohmann::ordered_json(nullptr);
  j["element_order"] = element_order;
  j["nodes"] = nodes;
  j["elements"] = elements;
  j["dofs"] = dofs;
  j["surface_triangles"] = surface_triangles;
  if (curved_repair) {
    const CurvedElementRepair& c = *curved_repair;
    auto count = [](Eigen::Index n) { return n >= 0 ? nlohmann::ordered_json(n) : nlohmann::ordered_json(nullptr); };
    j["folded_elements"] = {{"after_order_2", c.folded},
                            {"after_gmsh_elastic", count(c.after_elastic)},
                            {"gmsh_message", c.elastic_message},
                            {"straightened_elements", c.straightened.elements},
                            {"straightened_nodes", c.straightened.nodes},
                            {"largest_move_m", c.straightened.largest_move_m},
                            {"seconds", c.seconds}};
  } else {
    j["folded_elements"] = nullptr;
  }
  j["mesh_quality"] = {{"measure", "radius ratio 3 r_in / r_circ"},
                       {"min", quality.min_radius_ratio},
                       {"mean", quality.mean_radius_ratio},
                       {"worst_element", quality.worst_element},
                       {"below_0_1", quality.below_0_1},
                       {"below_0_3", quality.below_0_3},
                       {"min_edge_m", quality.min_edge_m},
                       {"max_edge_m", quality.max_edge_m},
                       {"volume_m3", quality.volume_m3},
                       {"min_jacobian_ratio", quality.min_jacobian_ratio},
                       {"worst_jacobian_element", quality.worst_jacobian_element}};
  j["cad_volume_m3"] = cad_volume_m3 ? nlohmann::ordered_json(*cad_volume_m3) : nlohmann::ordered_json(nullptr);
  j["volume_error"] = cad_volume_m3 ? nlohmann::ordered_json(volume_error()) : nlohmann::ordered_json(nullptr);
  j["mesh_size_refined_from_m"] = refined_from_m > 0.0 ? nlohmann::ordered_json(refined_from_m) : nlohmann::ordered_json(nullptr);
  j["first_volume_error"] = first_volume_error ? nlohmann::ordered_json(*first_volume_error) : nlohmann::ordered_json(nullptr);
  if (refinement)
    j["mesh_refinement"] = {{"error_target", refinement->error_target},
                            {"first_frequency_hz", refinement->first_frequency_hz},
                            {"first_estimate", refinement->first_estimate},
                            {"first_dofs", refinement->first_dofs},
                            {"first_elements", refinement->first_elements},
                            {"predicted_elements", refinement->predicted_elements},
                            {"predicted_share", refinement->predicted_share},
                            {"budget_bound", refinement->budget_bound},
                            {"first_seconds", refinement->first_seconds}};
  else
    j["mesh_refinement"] = nullptr;
  j["material"] = {{"name", material.name},
                   {"E_pa", material.youngs_modulus},
                   {"nu", material.poisson_ratio},
                   {"rho_kgm3", material.density}};
  j["mass_kg"] = mass.mass;
  j["center_of_mass_m"] = {mass.center_of_mass_input(0), mass.center_of_mass_input(1), mass.center_of_mass_input(2)};
  j["inertia_kgm2"] = to_rows(mass.inertia_about_com);
  j["eigensolver"] = eigensolver;
  j["shift_rad2_s2"] = shift;
  j["reduction"] = std::string(to_string(reduction));
  j["frequencies_hz"] = to_std(frequencies_hz);
  j["accuracy_warning"] = accuracy_warning().empty() ? nlohmann::ordered_json(nullptr)
                                                     : nlohmann::ordered_json(accuracy_warning());
  if (frequency_errors.size() > 0) {
    std::vector<double> errors(frequency_errors.data(), frequency_errors.data() + frequency_errors.size());
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const double e : errors) list.push_back(std::isfinite(e) ? nlohmann::ordered_json(e) : nlohmann::ordered_json(nullptr));
    j["frequency_error_estimates"] = list;
  } else {
    j["frequency_error_estimates"] = nullptr;
  }
  j["fixed_interface_frequencies_hz"] = to_std(fixed_interface_frequencies_hz);
  j["relative_residuals"] = to_std(relative_residuals);
  // Over the eigenmodes: static correction modes are Ritz vectors with O(1) residuals by construction.
  const Eigen::Index normal = relative_residuals.size() - static_correction_modes;
  j["max_relative_residual"] = normal > 0 ? relative_residuals.head(normal).maxCoeff() : 0.0;
  // Rounding floors (eigen_residual.hpp) of the eigenmodes that are checked against them: the free-free normal
  // modes (the static corrections' entries too, unchecked), or the fixed-interface modes.
  j["residual_floors"] = to_std(residual_floors);
  j["fixed_interface_relative_residuals"] = to_std(fixed_interface_residuals);
  j["fixed_interface_residual_floors"] = to_std(fixed_interface_residual_floors);
  j["max_residual_to_floor"] = max_residual_to_floor();
  j["residual_acceptance"] = {{"min_bound", kMinResidualBound}, {"floor_factor", kResidualFloorFactor}};
  // The K r check runs with free-free modes only (it is part of that solver): null otherwise.
  j["rigid_body_residual"] = reduction == ReductionKind::free_free ? nlohmann::ordered_json(rigid_body_residual)
                                                                    : nlohmann::ordered_json(nullptr);
  j["rigid_body_coupling"] = rigid_body_coupling;
  j["factor_nonzeros"] = factor.factor_nonzeros;
  j["factor_flops"] = factor.factor_flops;
  j["factor_library"] = factor.factor_library;  // CHOLMOD, or MUMPS for the slepc backend
  // MUMPS's own count of the memory its factorization used, all ranks (null for CHOLMOD).
  j["factor_mb"] = factor.factor_megabytes > 0.0 ? nlohmann::ordered_json(factor.factor_megabytes)
                                                : nlohmann::ordered_json(nullptr);
  // CHOLMOD's size of the factor from its symbolic analysis, before the numeric work (null for MUMPS).
  j["factor_estimate_mb"] = factor.factor_estimate_megabytes > 0.0
                                ? nlohmann::ordered_json(factor.factor_estimate_megabytes)
                                : nlohmann::ordered_json(nullptr);
  j["mpi_ranks"] = factor.processes;
  // peak_memory_mb is rank 0's; this is the largest of the other ranks' (null on one process).
  j["peak_memory_other_ranks_mb"] = factor.processes > 1 ? nlohmann::ordered_json(factor.other_ranks_peak_megabytes)
                                                         : nlohmann::ordered_json(nullptr);
  j["solves"] = factor.solves;
  j["solve_passes"] = factor.solve_passes;  // passes over the factor: fewer than solves with block-lanczos
  // JSON has no infinity: a singular matrix's condition number is written as null.
  auto condition = [](double c) { return std::isfinite(c) ? nlohmann::ordered_json(c) : nlohmann::ordered_json(nullptr); };
  j["gcms_fields"] = gcms_fields;
  j["dropped_fields"] = dropped_fields;
  j["condition_mode_gram_before"] = condition(condition_mode_gram_before);
  j["condition_G_before"] = condition(condition_mass_before);
  j["condition_G_after"] = condition(condition_mass_after);
  j["condition_G_scaled_before"] = condition(condition_mass_scaled_before);
  j["condition_G_scaled_after"] = condition(condition_mass_scaled_after);
  nlohmann::ordered_json interface_list = nlohmann::ordered_json::array();
  for (const auto& i : interfaces)
    interface_list.push_back({{"name", i.name},
                              {"coupling", i.coupling},
                              {"nodes", i.nodes},
                              {"reference_point_m", {i.reference_point_input(0), i.reference_point_input(1),
                                                     i.reference_point_input(2)}}});
  j["interfaces"] = interface_list;
  j["static_loads"] = static_loads;
  j["static_correction"] = {{"loads", static_correction.loads},
                            {"dropped", static_correction.dropped},
                            {"modes", static_correction_modes},
                            {"iterations", static_correction.iterations},
                            {"max_relative_residual", static_correction.max_relative_residual},
                            {"max_residual_to_floor", static_correction.max_residual_to_floor}};
  j["geometric_stiffness_cases"] = prestress_cases;
  j["geometric_stiffness_solves"] = {{"iterations", prestress.iterations},
                                     {"max_relative_residual", prestress.max_relative_residual},
                                     {"max_residual_to_floor", prestress.max_residual_to_floor}};
  nlohmann::ordered_json region_list = nlohmann::ordered_json::array();
  for (const auto& region : output_regions) region_list.push_back({{"name", region.name}, {"nodes", region.nodes}});
  j["output_regions"] = region_list;
  j["output_regions_reason"] = output_regions_reason;
  nlohmann::ordered_json timings, memory;
  for (const auto& stage : stages) {
    timings[stage.name] = stage.seconds;
    memory[stage.name] = stage.peak_memory_mb;
  }
  timings["analyze"] = factor.analyze_seconds;
  timings["factorize"] = factor.factorize_seconds;
  timings["solve"] = factor.solve_seconds;
  timings["total"] = total_seconds;
  j["timings_s"] = timings;
  j["stage_peak_memory_mb"] = memory;
  j["peak_memory_mb"] = peak_memory_mb;
  j["output"] = output.string();
  j["output_bytes"] = output_bytes;
  // Paths need not be UTF-8: replace invalid bytes rather than throw after the body file exists.
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace flexbody::preprocess
