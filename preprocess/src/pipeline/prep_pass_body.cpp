// fbprep's last stages (prep_pass.hpp): the improved GCMS's constant blocks, the stress modes, the body file.
#include "prep_pass.hpp"

#include "flexbody/format/body_file.hpp"
#include "flexbody/preprocess/gcms_constants.hpp"
#include "flexbody/preprocess/geometric_stiffness.hpp"
#include "flexbody/preprocess/stress_recovery.hpp"

#include <fmt/chrono.h>

#include <algorithm>
#include <ctime>
#include <filesystem>

namespace flexbody::preprocess {
namespace {

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  return fmt::format("{:%Y-%m-%dT%H:%M:%SZ}", utc);
}

}  // namespace

// The constant blocks of the improved GCMS: fields, G, K̂ (formulations.md, "The Method": nodal fields and dependent
// fields).
void gcms_stage(PrepPass& pass) {
  const PrepOptions& options = pass.options;
  PrepSummary& summary = pass.summary;
  format::BodyData& body = pass.body;
  if (options.progress) options.progress("GCMS constants (G, K_hat)");
  body.modes.upsilon = upsilon_from_modes(pass.mode_vectors);
  body.gcms = pass.in_stage(
      "gcms", [&] { return gcms_constants(pass.stiffness, pass.scalar_mass, body.mesh.nodes, body.modes.upsilon); });
  summary.gcms_fields = body.gcms.field_count();
  summary.dropped_fields = body.modes.upsilon.cols() - summary.gcms_fields;
  summary.condition_mode_gram_before = body.gcms.condition_mode_gram_before;
  summary.condition_mass_before = body.gcms.condition_mass_before;
  summary.condition_mass_after = body.gcms.condition_mass_after;
  summary.condition_mass_scaled_before = body.gcms.condition_mass_scaled_before.value();
  summary.condition_mass_scaled_after = body.gcms.condition_mass_scaled_after;
  body.interfaces = pass.in_stage("interfaces", [&] {
    std::vector<format::Interface> markers;
    for (const SelectedInterface& s : pass.selected)
      markers.push_back(interface_marker(s.name, s.coupling, s.patch, body.mesh.nodes, body.gcms.fields));
    return markers;
  });
  for (const format::Interface& i : body.interfaces)
    summary.interfaces.push_back(
        {i.name, i.coupling, i.nodes.size(), i.reference_point + summary.mass.center_of_mass_input});
  if (pass.prestress_responses.cols() == 0) return;
  // Ĝ_σ on Y = [1, X̄, Ῡ'], the fields of G.
  if (options.progress) options.progress("geometric stiffness of the prestress cases");
  body.geometric_stiffness.cases = summary.prestress_cases;
  body.geometric_stiffness.matrices = pass.in_stage("geometric stiffness", [&] {
    // The constant field has no gradient: its row and column are exact zeros, the rest is projected on [X̄, Ῡ']
    // (computed, row 0 is round-off whose size relative to the other blocks depends on the units).
    Eigen::MatrixXd y(pass.node_count(), 3 + body.gcms.field_count());
    y << body.mesh.nodes, body.gcms.fields;
    const ImportedMesh& imported = pass.imported;
    const std::vector<Eigen::MatrixXd> projected =
        imported.quadratic
            ? projected_geometric_stiffness(*imported.quadratic, options.material, pass.prestress_responses, y)
            : projected_geometric_stiffness(imported.mesh, options.material, pass.prestress_responses, y);
    std::vector<Eigen::MatrixXd> padded;
    for (const Eigen::MatrixXd& g : projected) {
      padded.push_back(Eigen::MatrixXd::Zero(g.rows() + 1, g.cols() + 1));
      padded.back().bottomRightCorner(g.rows(), g.cols()) = g;
    }
    return padded;
  });
}

