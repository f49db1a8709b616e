#pragma once
// flexbody/runtime/joint.hpp: joints between two markers (either may be on ground) as algebraic constraints
// Φ(q, t) = 0 with exact Jacobians (formulations.md, "The Method": constraints and markers).
//
//   spherical        r_1 − r_2 = 0                                               3 rows
//   fixed            spherical, and the markers' frames keep their initial relative orientation   6 rows
//   revolute         spherical, and the axis at marker 1 stays perpendicular to two directions normal
//                    to the axis at marker 2                                      5 rows
//   prismatic        r_1 − r_2 keeps its initial components normal to the axis, frames as fixed   5 rows
//   driven revolute  revolute, and the angle about the axis follows φ(t) (φ(0) = 0: the initial state)   6 rows
//
// Directions are body-fixed at their marker and turn with it: A (I + [θ̄]×) d (marker.hpp). They are fixed in each
// body's frame from the global axis and the initial state when the joint is made, so the initial state satisfies
// every row (a spherical joint also needs r_1 = r_2 initially: the caller's scene must be assembled).

#include "flexbody/runtime/marker.hpp"

#include <Eigen/Core>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace flexbody::runtime {

enum class JointType { spherical, fixed, revolute, prismatic, driven_revolute };

struct Joint {
  std::string name;
  JointType type = JointType::spherical;
  Marker first, second;
  /// Unit vectors in the frame of each marker's body (global for ground): the axis at marker 1 and at marker 2,
  /// two normals at marker 2, and marker 1's normal that coincides with normal_a initially.
  Eigen::Vector3d axis_first = Eigen::Vector3d::UnitZ(), axis_second = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d normal_a = Eigen::Vector3d::UnitX(), normal_b = Eigen::Vector3d::UnitY();
  Eigen::Vector3d reference_first = Eigen::Vector3d::UnitX();
  /// Frames for fixed and prismatic joints: the global axes x, y, z in each body's frame initially.
  Eigen::Matrix3d triad_first = Eigen::Matrix3d::Identity(), triad_second = Eigen::Matrix3d::Identity();
  /// Prismatic: the initial components of r_1 − r_2 along normal_a and normal_b.
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
  /// Driven revolute: the angle about the axis [rad] as a function of time, φ(0) = 0.
  std::function<double(double)> angle;
  /// Driven revolute, optional: φ̇(t) [rad/s]. Without it, the constraints' time derivative differentiates φ
  /// numerically (driven_row_time_derivative).
  std::function<double(double)> angle_rate;
  /// Rows of the type's equations left out because they repeat other constraints (bit k: the type's row k), as
  /// System::remove_redundant_constraints finds them. The constraints they repeat carry their reactions.
  unsigned removed = 0;

  /// The rows the joint imposes: its type's rows less the removed ones.
  [[nodiscard]] int rows() const;
  /// The type's rows: spherical 3 (the gap r1 − r2), revolute 5 (the gap; the axis against two normals), prismatic
  /// 5 (the gap along two normals; three for the orientation), fixed 6, driven revolute 6 (the revolute's and the
  /// angle).
  [[nodiscard]] int type_rows() const;
  /// The type's first rows that are lengths [m]: the gap r1 − r2 (3), or a prismatic joint's gap along its two
  /// normals (2); the rest compare directions (cosines, dimensionless).
  [[nodiscard]] int length_rows() const { return type == JointType::prismatic ? 2 : 3; }
};

/// What the type's row `row` of joint j stops at (q1, q2), in global terms: "translation along x" (a gap row),
/// "translation along [0.71, 0.71, 0]", "rotation about [0, 1, 0]", "rotation about the axis (the driven angle)".
[[nodiscard]] std::string joint_row_meaning(const Joint& j, int row, const VectorRef& q1, const VectorRef& q2);

/// A joint assembled at the initial body coordinates q1, q2 (empty for ground): `axis` is global (revolute,
/// prismatic, driven revolute; ignored otherwise); `angle` and (optional, for an exact Φ_t) `angle_rate` drive a
/// driven revolute joint (ignored for other types). Throws std::invalid_argument naming the joint for a zero axis
/// or markers apart for a joint that ties their positions.
[[nodiscard]] Joint make_joint(const std::string& name, JointType type, Marker first, Marker second,
                               const Eigen::Vector3d& axis, const VectorRef& q1, const VectorRef& q2,
                               std::function<double(double)> angle = {},
                               std::function<double(double)> angle_rate = {});

/// Residuals, and Jacobians with respect to each marker's body coordinates (rows x n_b; 0 columns for ground).
struct JointEvaluation {
  Eigen::VectorXd residual;
  Eigen::MatrixXd jacobian_first, jacobian_second;
  /// Work storage: the markers' position Jacobians, the direction Jacobians (two at marker 1, four at marker 2), and
  /// each marker's rotations of its fields (R_f Aᵀ, shared by its directions).
  Eigen::MatrixXd position_first, position_second;
  std::array<Eigen::MatrixXd, 6> directions;
  std::array<Eigen::MatrixXd, 2> frames;
  /// Work storage of System's matrix-free Φ_qᵀ μ: the joint's part on each marker's body.
  Eigen::VectorXd product_first, product_second;
  /// Work storage of a joint with removed rows: all of its type's rows, before the removed ones are left out.
  Eigen::VectorXd all_residual;
  Eigen::MatrixXd all_first, all_second;
};
[[nodiscard]] JointEvaluation evaluate_joint(const Joint& joint, double t, const VectorRef& q1,
                                             const VectorRef& q2);
/// The same into `out`: an evaluation reused for the same joint allocates nothing (the Newton iteration's
/// joints, System).
void evaluate_joint(const Joint& joint, double t, const VectorRef& q1, const VectorRef& q2, JointEvaluation& out);
/// ∂Φ/∂t of a driven revolute joint's angle row (its type's last): φ̇(t) ∂Φ/∂φ, where ∂Φ/∂φ is exact (the row with
/// φ + π/2) and φ̇ is Joint::angle_rate or, without one, the central difference of φ with the step ∛(ε (1 + |t|/h)) h,
/// h = time_scale [s], a time over which φ turns by little (the integrator's step): the step follows the scene's own
/// time scale (a fixed ∛ε s differenced a 1 mm part's 3e5 rad/s spin over 2 rad). `frames` is work storage
/// (JointEvaluation::frames). Zero for other types.
[[nodiscard]] double driven_row_time_derivative(const Joint& joint, double t, double time_scale, const VectorRef& q1,
                                                const VectorRef& q2, std::array<Eigen::MatrixXd, 2>& frames);
/// Every row of the joint's type at (t, q1, q2), the removed ones included (type_rows()): how far a removed row is off.
[[nodiscard]] Eigen::VectorXd joint_type_residuals(const Joint& joint, double t, const VectorRef& q1, const VectorRef& q2);

}  // namespace flexbody::runtime
