#pragma once
// gcms_elastic_padded.hpp (internal): the elastic forces of gcms_elastic.hpp for a K̂ kept in the kernel's padded
// storage (kernels/dense_product.hpp). System keeps each flexible body's K̂ that way: its columns start on
// 64-byte boundaries, which makes K̂ ξ̄, one of the two largest products of an iteration, 1.2-1.6x faster.

#include "flexbody/runtime/gcms_elastic.hpp"

#include "../kernels/dense_product.hpp"

namespace flexbody::runtime::detail {

[[nodiscard]] ElasticForces elastic_forces(const PaddedMatrix& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi);
/// The same into `out`, with ξ̄ in `xi_bar`: no allocation once both are sized (System's Newton iterations).
void elastic_forces(const PaddedMatrix& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi, ElasticForces& out,
                    Eigen::VectorXd& xi_bar);

}  // namespace flexbody::runtime::detail