// Stress recovery: stress modes of the fields at the output regions' nodes (by default the whole body, or its
// surface, whichever fits kDefaultRecoveryBytes).
void recovery_stage(PrepPass& pass) {
  const PrepOptions& options = pass.options;
  PrepSummary& summary = pass.summary;
  format::BodyData& body = pass.body;
  const Eigen::Index node_count = pass.node_count();
  std::vector<OutputRegionRequest> regions;
  const double bytes_per_node = 8.0 * 6.0 * 3.0 * static_cast<double>(body.gcms.field_count());
  const Eigen::VectorXi surface_nodes = [&] {  // ascending, unique
    std::vector<int> used(body.mesh.surface_triangles.data(),
                          body.mesh.surface_triangles.data() + body.mesh.surface_triangles.size());
    std::sort(used.begin(), used.end());
    used.erase(std::unique(used.begin(), used.end()), used.end());
    return Eigen::VectorXi(Eigen::Map<const Eigen::VectorXi>(used.data(), static_cast<Eigen::Index>(used.size())));
  }();
  const double whole_body_bytes = bytes_per_node * static_cast<double>(node_count);
  const double surface_bytes = bytes_per_node * static_cast<double>(surface_nodes.size());
  if (options.output_regions) {
    regions = *options.output_regions;
    summary.output_regions_reason =
        regions.empty() ? "none: the body spec asks for none" : "as the body spec names them";
  } else if (whole_body_bytes <= kDefaultRecoveryBytes) {
    regions.push_back({"body", std::nullopt});
    summary.output_regions_reason = fmt::format(
        "the whole body by default (its stress modes take {:.3g} MB, at most "
        "{:.0f})",
        whole_body_bytes / 1e6, kDefaultRecoveryBytes / 1e6);
  } else if (surface_bytes <= kDefaultRecoveryBytes) {
    regions.push_back({"surface", std::nullopt, true});
    summary.output_regions_reason = fmt::format(
        "the surface by default (its stress modes take {:.3g} MB; the whole body's would take {:.3g}, at most {:.0f})",
        surface_bytes / 1e6, whole_body_bytes / 1e6, kDefaultRecoveryBytes / 1e6);
  } else {
    summary.output_regions_reason = fmt::format(
        "none: the surface's stress modes would take {:.3g} MB, the whole "
        "body's {:.3g} (default limit {:.0f}); name output_regions in the body "
        "spec",
        surface_bytes / 1e6, whole_body_bytes / 1e6, kDefaultRecoveryBytes / 1e6);
  }
  if (options.progress && !regions.empty())
    options.progress(
        fmt::format("stress modes for {} output region{}", regions.size(), regions.size() == 1 ? "" : "s"));
  const ImportedMesh& imported = pass.imported;
  body.recovery = pass.in_stage("recovery", [&] {
    std::vector<format::RecoveryRegion> recovery;
    for (const OutputRegionRequest& request : regions) {
      format::RecoveryRegion region;
      region.name = request.name;
      if (request.select) {
        region.nodes = select_surface_patch(fmt::format("output region '{}'", request.name),
                                            scaled(*request.select, metres_per(imported.unit)), pass.input_nodes(),
                                            body.mesh.surface_triangles, imported.surfaces)
                           .nodes;
      } else if (request.surface) {
        region.nodes = surface_nodes;
      } else {
        region.nodes = Eigen::VectorXi::LinSpaced(node_count, 0, static_cast<int>(node_count - 1));
      }
      region.stress_modes =
          imported.quadratic ? nodal_stress_modes(*imported.quadratic, options.material, body.gcms.fields, region.nodes)
                             : nodal_stress_modes(imported.mesh, options.material, body.gcms.fields, region.nodes);
      recovery.push_back(std::move(region));
    }
    return recovery;
  });
  for (const format::RecoveryRegion& region : body.recovery)
    summary.output_regions.push_back({region.name, region.nodes.size()});
}

void write_stage(PrepPass& pass) {
  const PrepOptions& options = pass.options;
  PrepSummary& summary = pass.summary;
  format::BodyData& body = pass.body;
  if (options.progress) options.progress("writing " + options.output.string());
  body.provenance.created_by = fmt::format("fbprep {}", kFbprepVersion);
  body.provenance.created_utc = utc_now();
  body.provenance.source_file = options.input.filename().string();
  body.provenance.source_sha256 = summary.input_sha256;
  body.provenance.input_unit = summary.unit;
  body.provenance.unit_reason = summary.unit_reason;
  body.provenance.declared_unit = summary.declared_unit;
  body.provenance.options = options.recorded_options;
  for (auto& [key, value] : body.provenance.options)  // the order an unset option resolved to (gmsh_import.hpp)
    if (key == "element_order" && value == "default") value = fmt::format("{} (default)", summary.element_order);
  body.material = options.material;
  body.mass = summary.mass;
  body.modes.kind = std::string(to_string(options.reduction));
  body.modes.frequencies_hz = summary.frequencies_hz;
  body.modes.relative_residuals = summary.relative_residuals;
  body.modes.fixed_interface_frequencies_hz = summary.fixed_interface_frequencies_hz;
  body.modes.eigensolver = summary.eigensolver;
  body.modes.shift = summary.shift;
  body.modes.static_loads = summary.static_loads;
  body.modes.static_correction_modes = summary.static_correction_modes;
  format::write_body_file(body, options.output);
  summary.output_bytes = std::filesystem::file_size(options.output);
}

}  // namespace flexbody::preprocess
