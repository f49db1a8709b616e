#include "flexbody/preprocess/fbprep_pipeline.hpp"
#include "flexbody/preprocess/error_estimate.hpp"
#include "refinement_pass.hpp"

#include "flexbody/format/body_file.hpp"
#include "flexbody/format/file_digest.hpp"
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/eigensolver.hpp"
#include "flexbody/preprocess/gcms_constants.hpp"
#include "flexbody/preprocess/geometric_stiffness.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"
#include "flexbody/preprocess/stress_recovery.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <ctime>

namespace flexbody::preprocess {
namespace {

using Clock = std::chrono::steady_clock;

class StageTimer {
 public:
  StageTimer(PrepSummary& summary, std::string name) : summary_(summary), name_(std::move(name)), start_(Clock::now()) {}
  void stop() {
    summary_.stages.push_back({name_, std::chrono::duration<double>(Clock::now() - start_).count(), peak_memory_mb()});
  }

 private:
  PrepSummary& summary_;
  std::string name_;
  Clock::time_point start_;
};

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  return fmt::format("{:%Y-%m-%dT%H:%M:%SZ}", utc);
}

void check_output_location(const PrepOptions& options) {
  const std::filesystem::path& output = options.output;
  if (output.empty()) throw std::invalid_argument("no output file given (-o FILE.fbh5)");
  // The same file by any path (a symbolic or hard link, a relative path): writing would replace it.
  for (const auto& [input, what] : {std::pair{options.input, "the input"}, std::pair{options.spec, "the body spec"}}) {
    std::error_code same;
    if (!input.empty() && std::filesystem::equivalent(input, output, same))
      throw std::invalid_argument(fmt::format("{}: the output would overwrite {} {}; choose another output (-o)",
                                              output.string(), what, input.string()));
  }
  const std::filesystem::path directory = output.has_parent_path() ? output.parent_path() : ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(directory, ec))
    throw std::invalid_argument(fmt::format("{}: the output directory does not exist", directory.string()));
  if (std::filesystem::is_directory(output, ec))
    throw std::invalid_argument(fmt::format("{}: the output is a directory, not a file", output.string()));
  if (std::filesystem::exists(output, ec) && !std::filesystem::is_regular_file(output, ec))
    throw std::invalid_argument(fmt::format("{}: the output exists and is not a regular file (a device, a pipe or a "
                                            "socket); choose another output (-o)", output.string()));
  if (std::filesystem::exists(output, ec) && !std::filesystem::is_empty(output, ec) &&
      !format::begins_like_body_file(output))
    throw std::invalid_argument(fmt::format(
        "{}: the output exists and is not a body file (it does not begin with a flexbody seal or HDF5's signature); "
        "fbprep replaces only body files: remove it or choose another output (-o)", output.string()));
}

}  // namespace

std::string_view to_string(ReductionKind kind) {
  return kind == ReductionKind::free_free ? "free-free" : "craig-bampton";
}

