// fbprep's modes stage (prep_pass.hpp): free-free modes with their discretisation error estimate, or Craig-Bampton
// modes on the rbe2 interfaces; and the geometric stiffness's static responses.
#include "prep_pass.hpp"

#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/eigensolver.hpp"
#include "flexbody/preprocess/error_estimate.hpp"
#include "flexbody/preprocess/geometric_stiffness.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"
#include "refinement_pass.hpp"

namespace flexbody::preprocess {
namespace {

bool free_free_stage(PrepPass& pass, std::shared_ptr<const MeshSizeField>* refine) {
  const PrepOptions& options = pass.options;
  PrepSummary& summary = pass.summary;
  FreeFreeOptions mode_options = options.modes;  // with auto, each solve picks its backend; the modes name it
  mode_options.progress = options.progress;
  FreeFreeModes modes = pass.in_stage("modes", [&] {
    return free_free_modes(pass.body.mesh.nodes, pass.stiffness, pass.scalar_mass, options.material, mode_options,
                           pass.static_loads, pass.prestress_loads, summary.prestress_cases);
  });
  pass.prestress_responses = std::move(modes.prestress_responses);
  pass.prestress_loads = Eigen::MatrixXd();  // solved: 3 n_n x p doubles back
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
  pass.mode_vectors = modes.vectors;

  // The eigenmodes' discretisation error (error_estimate.hpp).
  const ImportedMesh& imported = pass.imported;
  const Eigen::Index normal = modes.normal_modes;
  const FrequencyErrorEstimate estimate = pass.in_stage("error estimate", [&] {
    return imported.quadratic
               ? estimate_frequency_errors(*imported.quadratic, options.material, modes.vectors.leftCols(normal),
                                           modes.frequencies_hz.head(normal))
               : estimate_frequency_errors(imported.mesh, options.material, modes.vectors.leftCols(normal),
                                           modes.frequencies_hz.head(normal));
  });
  summary.frequency_errors = estimate.relative;
  if (refine) {
    *refine = pass.in_stage("mesh refinement", [&] {
      return detail::refine_by_the_estimate(options, imported.mesh, summary.element_order, estimate, summary);
    });
    if (*refine) return false;
  }
  if (const std::string warning = summary.accuracy_warning(); !warning.empty() && options.mesh.warning)
    options.mesh.warning(warning);
  return true;
}

void craig_bampton_stage(PrepPass& pass) {
  const PrepOptions& options = pass.options;
  PrepSummary& summary = pass.summary;
  const RowMatrixX3d& nodes = pass.body.mesh.nodes;
  std::vector<RigidInterface> rigid;
  for (const SelectedInterface& s : pass.selected)
    if (s.coupling == "rbe2") rigid.push_back({s.patch.nodes, patch_centroid(s.patch, nodes)});
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
  const CraigBamptonModes modes = pass.in_stage("modes", [&] {
    return craig_bampton_modes(nodes, pass.stiffness, pass.scalar_mass, options.material, rigid, cb_options,
                               pass.static_loads);
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
  pass.mode_vectors = modes.vectors;
  if (pass.prestress_loads.cols() == 0) return;
  // Craig-Bampton factorizes the interior only: the free part's own factorization, preconditioning a solve with the
  // rbe2 patches held rigid.
  if (options.progress) options.progress(fmt::format("prestress: {} unit load cases", pass.prestress_loads.cols()));
  pass.prestress_responses = pass.in_stage("geometric stiffness", [&] {
    const Eigen::MatrixXd rigid_fields = rigid_body_modes(nodes, pass.scalar_mass);
    const std::unique_ptr<ShiftSolve> solve =
        make_shift_solve(options.modes.solver.backend == EigensolverBackend::slepc ? EigensolverBackend::slepc
                                                                                   : EigensolverBackend::arpack,
                         pass.stiffness, pass.scalar_mass, rigid_fields);
    solve->set_shift(automatic_shift(nodes, options.material));
    // The rbe2 patches stay rigid in the prestress as in the modes: a hub that holds a bore keeps it from
    // expanding (solved on the free part they did not: a disk's stiffening was 25-33 % off CalculiX's).
    return relieved_static_responses(*solve, pass.stiffness, pass.scalar_mass, rigid_fields, pass.prestress_loads,
                                     summary.prestress, summary.prestress_cases, "geometric stiffness",
                                     {&nodes, rigid});
  });
  pass.prestress_loads = Eigen::MatrixXd();
}

}  // namespace

bool modes_stage(PrepPass& pass, std::shared_ptr<const MeshSizeField>* refine) {
  pass.summary.reduction = pass.options.reduction;
  if (pass.options.reduction == ReductionKind::free_free) return free_free_stage(pass, refine);
  craig_bampton_stage(pass);
  return true;
}

}  // namespace flexbody::preprocess
