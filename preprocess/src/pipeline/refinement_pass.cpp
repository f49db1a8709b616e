#include "refinement_pass.hpp"

#include "flexbody/preprocess/mesh_refinement.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace flexbody::preprocess::detail {

// A mesh whose sizes fbprep chose itself, with free-free modes (the estimate's): the one refine_by_the_estimate may
// replace (PrepOptions::error_target).
bool refinement_allowed(const PrepOptions& options) {
  return options.error_target > 0.0 && options.reduction == ReductionKind::free_free &&
         !(options.mesh.mesh_size > 0.0) && !(options.mesh.thin_feature_elements > 0.0) && !options.mesh.size_field &&
         input_format_of(options.input) != InputFormat::msh;
}

// The sizes of a second mesh when the first one's first frequency is estimated beyond PrepOptions::error_target
// (nullptr: it is not): the plan of mesh_refinement.hpp for the relative eigenvalue error 1 − (1 + e/2)^(−2) of half
// the target e (the estimate runs low on a coarse mesh: RLF_7030's 18 % was 26 % against a refined mesh), within
// kRefinementGrowth times the tetrahedra. Records what it did in summary.refinement.
std::shared_ptr<const MeshSizeField> refine_by_the_estimate(const PrepOptions& options, const TetMesh& corners,
                                                             int order, const FrequencyErrorEstimate& estimate,
                                                             PrepSummary& summary) {
  if (estimate.relative.size() == 0 || !(estimate.relative(0) > options.error_target)) return nullptr;
  RefinementRequest request;
  request.order = order;
  request.target_share = 1.0 - std::pow(1.0 + 0.5 * options.error_target, -2.0);
  request.max_elements = std::min(kRefinementGrowth * static_cast<double>(corners.element_count()),
                                  std::max(options.mesh.volume_search_elements,
                                           static_cast<double>(corners.element_count())));
  const RefinementPlan plan = plan_refinement(element_sizes(corners), estimate.element_shares, request);
  // A plan that refines nothing (the budget no larger than the mesh: at least volume_search_elements tetrahedra)
  // would mesh the same part again for nothing.
  if (!(plan.predicted_elements > 1.01 * static_cast<double>(corners.element_count()))) return nullptr;
  auto field = std::make_shared<MeshSizeField>();
  field->mesh = corners;
  field->sizes = plan.sizes;
  PrepSummary::MeshRefinement& r = summary.refinement.emplace();
  r.error_target = options.error_target;
  r.first_frequency_hz = summary.frequencies_hz(0);
  r.first_estimate = estimate.relative(0);
  r.first_dofs = summary.dofs;
  r.first_elements = summary.elements;
  r.predicted_elements = plan.predicted_elements;
  r.predicted_share = plan.predicted_share;
  r.budget_bound = plan.budget_bound;
  if (options.progress)
    options.progress(fmt::format("the first frequency ({:.4g} Hz) is estimated {:.1f} % too high at the default mesh "
                                 "(target {:.2g} %): remeshing where the estimate puts the error, about {:.3g} "
                                 "tetrahedra (from {}{})", r.first_frequency_hz, 100.0 * r.first_estimate,
                                 100.0 * r.error_target, r.predicted_elements, r.first_elements,
                                 r.budget_bound ? fmt::format(", at most {:g} times: the budget", kRefinementGrowth)
                                                : std::string()));
  return field;
}

}  // namespace flexbody::preprocess::detail