namespace {

// One pass from the input to the body file. With `refine` (the first pass of a mesh fbprep may refine), a first
// frequency estimated beyond options.error_target stops the pass after the estimate, with the second mesh's sizes in
// *refine and the plan in the returned summary's `refinement`.
PrepSummary run_pass(const PrepOptions& options, std::shared_ptr<const MeshSizeField>* refine) {
  const auto start = Clock::now();
  check_material(options.material);
  check_output_location(options);
  // Refused before any work: a free-free basis cannot honour a rigid tie, and Craig-Bampton needs one.
  const bool any_rbe2 = std::any_of(options.interfaces.begin(), options.interfaces.end(),
                                    [](const InterfaceRequest& i) { return i.coupling == "rbe2"; });
  if (options.reduction == ReductionKind::free_free)
    for (const InterfaceRequest& i : options.interfaces)
      if (i.coupling == "rbe2")
        throw std::invalid_argument(fmt::format(
            "interface '{}': coupling rbe2 ties its nodes rigidly, which changes the modes; free-free modes take "
            "rbe3 interfaces only (use reduction kind craig-bampton for rbe2)", i.name));
  if (options.reduction == ReductionKind::craig_bampton) {
    if (!any_rbe2)
      throw std::invalid_argument("craig-bampton reduction: no rbe2 interface; its constraint modes need at least one");
    if (options.modes.modes < 1 && !(options.modes.fmax_hz > 0.0))
      throw std::invalid_argument("craig-bampton reduction: give the number of fixed-interface modes (modes) or fmax");
  }
  PrepSummary summary;
  summary.input = options.input;
  summary.output = options.output;
  summary.material = options.material;

  // 1. Geometry and mesh.
  StageTimer mesh_timer(summary, "mesh");
  GmshImportOptions mesh_options = options.mesh;
  mesh_options.progress = options.progress;
  ImportedMesh imported = import_tet_mesh(options.input, mesh_options);
  summary.input_sha256 = format::sha256_of_file(options.input);
  summary.format = imported.format;
  summary.unit = std::string(to_string(imported.unit));
  summary.unit_reason = imported.unit_reason;
  summary.declared_unit = imported.declared_unit ? std::string(to_string(*imported.declared_unit)) : std::string();
  summary.unit_overrides_declared = imported.unit_overrides_declared;
  summary.volumes = imported.volumes;
  summary.sewn_faces = imported.sewn_faces;
  summary.loose_entities = imported.loose_entities;
  summary.meshed_here = imported.meshed_here;
  summary.mesh_size_m = imported.mesh_size_m;
  summary.mesher = options.mesh.algorithm;
  summary.curved_repair = imported.curved_repair;
  summary.cad_volume_m3 = imported.cad_volume_m3;
  summary.extent_m = imported.extent_m;
  summary.size_warning = imported.size_warning;
  summary.refined_from_m = imported.refined_from_m;
  summary.first_volume_error = imported.first_volume_error;
  // Quadratic tetrahedra (--order 2) number their corners first; every stage below takes all nodes.
  const std::optional<Tet10Mesh>& quadratic = imported.quadratic;
  const RowMatrixX3d& input_nodes = quadratic ? quadratic->nodes : imported.mesh.nodes;
  const Eigen::Index node_count = input_nodes.rows();
  summary.element_order = quadratic ? 2 : 1;
  summary.nodes = node_count;
  summary.elements = imported.mesh.element_count();
  summary.dofs = 3 * node_count;
  summary.quality = quadratic ? mesh_quality(*quadratic) : mesh_quality(imported.mesh);
  mesh_timer.stop();

  // Errors of the numerical stages name the input they came from.
  const std::string name = options.input.filename().string();
  auto in_stage = [&name](const char* stage, auto&& run) {
    try {
      return run();
    } catch (const std::bad_alloc&) {
      throw std::runtime_error(fmt::format("{}: out of memory in the {} stage", name, stage));
    } catch (const std::invalid_argument& e) {  // keeps its type: an impossible request (exit code 2)
      throw std::invalid_argument(fmt::format("{}: {}", name, e.what()));
    } catch (const std::exception& e) {
      throw std::runtime_error(fmt::format("{}: {}", name, e.what()));
    }
  };

  // 2. FE: K̄ and M_s in the input frame, then the body frame (origin at the centre of mass).
  StageTimer fe_timer(summary, "assembly");
  if (options.progress) options.progress(fmt::format("assembling K and M ({} DOFs)", summary.dofs));
  SparseMatrix stiffness, scalar_mass;
  in_stage("assembly", [&] {
    if (quadratic) {  // K̄ by the 4-point rule, the exact consistent M_s (tet10_assembly.hpp)
      Tet10Matrices matrices = assemble_tet10(*quadratic, options.material);
      stiffness = std::move(matrices.stiffness);
      scalar_mass = std::move(matrices.scalar_mass);
      return;
    }
    const TetMesh& mesh = imported.mesh;
    const NodeGraph graph = NodeGraph::build(mesh);  // graph and geometry die here: memory for the modes
    const std::vector<Tet4Geometry> geometry = element_geometries(mesh);
    stiffness = assemble_stiffness(mesh, graph, geometry, options.material);
    scalar_mass = assemble_scalar_mass(mesh, graph, geometry, options.material.density, MassScheme::consistent);
  });
  summary.mass = mass_properties(scalar_mass, input_nodes);
  fe_timer.stop();

  format::BodyData body;
  body.mesh.nodes = input_nodes.rowwise() - summary.mass.center_of_mass_input.transpose();
  if (quadratic) {
    body.mesh.tets = quadratic->tets;
    body.mesh.element_order = 2;
    body.mesh.surface_triangles = boundary_triangles(*quadratic);
  } else {
    body.mesh.tets = imported.mesh.tets;
    body.mesh.surface_triangles = boundary_triangles(imported.mesh);
  }
  summary.surface_triangles = body.mesh.surface_triangles.rows();

  // Interfaces are selected now (Craig-Bampton needs their nodes); their markers follow the GCMS fields.
  // Load points are rbe3 interfaces too (the runtime applies their loads there).
  const std::vector<SelectedInterface> selected = in_stage("interfaces", [&] {
    std::vector<InterfaceRequest> in_metres = options.interfaces;
    for (const LoadPointRequest& p : options.load_points) in_metres.push_back({p.name, p.select, "rbe3", "load point"});
    for (InterfaceRequest& request : in_metres) request.select = scaled(request.select, metres_per(imported.unit));
    std::vector<SelectedInterface> chosen =
        select_interfaces(in_metres, input_nodes, body.mesh.surface_triangles, imported.surfaces);
    // A patch whose nodes lie on a line has no defined rotation (and would leave Craig-Bampton's interior
    // singular): refuse it now, before the modes, naming the interface.
    for (const SelectedInterface& s : chosen)
      (void)interface_marker(s.name, s.coupling, s.patch, body.mesh.nodes, Eigen::MatrixXd(node_count, 0));
    return chosen;
  });

  // The load points' unit loads, whose static corrections join the modes.
  std::vector<LoadPoint> load_points;
  for (const LoadPointRequest& request : options.load_points)
    for (const SelectedInterface& s : selected)
      if (s.name == request.name)
        load_points.push_back(
            {s.name, s.patch.nodes, s.patch.weights, patch_centroid(s.patch, body.mesh.nodes), request.loads});
  const Eigen::MatrixXd static_loads =
      in_stage("interfaces", [&] { return unit_load_vectors(body.mesh.nodes, load_points); });
  summary.static_loads = unit_load_labels(load_points);

  // The geometric stiffness's load cases (issue 29, geometric_stiffness.hpp): the six centrifugal ones and a unit force
  // and moment at every interface, each balanced by inertia relief.
  Eigen::MatrixXd prestress_loads, prestress_responses;
  if (options.geometric_stiffness) {
    std::vector<LoadPoint> at_interfaces;
    for (const SelectedInterface& s : selected)
      at_interfaces.push_back({s.name, s.patch.nodes, s.patch.weights, patch_centroid(s.patch, body.mesh.nodes)});
    prestress_loads = in_stage("geometric stiffness", [&] {
      const Eigen::MatrixXd interface_loads = unit_load_vectors(body.mesh.nodes, at_interfaces);
      Eigen::MatrixXd loads(3 * node_count, 6 + interface_loads.cols());
      loads << centrifugal_unit_loads(body.mesh.nodes, scalar_mass), interface_loads;
      return loads;
    });
    for (const char* c : kCentrifugalCases) summary.prestress_cases.push_back(std::string("centrifugal:") + c);
    for (const std::string& label : unit_load_labels(at_interfaces)) summary.prestress_cases.push_back(label);
  }

  // 3. Modes: free-free, or Craig-Bampton on the rbe2 interfaces.
  StageTimer modes_timer(summary, "modes");
  summary.reduction = options.reduction;
  Eigen::MatrixXd mode_vectors;
  if (options.reduction == ReductionKind::free_free) {
    FreeFreeOptions mode_options = options.modes;  // with auto, each solve picks its backend; the modes name it
    mode_options.progress = options.progress;
    FreeFreeModes modes = in_stage("modes", [&] {
      return free_free_modes(body.mesh.nodes, stiffness, scalar_mass, options.material, mode_options, static_loads,
                             prestress_loads, summary.prestress_cases);
    });
    prestress_responses = std::move(modes.prestress_responses);
    prestress_loads = Eigen::MatrixXd();  // solved: 3 n_n x p doubles back
    summary.prestress = modes.prestress;
    summary.static_correction = modes.static_correction;
    summary.static_correction_modes = modes.vectors.cols() - modes.normal_modes;
    summary.frequencies_hz = modes.frequencies_hz;
    summary.relative_residuals = modes.relative_residuals;
    summary.residual_floors = modes.residual_floors;
    summary.shift = modes.shift;
    summary.rigid_body_residual = modes.rigid_body_residual;
    summary.rigid_body_coupling = modes.rigid_body_coupling;
    summary.solver_runs = modes.solver_runs;
    summary.restarts = modes.restarts;
    summary.operator_applies = modes.operator_applies;
    summary.eigensolver = std::string(to_string(modes.eigensolver));
    summary.factor = modes.stats;
    mode_vectors = modes.vectors;
    {  // the eigenmodes' discretisation error (error_estimate.hpp)
      const Eigen::Index normal = modes.normal_modes;
      const FrequencyErrorEstimate estimate = in_stage("error estimate", [&] {
        return quadratic ? estimate_frequency_errors(*quadratic, options.material, modes.vectors.leftCols(normal),
                                                     modes.frequencies_hz.head(normal))
                         : estimate_frequency_errors(imported.mesh, options.material, modes.vectors.leftCols(normal),
                                                     modes.frequencies_hz.head(normal));
      });
      summary.frequency_errors = estimate.relative;
      if (refine) {
        *refine = in_stage("mesh refinement", [&] {
          return detail::refine_by_the_estimate(options, imported.mesh, summary.element_order, estimate, summary);
        });
        if (*refine) {
          modes_timer.stop();
          summary.refinement->first_seconds = std::chrono::duration<double>(Clock::now() - start).count();
          return summary;
        }
      }
      if (const std::string warning = summary.accuracy_warning(); !warning.empty() && options.mesh.warning)
        options.mesh.warning(warning);
    }
  } else {
    std::vector<RigidInterface> rigid;
    for (const SelectedInterface& s : selected)
      if (s.coupling == "rbe2") rigid.push_back({s.patch.nodes, patch_centroid(s.patch, body.mesh.nodes)});
    CraigBamptonOptions cb_options;
    cb_options.fixed_interface_modes = options.modes.modes;
    cb_options.fmax_hz = options.modes.fmax_hz;
    cb_options.solver = options.modes.solver;
    cb_options.shift = options.modes.shift;
    if (options.progress)
      options.progress(fmt::format("Craig-Bampton: fixed-interface modes ({}), {} rbe2 interfaces",
                                   options.modes.modes > 0 ? std::to_string(options.modes.modes)
                                                           : fmt::format("up to {} Hz", options.modes.fmax_hz),
                                   rigid.size()));
    const CraigBamptonModes modes = in_stage("modes", [&] {
      return craig_bampton_modes(body.mesh.nodes, stiffness, scalar_mass, options.material, rigid, cb_options,
                                 static_loads);
    });
    summary.static_correction = modes.static_correction;
    summary.frequencies_hz = modes.frequencies_hz;
    summary.relative_residuals = modes.relative_residuals;
    summary.fixed_interface_frequencies_hz = modes.fixed_interface_frequencies_hz;
    summary.fixed_interface_residuals = modes.fixed_interface_residuals;
    summary.fixed_interface_residual_floors = modes.fixed_interface_residual_floors;
    summary.shift = modes.shift;
    summary.rigid_body_coupling = modes.rigid_body_coupling;
    summary.solver_runs = 1;
    summary.eigensolver = std::string(to_string(modes.eigensolver));
    summary.factor = modes.stats;
    summary.operator_applies = static_cast<int>(modes.stats.solves);
    mode_vectors = modes.vectors;
    if (prestress_loads.cols() > 0) {  // Craig-Bampton factorizes the interior only: the free part's own factorization,
                                       // preconditioning a solve with the rbe2 patches held rigid
      if (options.progress) options.progress(fmt::format("prestress: {} unit load cases", prestress_loads.cols()));
      prestress_responses = in_stage("geometric stiffness", [&] {
        const Eigen::MatrixXd rigid_fields = rigid_body_modes(body.mesh.nodes, scalar_mass);
        const std::unique_ptr<ShiftSolve> solve = make_shift_solve(
            options.modes.solver.backend == EigensolverBackend::slepc ? EigensolverBackend::slepc
                                                                       : EigensolverBackend::arpack,
            stiffness, scalar_mass, rigid_fields);
        solve->set_shift(automatic_shift(body.mesh.nodes, options.material));
        // The rbe2 patches stay rigid in the prestress as in the modes: a hub that holds a bore keeps it from
        // expanding (solved on the free part they did not: a disk's stiffening was 25-33 % off CalculiX's).
        return relieved_static_responses(*solve, stiffness, scalar_mass, rigid_fields, prestress_loads, summary.prestress,
                                         summary.prestress_cases, "geometric stiffness", {&body.mesh.nodes, rigid});
      });
      prestress_loads = Eigen::MatrixXd();
    }
  }
  modes_timer.stop();

  // 4. The constant blocks of the improved GCMS: fields, G, K̂ (formulations.md, "The Method": nodal fields and
  // dependent fields).
  StageTimer reduce_timer(summary, "gcms");
  if (options.progress) options.progress("GCMS constants (G, K_hat)");
  body.modes.upsilon = upsilon_from_modes(mode_vectors);
  body.gcms = in_stage("gcms", [&] { return gcms_constants(stiffness, scalar_mass, body.mesh.nodes, body.modes.upsilon); });
  summary.gcms_fields = body.gcms.field_count();
  summary.dropped_fields = body.modes.upsilon.cols() - summary.gcms_fields;
  summary.condition_mode_gram_before = body.gcms.condition_mode_gram_before;
  summary.condition_mass_before = body.gcms.condition_mass_before;
  summary.condition_mass_after = body.gcms.condition_mass_after;
  summary.condition_mass_scaled_before = body.gcms.condition_mass_scaled_before.value();
  summary.condition_mass_scaled_after = body.gcms.condition_mass_scaled_after;
  body.interfaces = in_stage("interfaces", [&] {
    std::vector<format::Interface> markers;
    for (const SelectedInterface& s : selected)
      markers.push_back(interface_marker(s.name, s.coupling, s.patch, body.mesh.nodes, body.gcms.fields));
    return markers;
  });
  for (const format::Interface& i : body.interfaces)
    summary.interfaces.push_back({i.name, i.coupling, i.nodes.size(), i.reference_point + summary.mass.center_of_mass_input});
  if (prestress_responses.cols() > 0) {  // Ĝ_σ on Y = [1, X̄, Ῡ'], the fields of G
    if (options.progress) options.progress("geometric stiffness of the prestress cases");
    body.geometric_stiffness.cases = summary.prestress_cases;
    body.geometric_stiffness.matrices = in_stage("geometric stiffness", [&] {
      // The constant field has no gradient: its row and column are exact zeros, the rest is projected on [X̄, Ῡ']
      // (computed, row 0 is round-off whose size relative to the other blocks depends on the units: helper review).
      Eigen::MatrixXd y(node_count, 3 + body.gcms.field_count());
      y << body.mesh.nodes, body.gcms.fields;
      const std::vector<Eigen::MatrixXd> projected =
          quadratic ? projected_geometric_stiffness(*quadratic, options.material, prestress_responses, y)
                    : projected_geometric_stiffness(imported.mesh, options.material, prestress_responses, y);
      std::vector<Eigen::MatrixXd> padded;
      for (const Eigen::MatrixXd& g : projected) {
        padded.push_back(Eigen::MatrixXd::Zero(g.rows() + 1, g.cols() + 1));
        padded.back().bottomRightCorner(g.rows(), g.cols()) = g;
      }
      return padded;
    });
  }
  reduce_timer.stop();

  // 5. Stress recovery: stress modes of the fields at the output regions' nodes.
  StageTimer recovery_timer(summary, "recovery");
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
    summary.output_regions_reason = regions.empty() ? "none: the body spec asks for none" : "as the body spec names them";
  } else if (whole_body_bytes <= kDefaultRecoveryBytes) {
    regions.push_back({"body", std::nullopt});
    summary.output_regions_reason = fmt::format("the whole body by default (its stress modes take {:.3g} MB, at most "
                                                "{:.0f})", whole_body_bytes / 1e6, kDefaultRecoveryBytes / 1e6);
  } else if (surface_bytes <= kDefaultRecoveryBytes) {
    regions.push_back({"surface", std::nullopt, true});
    summary.output_regions_reason = fmt::format(
        "the surface by default (its stress modes take {:.3g} MB; the whole body's would take {:.3g}, at most {:.0f})",
        surface_bytes / 1e6, whole_body_bytes / 1e6, kDefaultRecoveryBytes / 1e6);
  } else {
    summary.output_regions_reason = fmt::format("none: the surface's stress modes would take {:.3g} MB, the whole "
                                                "body's {:.3g} (default limit {:.0f}); name output_regions in the body "
                                                "spec", surface_bytes / 1e6, whole_body_bytes / 1e6,
                                                kDefaultRecoveryBytes / 1e6);
  }
  if (options.progress && !regions.empty())
    options.progress(fmt::format("stress modes for {} output region{}", regions.size(), regions.size() == 1 ? "" : "s"));
  body.recovery = in_stage("recovery", [&] {
    std::vector<format::RecoveryRegion> recovery;
    for (const OutputRegionRequest& request : regions) {
      format::RecoveryRegion region;
      region.name = request.name;
      if (request.select) {
        region.nodes = select_surface_patch(fmt::format("output region '{}'", request.name),
                                            scaled(*request.select, metres_per(imported.unit)), input_nodes,
                                            body.mesh.surface_triangles, imported.surfaces)
                           .nodes;
      } else if (request.surface) {
        region.nodes = surface_nodes;
      } else {
        region.nodes = Eigen::VectorXi::LinSpaced(node_count, 0, static_cast<int>(node_count - 1));
      }
      region.stress_modes = quadratic
                                ? nodal_stress_modes(*quadratic, options.material, body.gcms.fields, region.nodes)
                                : nodal_stress_modes(imported.mesh, options.material, body.gcms.fields, region.nodes);
      recovery.push_back(std::move(region));
    }
    return recovery;
  });
  for (const format::RecoveryRegion& region : body.recovery) summary.output_regions.push_back({region.name, region.nodes.size()});
  recovery_timer.stop();

