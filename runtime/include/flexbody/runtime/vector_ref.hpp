#pragma once
// flexbody/runtime/vector_ref.hpp: the runtime's read-only vector parameter.

#include <Eigen/Core>

namespace flexbody::runtime {

/// A read-only view of a vector or of a contiguous segment of one, so that one body's slice of the system's
/// coordinates passes without a copy. Every function called in a Newton iteration takes its vectors this way.
using VectorRef = Eigen::Ref<const Eigen::VectorXd>;

}  // namespace flexbody::runtime
