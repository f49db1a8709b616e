#pragma once
// When and how fbprep's run refines its own mesh by the error estimate (PrepOptions::error_target; fbprep_pipeline.cpp
// runs the passes; not installed).

#include "flexbody/preprocess/error_estimate.hpp"
#include "flexbody/preprocess/fbprep_pipeline.hpp"

#include <memory>

namespace flexbody::preprocess::detail {

/// A mesh whose sizes fbprep chose itself, with free-free modes (the estimate's): the one refine_by_the_estimate may
/// replace.
[[nodiscard]] bool refinement_allowed(const PrepOptions& options);

/// The sizes of a second mesh when the first one's first frequency is estimated beyond PrepOptions::error_target
/// (nullptr: it is not), recorded in summary.refinement.
[[nodiscard]] std::shared_ptr<const MeshSizeField> refine_by_the_estimate(const PrepOptions& options,
                                                                          const TetMesh& corners, int order,
                                                                          const FrequencyErrorEstimate& estimate,
                                                                          PrepSummary& summary);

}  // namespace flexbody::preprocess::detail