  // 6. The body file.
  StageTimer write_timer(summary, "write");
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
  write_timer.stop();

  summary.total_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  summary.peak_memory_mb = peak_memory_mb();
  return summary;
}

}  // namespace

PrepSummary run_fbprep(const PrepOptions& options) {
  if (!(options.error_target >= 0.0 && options.error_target < 1.0))
    throw std::invalid_argument(fmt::format("error target {} is not a relative frequency error in [0, 1) (0: no "
                                            "refinement)", options.error_target));
  const auto start = Clock::now();
  std::shared_ptr<const MeshSizeField> sizes;
  PrepSummary first = run_pass(options, detail::refinement_allowed(options) ? &sizes : nullptr);
  if (!sizes) return first;
  PrepOptions refined = options;
  refined.mesh.size_field = std::move(sizes);
  // The second mesh may fail where the first did not (memory, the volume check): say which mesh, and the way back.
  const std::string second = fmt::format(" (on the mesh refined by the error estimate: the first mesh's frequency was "
                                         "estimated {:.1f} % off; --error-target 0 keeps the first mesh)",
                                         100.0 * first.refinement->first_estimate);
  PrepSummary summary;
  try {
    summary = run_pass(refined, nullptr);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(e.what() + second);
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(options.input.filename().string() + ": out of memory" + second);
  } catch (const std::exception& e) {
    throw std::runtime_error(e.what() + second);
  }
  summary.refinement = first.refinement;
  for (StageRecord& stage : first.stages) stage.name += " (first mesh)";
  summary.stages.insert(summary.stages.begin(), first.stages.begin(), first.stages.end());
  summary.total_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return summary;
}

}  // namespace flexbody::preprocess
