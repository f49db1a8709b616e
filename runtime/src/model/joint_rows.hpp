#pragma once
// joint_rows.hpp (internal): a joint's rows as one description shared by the Jacobian (evaluate_joint, joint.cpp)
// and by the Newton iteration's matrix-free products (this file): each row is a component of the gap r_1 − r_2, the
// gap along a direction at marker 2, or the dot product of a direction at marker 1 with one at marker 2 (joint.hpp
// lists the types' rows). Without the Jacobian, Φ, Φ_q q̇ and Φ_qᵀ μ cost what the rows' few 3-vectors and one
// pass over each marker's fields cost (MarkerFrame): a revolute joint's Φ_qᵀ μ on a GCMS body with 18 fields forms no
// 5 x 66 row block.

#include "flexbody/runtime/joint.hpp"

#include <Eigen/Core>

#include <array>

namespace flexbody::runtime::detail {

struct JointForm {
  enum class Kind : unsigned char { gap, along, dot };
  /// gap: component `a` of r_1 − r_2; along: (r_1 − r_2) · second[a] − offset(b); dot: first[a] · second[b].
  struct Row {
    Kind kind;
    int a, b;
  };
  std::array<Eigen::Vector3d, 2> first;   ///< body-fixed directions at marker 1 (its body's frame)
  std::array<Eigen::Vector3d, 4> second;  ///< at marker 2
  int first_count = 0, second_count = 0;
  std::array<Row, 6> rows;  ///< the type's rows, in order (removed ones included)
  int row_count = 0;
};

/// The rows of joint j's type at time t (a driven joint's angle φ(t) turns its last direction).
[[nodiscard]] JointForm joint_form(const Joint& j, double t);

/// Φ_j at (t, q1, q2), its kept rows (j.rows()) into `residual`; the second also Φ_q,j q̇ for the body velocities
/// v1, v2 into `rate`. Ground sides take empty vectors.
void joint_residual(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2, Eigen::Ref<Eigen::VectorXd> residual);
void joint_residual_and_rate(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2, const VectorRef& v1,
                             const VectorRef& v2, Eigen::Ref<Eigen::VectorXd> residual, Eigen::Ref<Eigen::VectorXd> rate);
/// (∂Φ_j/∂q1)ᵀ μ_j into out1 and (∂Φ_j/∂q2)ᵀ μ_j into out2, each set (resized to its body's coordinates; size 0 on
/// ground), for μ_j over the kept rows.
void joint_transpose_product(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2, const VectorRef& mu,
                             Eigen::VectorXd& out1, Eigen::VectorXd& out2);

}  // namespace flexbody::runtime::detail
